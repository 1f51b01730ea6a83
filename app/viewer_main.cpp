// softbody [SCENE] [options]: the interactive viewer, or a headless run when there is no display.
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

#include "app/commands.h"
#include "app/viewer_headless.h"
#include "app/viewer_options.h"
#include "sim/base/parallel.h"
#include "sim/scene/scene.h"

#ifdef SOFTBODY_HAVE_VIEWER
#include <GLFW/glfw3.h>

#include "app/viewer_app.h"
#endif

namespace sb::app {

namespace {

#ifdef SOFTBODY_HAVE_VIEWER
void glfwError(int code, const char* description) {
  // Reported once in context by the caller; keep the raw message for diagnosis.
  std::fprintf(stderr, "softbody: GLFW error %d: %s\n", code, description);
}
#endif

bool parseSize(const std::string& text, int* width, int* height) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
    return false;
  if (w < 64 || h < 64 || w > 16384 || h > 16384) return false;
  *width = w;
  *height = h;
  return true;
}

}  // namespace

int runViewerCommand(int argc, char** argv) {
  ViewerOptions options;
  std::string size = "1280x720";
  CLI::App cli("softbody viewer: opens SCENE in a window (runs it headless without a display)",
               "softbody");
  cli.footer(
      "Mouse: left drag pulls the surface point under the cursor; Ctrl + left drag pulls the\n"
      "nearest particle; right drag orbits; Shift + right drag or middle drag pans; wheel zooms.\n"
      "Keys: space pause, S/N single step, R reset, F frame the scene, H hide/show the panel,\n"
      "Ctrl+Z undo a parameter change, P/C/K/G particles, cage, clusters, goals overlays,\n"
      "arrows orbit, +/- zoom, Esc/Q quit.\n"
      "Without a display the scene runs headless for --frames steps (300 by default).");
  cli.add_option("scene", options.scenePath, "scene file (JSON); default: the bundled scene");
  cli.add_option("--frames", options.frames, "exit after N frames (headless: steps, default 300)")
      ->check(CLI::PositiveNumber);
  cli.add_option("--screenshot", options.screenshot,
                 "write a PNG of the last frame (of frame 120 without --frames)");
  cli.add_option("--stats", options.statsPath,
                 "write timings, body centres and screen bounds as JSON (at exit and every "
                 "--stats-every frames)");
  cli.add_option("--stats-every", options.statsEvery,
                 "rewrite the stats file every N frames (0: at exit only)")
      ->check(CLI::NonNegativeNumber);
  cli.add_option("--fps-cap", options.fpsCap, "frames per second at most (0: uncapped)")
      ->check(CLI::NonNegativeNumber);
  cli.add_option("--size", size, "window size WxH in pixels");
  cli.add_option(
         "--sim-threads", options.simThreads,
         "simulation threads (0: all cores); 1 by default, as llvmpipe renders on the same cores")
      ->check(CLI::NonNegativeNumber);
  cli.add_option(
         "--show", options.show,
         "overlays to switch on, comma separated: particles,cage,clusters,goals,folds (the fold "
         "check)")
      ->check([](const std::string& text) {
        std::string rest = text + ",";
        for (std::size_t at; (at = rest.find(',')) != std::string::npos; rest.erase(0, at + 1)) {
          const std::string item = rest.substr(0, at);
          if (!item.empty() && item != "particles" && item != "cage" && item != "clusters" &&
              item != "goals" && item != "folds")
            return "unknown overlay '" + item + "' (particles, cage, clusters, goals, folds)";
        }
        return std::string();
      });
  cli.add_flag("--paused", options.startPaused, "start with the simulation paused");
  bool noOverlap = false;
  cli.add_flag("--no-overlap", noOverlap,
               "step the simulation before drawing the frame, not on a second thread while it "
               "is drawn (for comparing frame rates)");
  cli.add_flag("--hide-bodies", options.hideBodies, "do not draw the body meshes (for tests)");
  cli.add_flag("--no-ui", options.hideUi, "hide the control panel");
  try {
    cli.parse(argc, argv);
    options.overlapStep = !noOverlap;
    if (!parseSize(size, &options.width, &options.height))
      throw CLI::ValidationError("--size",
                                 "expected WxH with 64 <= W, H <= 16384, got '" + size + "'");
  } catch (const CLI::ParseError& e) {
    return cli.exit(e);
  }

  if (options.scenePath.empty()) options.scenePath = defaultScenePath();
  Scene scene;
  try {
    scene = loadScene(options.scenePath);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softbody: %s\n", e.what());
    return 1;
  }

#ifndef SOFTBODY_HAVE_VIEWER
  setThreadCount(options.simThreads);
  std::printf("softbody: no display: running headless (built without the viewer)\n");
  return runViewerHeadless(scene, options);
#else
  setThreadCount(options.simThreads);
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  const bool haveDisplay = (display && *display) || (wayland && *wayland);
  if (haveDisplay) glfwSetErrorCallback(glfwError);
  if (!haveDisplay || !glfwInit()) {
    std::printf("softbody: no display: running headless (%d steps of %s, no window)\n",
                options.frames > 0 ? options.frames : 300, options.scenePath.c_str());
    std::fflush(stdout);
    return runViewerHeadless(scene, options);
  }

  int code = 0;
  bool windowFailed = false;
  {
    ViewerApp app(options, std::move(scene));
    std::string error;
    if (!app.open(&error)) {
      std::fprintf(stderr, "softbody: %s\n", error.c_str());
      windowFailed = true;
    } else {
      code = app.run();
    }
  }
  glfwTerminate();
  if (windowFailed) {
    // A display without usable OpenGL 3.3: still run the scene, as with no display at all.
    std::printf("softbody: no usable display: running headless (%d steps of %s, no window)\n",
                options.frames > 0 ? options.frames : 300, options.scenePath.c_str());
    try {
      Scene again = loadScene(options.scenePath);
      return runViewerHeadless(again, options);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "softbody: %s\n", e.what());
      return 1;
    }
  }
  return code;
#endif
}

}  // namespace sb::app
