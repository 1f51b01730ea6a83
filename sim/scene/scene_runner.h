// Steps a scene and adds up what every report of a run needs: the one step-and-report loop of
// the run command, the headless viewer and the scene benchmarks.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "sim/scene/scene.h"

namespace sb {

struct RunTotals {
  long long steps = 0;
  StepProfile phases;        // seconds per phase, summed over the steps
  double deformSeconds = 0;  // render-mesh deform (0 without deform)
  long long contacts = 0;    // body–body contacts of each step's last sub-step, summed
  long long events = 0;      // WorldEvents (NaN resets, ...)
  double seconds() const { return phases.total() + deformSeconds; }
};

class SceneRunner {
 public:
  // deform: update every render mesh after each step (as the viewer draws them).
  SceneRunner(Scene& scene, bool deform);

  // One World::step(); render meshes deformed when enabled (those of bodies that sleep and were
  // deformed since they fell asleep are current and skipped); each event handed to onEvent.
  void step(const std::function<void(const WorldEvent&)>& onEvent = {});

  const RunTotals& totals() const { return totals_; }
  void clearTotals() { totals_ = RunTotals{}; }
  // The render vertices of every body after the last step (the particles for bodies without a
  // render mesh); filled at construction.
  const std::vector<PointsRowMajor>& renderMeshes() const { return meshes_; }

 private:
  Scene& scene_;
  bool deform_;
  RunTotals totals_;
  std::vector<PointsRowMajor> meshes_;
  // Per body: its mesh was deformed while it slept (Scene::renderVerticesStale).
  std::unique_ptr<bool[]> currentWhileAsleep_;
};

}  // namespace sb
