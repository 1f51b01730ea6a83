// `softbody run`: steps a scene without a window, exports frames, prints per-phase timings.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "app/commands.h"
#include "sim/base/parallel.h"
#include "sim/scene/fold_watch.h"
#include "sim/scene/frame_export.h"
#include "sim/scene/gltf_take.h"
#include "sim/scene/point_cache.h"
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

// What a person watches to see whether a run settles: kinetic energy, the fastest particle, and
// the largest growth of any body's size (largest distance of a particle from its body's centre,
// relative to the start).
class RunMonitor {
 public:
  explicit RunMonitor(const World& world) : world_(world) {
    for (BodyHandle b : world.bodies()) startRadius_.push_back(radius(b));
  }
  void print(int contacts) const {
    double energy = 0, fastest = 0, growth = 0;
    const std::vector<BodyHandle> bodies = world_.bodies();
    for (size_t k = 0; k < bodies.size(); ++k) {
      const BodyHandle b = bodies[k];
      const Eigen::VectorXf m = world_.masses(b);
      const ConstPointsRef v = world_.velocities(b);
      for (int i = 0; i < v.rows(); ++i) {
        const double s2 = double(v.row(i).squaredNorm());
        energy += 0.5 * double(m[i]) * s2;
        fastest = std::max(fastest, std::sqrt(s2));
      }
      if (k < startRadius_.size() && startRadius_[k] > 0)
        growth = std::max(growth, radius(b) / startRadius_[k] - 1.0);
    }
    std::printf(
        "  t %8.3f s  kinetic %11.5g J  fastest %10.4g m/s  growth %+8.3f %%  contacts %d\n",
        world_.time(), energy, fastest, 100.0 * growth, contacts);
  }

