// Scene benchmarks (Google Benchmark): whole shipped scenes and body–body contact scaling.
// Run a Release build:  build/release/tests/bench/bench_scene
// Counters are milliseconds per step (simulation phases and the render-mesh deform) averaged
// over the timed steps, and steps_per_s for simulation + deform together.
#include <benchmark/benchmark.h>

#include <algorithm>

#include "sim/base/parallel.h"
#include "sim/mesh/mesh_io.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"

namespace sb {
namespace {

const std::string kAssets = SOFTBODY_ASSET_DIR;

// Every phase of the step (step_phases.h) as "<phase>_ms", plus the deform and totals.
void reportPhases(benchmark::State& state, const RunTotals& totals) {
  const double perStep = 1e3 / double(totals.steps);
  for (Phase phase : kPhases)
    state.counters[std::string(phaseName(phase)) + "_ms"] = totals.phases[phase] * perStep;
  state.counters["deform_ms"] = totals.deformSeconds * perStep;
  state.counters["steps_per_s"] = double(totals.steps) / totals.seconds();
  state.counters["contacts_per_substep"] = double(totals.contacts) / double(totals.steps);
  state.counters["threads"] = threadCount();
}

// The share of the contact solve's velocity-sweep visits skipped as provably idle
// (ContactPoint::idleSlack), over the timed steps, as "idle_skipped_pct".
struct SweepVisits {
  long visits = 0, skipped = 0, triangleTests = 0, steps = 0;
  void add(const World& world) {
    visits += world.lastContactWork().sweepVisits;
    skipped += world.lastContactWork().skippedVisits;
    triangleTests += world.lastContactWork().triangleTests;
    ++steps;
  }
  void report(benchmark::State& state) const {
    state.counters["idle_skipped_pct"] = 100.0 * double(skipped) / double(std::max(1L, visits));
    state.counters["sweep_visits_per_step"] = double(visits) / double(std::max(1L, steps));
    state.counters["triangle_tests_per_step"] = double(triangleTests) / double(std::max(1L, steps));
  }
};

// The shipped large scene (≥ 50 bodies, ≥ 50k render vertices): simulation, collisions and the
// deform of every render mesh, timed after the first 2 s (the top layer is still landing then).
void BM_LargeScene(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  Scene scene = loadScene(kAssets + "/scenes/large.json");
  for (int s = 0; s < 120; ++s) scene.world.step();
  SceneRunner runner(scene, /*deform=*/true);
  long long renderVertices = 0;
  for (const PointsRowMajor& mesh : runner.renderMeshes()) renderVertices += mesh.rows();
  SweepVisits sweeps;
  for (auto _ : state) {
    runner.step();
    sweeps.add(scene.world);
  }
  reportPhases(state, runner.totals());
  sweeps.report(state);
  state.counters["bodies"] = double(scene.bodies.size());
  state.counters["render_vertices"] = double(renderVertices);
  setThreadCount(0);
}
// A fixed number of steps, so every run times the same stretch of simulated time (t = 2 … 7 s).
BENCHMARK(BM_LargeScene)
    ->Arg(1)
    ->Arg(2)
    ->Iterations(300)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The source's big scene (issue 13, assets/scenes/seed-scale.json: 384 bodies, 55,092
// particles, 2,448 clusters, 584k render vertices): simulation, collisions and the deform of
// every render mesh while the pile forms, timed from 1 s (the lower layers have landed) over
// the next 0.5 s. Arg: threads.
void BM_SeedScale(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  Scene scene = loadScene(kAssets + "/scenes/seed-scale.json");
  for (int s = 0; s < 60; ++s) scene.world.step();
  SceneRunner runner(scene, /*deform=*/true);
  SweepVisits sweeps;
  for (auto _ : state) {
    runner.step();
    sweeps.add(scene.world);
  }
  reportPhases(state, runner.totals());
  sweeps.report(state);
  state.counters["bodies"] = double(scene.bodies.size());
  setThreadCount(0);
}
BENCHMARK(BM_SeedScale)
    ->Arg(1)
    ->Arg(2)
    ->Iterations(30)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The render-mesh deform of every body of the seed-scale scene in one frame (issue 13: ≤ 4 ms on
// two threads), as SceneRunner does it, at 1.5 s (the pile forming, every body awake). Bodies
// whose cage moved as a whole (rigid ones) follow it without the weights
// (sim/cage/rigid_follow.h): counted as `followed`. Arg: threads.
void BM_SeedScaleDeform(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  Scene scene = loadScene(kAssets + "/scenes/seed-scale.json");
  for (int s = 0; s < 90; ++s) scene.world.step();
  std::vector<int> which;
  std::vector<PointsRowMajor> meshes(scene.bodies.size());
  std::vector<PointsRowMajor*> outs;
  long long vertices = 0, weights = 0;
  int followed = 0;
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    which.push_back(int(i));
    outs.push_back(&meshes[i]);
    const SceneBody& b = scene.bodies[i];
    if (!b.render) continue;
    PointsRowMajor out;
    const ConstPointsRef cage = scene.world.positions(b.handle).topRows(b.cageVertexCount);
    if (b.render->rigidFollow && b.render->rigidFollow->follow(cage, out))
      ++followed;
    else
      weights += b.render->embedding->nonZeros();
    vertices += b.render->embedding->meshVertexCount();
  }
  for (auto _ : state) scene.renderVertices(which, outs);
  state.counters["render_vertices"] = double(vertices);
  state.counters["weights_applied"] = double(weights);
  state.counters["followed"] = followed;
  setThreadCount(0);
}
BENCHMARK(BM_SeedScaleDeform)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The large scene once every body sleeps (issue 11: a resting scene should cost next to
// nothing): stepped until all sleep (4.4 s simulated), then timed with the render-mesh deform.
void BM_LargeSceneAsleep(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  Scene scene = loadScene(kAssets + "/scenes/large.json");
  for (int s = 0; s < 1200 && scene.world.sleepingCount() < int(scene.bodies.size()); ++s)
    scene.world.step();
  SceneRunner runner(scene, /*deform=*/true);
  runner.step();  // the first deform of every mesh
  runner.clearTotals();
  for (auto _ : state) runner.step();
  reportPhases(state, runner.totals());
  state.counters["sleeping"] = double(scene.world.sleepingCount());
  state.counters["bodies"] = double(scene.bodies.size());
  setThreadCount(0);
}
BENCHMARK(BM_LargeSceneAsleep)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();

// How the contact phase grows with the number of bodies: N bunny cages (164 particles each) in
// a square layer on the floor, each touching its neighbours, settled for 2 s before timing.
void BM_ContactScaling(benchmark::State& state) {
  setThreadCount(int(state.range(1)));
  const int count = int(state.range(0));
  const mesh::TriangleMesh cage = mesh::readMesh(kAssets + "/meshes/bunny_cage.obj");
  WorldSettings settings;
  settings.timeStep = 1.0 / 60;
  settings.substeps = 4;
  settings.sleep = false;  // the cost of awake contact (settled bodies would fall asleep)
  World world(settings);
  world.addCollider(Collider::plane(Vec3::UnitY(), 0.0, 0.6));
  const int side = int(std::ceil(std::sqrt(double(count))));
  const double scale = 0.05, pitch = 0.45;  // bunnies ~0.5 m wide: neighbours overlap boxes
  for (int b = 0; b < count; ++b) {
    BodyDef def;
    def.name = "bunny " + std::to_string(b);
    const Vec3 at(pitch * (b % side), 0.3 + 0.02 * (b % 3), pitch * (b / side));
    for (const Vec3& v : cage.vertices) def.positions.push_back(at + scale * v);
    def.surface = cage.triangles;
    def.params.mode = b % 2 ? Mode::Linear : Mode::Quadratic;
    def.params.alpha = 0.3;
    def.params.damping = 0.05;
    world.addBody(def);
  }
  for (int s = 0; s < 120; ++s) world.step();
  RunTotals totals;
  SweepVisits sweeps;
  for (auto _ : state) {
    world.step();
    totals.phases += world.lastProfile();
    totals.contacts += world.lastContactCount();
    ++totals.steps;
    sweeps.add(world);
  }
  reportPhases(state, totals);
  sweeps.report(state);
  state.counters["contacts_us_per_body"] =
      1e6 * totals.phases[Phase::Contacts] / double(totals.steps) / count;
  setThreadCount(0);
}
BENCHMARK(BM_ContactScaling)
    ->ArgsProduct({{8, 16, 32, 64, 128}, {1, 2}})
    ->Iterations(120)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace sb

BENCHMARK_MAIN();
