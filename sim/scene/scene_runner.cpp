#include "sim/scene/scene_runner.h"

#include <chrono>

namespace sb {

SceneRunner::SceneRunner(Scene& scene, bool deform)
    : scene_(scene),
      deform_(deform),
      currentWhileAsleep_(std::make_unique<bool[]>(scene.bodies.size())) {
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
    std::vector<int> stale;
    std::vector<PointsRowMajor*> outs;
    for (size_t i = 0; i < meshes_.size(); ++i)
      if (scene_.renderVerticesStale(int(i), currentWhileAsleep_[i])) {
        stale.push_back(int(i));
        outs.push_back(&meshes_[i]);
      }
    scene_.renderVertices(stale, outs);
    totals_.deformSeconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  for (const WorldEvent& e : scene_.world.takeEvents()) {
    ++totals_.events;
    if (onEvent) onEvent(e);
  }
}

}  // namespace sb
