// `softbody run`: steps a scene without a window, exports frames, prints per-phase timings.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "app/commands.h"
#include "sim/base/parallel.h"
#include "sim/scene/frame_export.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"
#include "sim/world/param_ranges.h"

namespace sb::app {

namespace {

void printTimings(const RunTotals& totals, long long particles) {
  const double steps = double(totals.steps);
  auto line = [&](const char* name, double seconds) {
    const double perStep = seconds / steps;
    std::printf("  %-11s %10.4f ms/step %10.2f ns/particle/step\n", name, perStep * 1e3,
                particles > 0 ? perStep * 1e9 / double(particles) : 0.0);
  };
  std::printf("timings per step phase (%lld steps, %lld particles):\n", totals.steps, particles);
  for (Phase phase : kPhases) line(phaseName(phase), totals.phases[phase]);
  line("deform", totals.deformSeconds);
  line("total", totals.seconds());
  std::printf("%.1f steps per second (simulation%s)\n", steps / totals.seconds(),
              totals.deformSeconds > 0 ? " and render-mesh deform" : " only");
}

// A CLI11 check of a number against the range the World accepts (sim/world/param_ranges.h).
CLI::Validator inRange(const ParamRange& range) {
  return CLI::Validator(
      [range](std::string& text) {
        double v = 0;
        try {
          size_t used = 0;
          v = std::stod(text, &used);
          if (used != text.size()) return std::string("not a number: ") + text;
        } catch (const std::exception&) {
          return std::string("not a number: ") + text;
        }
        return rangeViolation(range, v);
      },
      describe(range));
}

}  // namespace

int runHeadlessCommand(int argc, char** argv) {
  CLI::App cli{"Step a scene headless: export particle positions per frame, print timings.",
               "softbody run"};
  std::string scenePath;
  int steps = 0;
  double dt = 0;
  int substeps = 0;
  std::string exportDir;
  int every = 1;
  std::string format = "obj";
  int threads = 0;
  bool noDeform = false;
  cli.add_option("scene", scenePath, "Scene file (JSON)")->required();
  cli.add_option("--steps", steps, "Number of steps to run (≥ 1)")
      ->required()
      ->check(CLI::Range(1, 100000000));
  cli.add_option("--dt", dt, "Seconds per step (overrides the scene's world.timeStep)")
      ->check(inRange(limits::timeStep));
  cli.add_option("--substeps", substeps, "Sub-steps per step (overrides the scene)")
      ->check(inRange(limits::substeps));
  cli.add_option("--export", exportDir, "Write a frame file per exported step into this folder");
  cli.add_option("--every", every, "Export every K-th step (default 1)")
      ->check(CLI::Range(1, 100000000));
  cli.add_option("--format", format, "Frame format: obj or bin (see sim/scene/frame_export.h)")
      ->check(CLI::IsMember({"obj", "bin"}));
  cli.add_option("--threads", threads, "Simulation threads (default: all cores)")
      ->check(CLI::Range(1, 256));
  cli.add_flag("--no-deform", noDeform,
               "Do not update the render meshes each step (by default they follow the "
               "particles every step, as in the viewer)");
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e);
  }
  if (threads > 0) setThreadCount(threads);

  Scene scene;
  try {
    scene = loadScene(scenePath);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softbody run: %s\n", e.what());
    return 1;
  }
  WorldSettings settings = scene.world.settings();
  if (dt > 0) settings.timeStep = dt;
  if (substeps > 0) settings.substeps = substeps;
  scene.world.setSettings(settings);

  const FrameFormat frameFormat = format == "bin" ? FrameFormat::Binary : FrameFormat::Obj;
  if (!exportDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(exportDir, ec);
    if (ec || !std::filesystem::is_directory(exportDir)) {
      std::fprintf(stderr, "softbody run: --export %s: cannot create the folder\n",
                   exportDir.c_str());
      return 1;
    }
  }
  SceneRunner runner(scene, !noDeform);
  long long particles = 0, renderVertices = 0;
  for (const SceneBody& b : scene.bodies) particles += scene.world.particleCount(b.handle);
  for (const PointsRowMajor& mesh : runner.renderMeshes()) renderVertices += mesh.rows();
  std::printf(
      "%s: %zu bodies, %lld particles, %lld render vertices, dt %.6g s, %d substeps, "
      "%d threads\n",
      scenePath.c_str(), scene.bodies.size(), particles, renderVertices, settings.timeStep,
      settings.substeps, threadCount());

  int exported = 0;
  for (int s = 1; s <= steps; ++s) {
    runner.step([&](const WorldEvent& e) {
      std::fprintf(stderr, "softbody run: step %d: %s\n", s, e.message.c_str());
    });
    if (!exportDir.empty() && s % every == 0) {
      char name[64];
      std::snprintf(name, sizeof name, "frame_%06d.%s", s, format.c_str());
      try {
        writeFrame(scene, (std::filesystem::path(exportDir) / name).string(), frameFormat);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "softbody run: %s\n", e.what());
        return 1;
      }
      ++exported;
    }
  }
  for (const SceneBody& b : scene.bodies) {
    const Vec3 c = scene.world.centreOfMass(b.handle);
    std::printf("  body '%s': centre of mass (%.4f, %.4f, %.4f) m\n",
                scene.world.name(b.handle).c_str(), c.x(), c.y(), c.z());
  }
  if (!exportDir.empty()) std::printf("exported %d frames to %s\n", exported, exportDir.c_str());
  std::printf("state hash %016llx after %.4f s simulated\n",
              static_cast<unsigned long long>(scene.world.stateHash()), scene.world.time());
  std::printf("%.1f body-body contacts per sub-step on average\n",
              double(runner.totals().contacts) / steps);
  printTimings(runner.totals(), particles);
  return 0;
}

}  // namespace sb::app
