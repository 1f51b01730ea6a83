#include "sim/scene/scene_runner.h"

#include <chrono>

#include "sim/base/parallel_for.h"

namespace sb {

SceneRunner::SceneRunner(Scene& scene, bool deform)
    : scene_(scene), deform_(deform), currentWhileAsleep_(scene.bodies.size(), 0) {
  meshes_.resize(scene.bodies.size());
  for (size_t i = 0; i < scene.bodies.size(); ++i) scene.renderVertices(int(i), meshes_[i]);
}

void SceneRunner::step(const std::function<void(const WorldEvent&)>& onEvent) {
  scene_.world.step();
  totals_.phases += scene_.world.lastProfile();
  totals_.contacts += scene_.world.lastContactCount();
  ++totals_.steps;
  if (deform_) {
    const auto t0 = std::chrono::steady_clock::now();
    // A sleeping body does not move (anything that moves it wakes it first), so its mesh,
    // deformed once while it sleeps, stays current: resting scenes cost no deform.
    parallelFor(static_cast<int>(meshes_.size()), 2, [&](int i) {
      const bool asleep = scene_.world.isSleeping(scene_.bodies[size_t(i)].handle);
      if (asleep && currentWhileAsleep_[size_t(i)]) return;
      scene_.renderVertices(i, meshes_[size_t(i)]);
      currentWhileAsleep_[size_t(i)] = asleep;
    });
    totals_.deformSeconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  for (const WorldEvent& e : scene_.world.takeEvents()) {
    ++totals_.events;
    if (onEvent) onEvent(e);
  }
}

}  // namespace sb
