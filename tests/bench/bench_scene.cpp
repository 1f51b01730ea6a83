// Scene benchmarks (Google Benchmark): whole shipped scenes and body–body contact scaling.
// Run a Release build:  build/release/tests/bench/bench_scene
// Counters are milliseconds per step (simulation phases and the render-mesh deform) averaged
// over the timed steps, and steps_per_s for simulation + deform together.
#include <benchmark/benchmark.h>

#include <chrono>

#include "sim/cage/mesh_io.h"
#include "sim/parallel.h"
#include "sim/scene.h"

namespace sb {
namespace {

const std::string kAssets = SOFTBODY_ASSET_DIR;

void reportPhases(benchmark::State& state, const StepProfile& sum, double deformSeconds,
                  long long contacts, long long steps) {
  const double perStep = 1e3 / double(steps);
  state.counters["goals_ms"] = sum.goals * perStep;
  state.counters["integrate_ms"] = sum.integrate * perStep;
  state.counters["damping_ms"] = sum.damping * perStep;
  state.counters["contacts_ms"] = sum.contacts * perStep;
  state.counters["collide_ms"] = sum.collide * perStep;
  state.counters["deform_ms"] = deformSeconds * perStep;
  state.counters["steps_per_s"] = double(steps) / (sum.total() + deformSeconds);
  state.counters["contacts_per_substep"] = double(contacts) / double(steps);
  state.counters["threads"] = threadCount();
}

// The shipped large scene (≥ 50 bodies, ≥ 50k render vertices): simulation, collisions and the
// deform of every render mesh, timed after the first 2 s (the top layer is still landing then).
void BM_LargeScene(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  Scene scene = loadScene(kAssets + "/scenes/large.json");
  for (int s = 0; s < 120; ++s) scene.world.step();
  std::vector<PointsRowMajor> meshes(scene.bodies.size());
  long long renderVertices = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    scene.renderVertices(int(i), meshes[i]);
    renderVertices += meshes[i].rows();
  }
  StepProfile sum;
  double deformSeconds = 0;
  long long contacts = 0, steps = 0;
  for (auto _ : state) {
    scene.world.step();
    const auto t0 = std::chrono::steady_clock::now();
    scene.renderVerticesAll(meshes);
    deformSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    sum += scene.world.lastProfile();
    contacts += scene.world.lastContactCount();
    ++steps;
  }
  reportPhases(state, sum, deformSeconds, contacts, steps);
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

// How the contact phase grows with the number of bodies: N bunny cages (164 particles each) in
// a square layer on the floor, each touching its neighbours, settled for 2 s before timing.
void BM_ContactScaling(benchmark::State& state) {
  setThreadCount(int(state.range(1)));
  const int count = int(state.range(0));
  const cage::TriangleMesh cage = cage::readMesh(kAssets + "/meshes/bunny_cage.obj");
  WorldSettings settings;
  settings.timeStep = 1.0 / 60;
  settings.substeps = 4;
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
  StepProfile sum;
  long long contacts = 0, steps = 0;
  for (auto _ : state) {
    world.step();
    sum += world.lastProfile();
    contacts += world.lastContactCount();
    ++steps;
  }
  reportPhases(state, sum, 0.0, contacts, steps);
  state.counters["contacts_us_per_body"] = 1e6 * sum.contacts / double(steps) / count;
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
