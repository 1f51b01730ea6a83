// TEMPORARY placeholder, replaced by the viewer work: runs the scene headless.
#include <cstdio>
#include "app/commands.h"
namespace sb::app {
int runViewerCommand(int, char**) { std::fprintf(stderr, "viewer: not built yet\n"); return 2; }
}  // namespace sb::app
