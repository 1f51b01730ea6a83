// Command-line options of the viewer (softbody [SCENE] [options]).
#pragma once

#include <string>

namespace sb::app {

struct ViewerOptions {
  std::string scenePath;   // empty: defaultScenePath()
  int frames = -1;         // > 0: exit after this many frames (headless: steps; default 300)
  std::string screenshot;  // PNG written at the last frame (or at frame 120 without --frames)
  std::string statsPath;   // JSON with timings, body centres and screen bounds
  int statsEvery =
      30;  // also rewrite the stats file every N frames while running (0: only at exit)
  double fpsCap = 60.0;  // frames per second at most (vsync does not throttle under Xvfb)
  int width = 1280;      // window size in pixels
  int height = 720;
  bool startPaused = false;  // start with the simulation paused
  bool hideBodies = false;   // draw everything but the body meshes (tests compare against it)
  bool hideUi = false;       // no ImGui panel
  std::string show;  // overlays on at start: comma list of particles,cage,clusters,goals,folds
  // Simulation threads (0: all cores). One by default: llvmpipe renders on the
  // same cores, and spinning OpenMP workers competing with it cost more than they give for
  // scenes of a few hundred particles.
  int simThreads = 1;
  // Step the simulation on a second thread while the frame is drawn (--no-overlap: one after
  // the other, as before; for comparing frame rates).
  bool overlapStep = true;
};

}  // namespace sb::app
