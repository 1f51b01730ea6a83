// The viewer's fallback when no display is available: steps the scene without a window.
#pragma once

#include "app/viewer_options.h"

namespace sb {
struct Scene;
}

namespace sb::app {

// Steps scene for options.frames steps (300 when not given), prints a summary (simulated time,
// ms per step, each body's centre, events) and writes options.statsPath if set. Returns 0.
int runViewerHeadless(Scene& scene, const ViewerOptions& options);

}  // namespace sb::app
