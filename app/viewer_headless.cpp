// Headless fallback of the viewer (no display): steps the scene a fixed number of times and
// prints what happened.
#include "app/viewer_headless.h"

#include <chrono>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "sim/base/file_io.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"

namespace sb::app {

int runViewerHeadless(Scene& scene, const ViewerOptions& options) {
  const int steps = options.frames > 0 ? options.frames : 300;
  World& world = scene.world;
  SceneRunner runner(scene, /*deform=*/false);
  const auto start = std::chrono::steady_clock::now();
  for (int s = 0; s < steps; ++s)
    runner.step([&](const WorldEvent& e) {
      std::printf("  event: %s: %s\n",
                  world.contains(e.body) ? world.name(e.body).c_str() : "world", e.message.c_str());
    });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const long long events = runner.totals().events;
  std::printf("softbody (headless): %d steps, %.3f s simulated, %.3f ms per step, %lld event(s)\n",
              steps, world.time(), 1e3 * seconds / steps, events);
  nlohmann::json bodies = nlohmann::json::array();
  for (const SceneBody& body : scene.bodies) {
    const Vec3 c = world.centreOfMass(body.handle);
    std::printf("  %-16s %4d particles  centre (%.3f, %.3f, %.3f)\n",
                world.name(body.handle).c_str(), world.particleCount(body.handle), c.x(), c.y(),
                c.z());
    bodies.push_back({{"name", world.name(body.handle)}, {"centre", {c.x(), c.y(), c.z()}}});
  }
  if (!options.statsPath.empty()) {
    nlohmann::json j;
    j["headless"] = true;
    j["steps"] = steps;
    j["simTime"] = world.time();
    j["msPerStep"] = {{"total", 1e3 * runner.totals().phases.total() / steps},
                      {"wall", 1e3 * seconds / steps}};
    j["events"] = events;
    j["bodies"] = bodies;
    try {
      writeFileAtomic(options.statsPath, [&](std::ostream& out) { out << j.dump(2) << "\n"; });
    } catch (const FileError& e) {
      std::fprintf(stderr, "softbody: cannot write the stats file: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}

}  // namespace sb::app