 private:
  double radius(BodyHandle b) const {
    const Vec3 c = world_.centreOfMass(b);
    const ConstPointsRef x = world_.positions(b);
    double r = 0;
    for (int i = 0; i < x.rows(); ++i)
      r = std::max(r, (x.row(i).transpose().cast<double>() - c).norm());
    return r;
  }
  const World& world_;
  std::vector<double> startRadius_;
};

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
  double maxSubstep = 0;
  std::string exportDir;
  std::string pc2Path, mddPath, gltfPath, restMeshPath, meshDir;
  int every = 1;
  std::string format = "obj";
  int threads = 0;
  bool noDeform = false;
  int monitor = 0;
  bool foldCheck = false;
  cli.add_option("scene", scenePath, "Scene file (JSON)")->required();
  cli.add_option("--steps", steps, "Number of steps to run (≥ 1)")
      ->required()
      ->check(CLI::Range(1, 100000000));
  cli.add_option("--dt", dt, "Seconds per step (overrides the scene's world.timeStep)")
      ->check(inRange(limits::timeStep));
  cli.add_option("--substeps", substeps, "Sub-steps per step (overrides the scene)")
      ->check(inRange(limits::substeps));
  cli.add_option("--max-substep", maxSubstep,
                 "Longest sub-step in seconds; longer steps run more sub-steps (overrides the "
                 "scene's world.maxSubstep, default 1/120)")
      ->check(inRange(limits::maxSubstep));
  cli.add_option("--export", exportDir, "Write a frame file per exported step into this folder");
  cli.add_option("--export-pc2", pc2Path,
                 "Write the render meshes' vertices at the initial state and every K-th step as "
                 "one PC2 point cache (all bodies, in scene order; see --export-mesh)");
  cli.add_option("--export-mdd", mddPath, "The same as an MDD point cache");
  cli.add_option("--export-gltf", gltfPath,
                 "Write the render meshes at the initial state and every K-th step as one glTF "
                 "binary (.glb): a mesh per body, the frames as morph targets keyed by an "
                 "animation (sim/scene/gltf_take.h)");
  cli.add_option("--export-mesh", restMeshPath,
                 "Write the render meshes at the initial state as one OBJ object, the mesh the "
                 "point caches move (a group per body)");
  cli.add_option("--export-meshes", meshDir,
                 "Write the render meshes at the initial state and every K-th step as an OBJ "
                 "sequence into this folder (frame_STEP.obj, an object per body)");
  cli.add_option("--every", every, "Export every K-th step (default 1)")
      ->check(CLI::Range(1, 100000000));
  cli.add_option("--format", format, "Frame format: obj or bin (see sim/scene/frame_export.h)")
      ->check(CLI::IsMember({"obj", "bin"}));
  cli.add_option("--threads", threads, "Simulation threads (default: all cores)")
      ->check(CLI::Range(1, 256));
  cli.add_option("--monitor", monitor,
                 "Every K steps print the time, kinetic energy, fastest particle, largest "
                 "growth of a body and contacts (to watch a run settle)")
      ->check(CLI::Range(1, 100000000));
  cli.add_flag("--fold-check", foldCheck,
               "After every exported step (--every), check each render mesh's map for folds "
               "(det J <= 0 inside the cage, sim/cage/fold_check.h); report the first step at "
               "which each body folds");
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
  if (maxSubstep > 0) settings.maxSubstep = maxSubstep;
  scene.world.setSettings(settings);

  const FrameFormat frameFormat = format == "bin" ? FrameFormat::Binary : FrameFormat::Obj;
  const bool renderExport = !pc2Path.empty() || !mddPath.empty() || !gltfPath.empty() ||
                            !restMeshPath.empty() || !meshDir.empty();
  if (renderExport) {
    if (noDeform) {
      std::fprintf(stderr,
                   "softbody run: --no-deform: the render meshes would not follow the bodies; "
                   "it cannot be combined with --export-pc2, --export-mdd, --export-gltf, "
                   "--export-mesh or --export-meshes\n");
      return 1;
    }
    if (std::none_of(scene.bodies.begin(), scene.bodies.end(),
                     [](const SceneBody& b) { return b.render != nullptr; })) {
      std::fprintf(stderr,
                   "softbody run: %s has no render meshes to export (no body names a "
                   "renderMesh); export the particles with --export\n",
                   scenePath.c_str());
      return 1;
    }
  }
  for (const std::string* dir : {&exportDir, &meshDir}) {
    if (dir->empty()) continue;
    std::error_code ec;
    std::filesystem::create_directories(*dir, ec);
    if (ec || !std::filesystem::is_directory(*dir)) {
      std::fprintf(stderr, "softbody run: %s %s: cannot create the folder\n",
                   dir == &exportDir ? "--export" : "--export-meshes", dir->c_str());
      return 1;
    }
  }
  SceneRunner runner(scene, !noDeform);
  long long particles = 0, clusters = 0, renderVertices = 0;
  for (const SceneBody& b : scene.bodies) {
    particles += scene.world.particleCount(b.handle);
    clusters += scene.world.clusterCount(b.handle);
  }
  for (const PointsRowMajor& mesh : runner.renderMeshes()) renderVertices += mesh.rows();
  std::printf(
      "%s: %zu bodies, %lld particles, %lld clusters, %lld render vertices, dt %.6g s, "
      "%d substeps, %d threads\n",
      scenePath.c_str(), scene.bodies.size(), particles, clusters, renderVertices,
      settings.timeStep, scene.world.substepsFor(settings.timeStep), threadCount());

  // Render-mesh exports: the initial state, then every K-th step. A failure stops the run; the
  // caches are published only when complete (an unfinished one is removed).
  std::vector<std::unique_ptr<PointCacheWriter>> caches;
  std::unique_ptr<GltfTakeWriter> gltf;
  auto exportRenderFrame = [&](int step) {
    for (auto& cache : caches) cache->addFrame(runner.renderMeshes());
    if (gltf) gltf->addFrame(runner.renderMeshes());
    if (!meshDir.empty()) {
      char name[64];
      std::snprintf(name, sizeof name, "frame_%06d.obj", step);
      writeRenderMeshesObj(scene, runner.renderMeshes(),
                           (std::filesystem::path(meshDir) / name).string(), ObjObjects::PerBody);
    }
  };
  try {
    const int frames = steps / every + 1;
    const double interval = settings.timeStep * every;
    if (!pc2Path.empty())
      caches.push_back(std::make_unique<PointCacheWriter>(pc2Path, PointCacheFormat::Pc2,
                                                          int(renderVertices), frames,
                                                          scene.world.time(), interval));
    if (!mddPath.empty())
      caches.push_back(std::make_unique<PointCacheWriter>(mddPath, PointCacheFormat::Mdd,
                                                          int(renderVertices), frames,
                                                          scene.world.time(), interval));
    if (!gltfPath.empty()) {
      std::vector<int> vertexCounts;
      for (const PointsRowMajor& mesh : runner.renderMeshes())
        vertexCounts.push_back(int(mesh.rows()));
      gltf = std::make_unique<GltfTakeWriter>(gltfPath, scene, vertexCounts, frames, interval);
    }
    if (!restMeshPath.empty())
      writeRenderMeshesObj(scene, runner.renderMeshes(), restMeshPath, ObjObjects::One);
    if (renderExport) exportRenderFrame(0);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softbody run: %s\n", e.what());
    return 1;
  }

  std::unique_ptr<FoldWatch> folds;
  std::vector<char> foldedBefore(scene.bodies.size(), 0);
  int foldSteps = 0;
  if (foldCheck) {
    try {
      folds = std::make_unique<FoldWatch>(scene);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "softbody run: --fold-check: %s\n", e.what());
      return 1;
    }
    if (folds->watchedBodies() == 0) {
      std::fprintf(stderr, "softbody run: --fold-check: %s has no render meshes to check\n",
                   scenePath.c_str());
      return 1;
    }
  }
  // Reports a body's first fold, and counts the checked steps with any fold.
  auto checkFolds = [&](int step) {
    const std::vector<FoldWatch::BodyFolds> now = folds->folded(scene);
    if (!now.empty()) ++foldSteps;
    for (const FoldWatch::BodyFolds& f : now) {
      if (foldedBefore[size_t(f.body)]) continue;
      foldedBefore[size_t(f.body)] = 1;
      std::printf(
          "fold: step %d (t %.4f s): body '%s' folds at %d of %d samples (min det J %.3g)\n", step,
          scene.world.time(), scene.world.name(scene.bodies[size_t(f.body)].handle).c_str(),
          f.report.folded, f.report.samples, f.report.minDeterminant);
    }
  };

  RunMonitor watch(scene.world);
  int exported = 0;
  for (int s = 1; s <= steps; ++s) {
    runner.step([&](const WorldEvent& e) {
      std::fprintf(stderr, "softbody run: step %d: %s\n", s, e.message.c_str());
    });
    if (s % every == 0) {
      try {
        if (!exportDir.empty()) {
          char name[64];
          std::snprintf(name, sizeof name, "frame_%06d.%s", s, format.c_str());
          writeFrame(scene, (std::filesystem::path(exportDir) / name).string(), frameFormat);
          ++exported;
        }
        if (renderExport) exportRenderFrame(s);
        if (folds) checkFolds(s);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "softbody run: %s\n", e.what());
        return 1;
      }
    }
    if (monitor > 0 && s % monitor == 0) watch.print(scene.world.lastContactCount());
  }
  for (const SceneBody& b : scene.bodies) {
    const Vec3 c = scene.world.centreOfMass(b.handle);
    std::printf("  body '%s': centre of mass (%.4f, %.4f, %.4f) m\n",
                scene.world.name(b.handle).c_str(), c.x(), c.y(), c.z());
  }
  if (!exportDir.empty()) std::printf("exported %d frames to %s\n", exported, exportDir.c_str());
  if (folds)
    std::printf("fold check: %d of %d checked steps had a fold (%d bodies watched)\n", foldSteps,
                steps / every, folds->watchedBodies());
  try {
    for (auto& cache : caches) cache->finish();
    if (gltf) gltf->finish();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softbody run: %s\n", e.what());
    return 1;
  }
  const int renderFrames = steps / every + 1;
  if (!pc2Path.empty()) std::printf("exported %d frames to %s\n", renderFrames, pc2Path.c_str());
  if (!mddPath.empty()) std::printf("exported %d frames to %s\n", renderFrames, mddPath.c_str());
  if (!gltfPath.empty()) std::printf("exported %d frames to %s\n", renderFrames, gltfPath.c_str());
  if (!restMeshPath.empty()) std::printf("exported the rest mesh to %s\n", restMeshPath.c_str());
  if (!meshDir.empty()) std::printf("exported %d frames to %s\n", renderFrames, meshDir.c_str());
  std::printf("state hash %016llx after %.4f s simulated\n",
              static_cast<unsigned long long>(scene.world.stateHash()), scene.world.time());
  std::printf("%.1f body-body contacts per sub-step on average\n",
              double(runner.totals().contacts) / steps);
  printTimings(runner.totals(), particles);
  return 0;
}

}  // namespace sb::app
