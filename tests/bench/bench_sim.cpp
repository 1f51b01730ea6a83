// Simulation benchmarks (Google Benchmark). Run a Release build:
//   build/release/tests/bench/bench_sim
// Counters: ns_per_particle = seconds per particle per step; ns_per_membership = seconds per
// particle–cluster membership per step (displayed with SI prefixes, e.g. "4.1n" = 4.1 ns).
#include <benchmark/benchmark.h>

#include "sim/parallel.h"
#include "sim/world.h"

namespace sb {
namespace {

std::vector<Vec3> gridPoints(int nx, int ny, int nz, double spacing) {
  std::vector<Vec3> p;
  p.reserve(size_t(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) p.push_back(spacing * Vec3(i, j, k));
  return p;
}

WorldSettings settings(int substeps) {
  WorldSettings s;
  s.gravity = Vec3(0, -9.81, 0);
  s.timeStep = 1.0 / 60.0;
  s.substeps = substeps;
  return s;
}

// Deform the start so the goals do real work (not an identity fit).
void squash(World& world, BodyHandle b) {
  Eigen::MatrixX3d x = world.positions(b).cast<double>();
  x.col(0) *= 1.1;
  x.col(1) *= 0.9;
  world.setState(b, x, Eigen::MatrixX3d::Zero(x.rows(), 3));
}

void runSteps(benchmark::State& state, World& world, double particles, double memberships) {
  for (auto _ : state) world.step();
  state.counters["ns_per_particle"] = benchmark::Counter(
      particles, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  if (memberships > 0)
    state.counters["ns_per_membership"] = benchmark::Counter(
        memberships, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["threads"] = threadCount();
}

// One cluster holding 10⁶ particles (100³ grid).
void singleCluster(benchmark::State& state, Mode mode) {
  setThreadCount(int(state.range(0)));
  World world(settings(1));
  BodyDef def;
  def.positions = gridPoints(100, 100, 100, 0.01);
  def.params.mode = mode;
  def.params.alpha = 0.5;
  def.params.beta = 0.5;
  const BodyHandle b = world.addBody(def);
  squash(world, b);
  runSteps(state, world, double(def.positions.size()), 0);
  setThreadCount(0);
}

void BM_LinearOneCluster(benchmark::State& state) {
  singleCluster(state, Mode::Linear);
}
void BM_QuadraticOneCluster(benchmark::State& state) {
  singleCluster(state, Mode::Quadratic);
}
BENCHMARK(BM_LinearOneCluster)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_QuadraticOneCluster)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Overlapping grid clusters: cells of 4³ particles grown by one whole cell on every side, so an
// interior particle belongs to 27 clusters. 40³ = 64,000 particles.
void BM_OverlappingClusters(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  World world(settings(1));
  BodyDef def;
  def.positions = gridPoints(40, 40, 40, 0.01);
  def.params.mode = Mode::Linear;
  def.clusters.kind = ClusterDef::Kind::Grid;
  def.clusters.cellSize = 0.04;
  def.clusters.overlap = 0.04;
  const BodyHandle b = world.addBody(def);
  squash(world, b);
  double memberships = 0;
  for (const auto& c : world.clusterMembers(b)) memberships += double(c.size());
  state.counters["memberships_per_particle"] = memberships / double(def.positions.size());
  runSteps(state, world, double(def.positions.size()), memberships);
  setThreadCount(0);
}
BENCHMARK(BM_OverlappingClusters)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// A bar of 30×5×5 = 750 particles split into tetrahedral four-particle clusters (5 per grid
// cube: 2,320 clusters), 5 sub-steps per step.
void BM_TetBar(benchmark::State& state) {
  setThreadCount(int(state.range(0)));
  World world(settings(5));
  BodyDef def;
  const int nx = 30, ny = 5, nz = 5;
  def.positions = gridPoints(nx, ny, nz, 0.02);
  def.params.mode = Mode::Linear;
  def.clusters.kind = ClusterDef::Kind::Explicit;
  auto id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        const int c[8] = {id(i, j, k),         id(i + 1, j, k),        id(i, j + 1, k),
                          id(i + 1, j + 1, k), id(i, j, k + 1),        id(i + 1, j, k + 1),
                          id(i, j + 1, k + 1), id(i + 1, j + 1, k + 1)};
        // Five tetrahedra per cube.
        def.clusters.clusters.push_back({c[0], c[1], c[2], c[4]});
        def.clusters.clusters.push_back({c[1], c[3], c[2], c[7]});
        def.clusters.clusters.push_back({c[1], c[4], c[5], c[7]});
        def.clusters.clusters.push_back({c[2], c[4], c[7], c[6]});
        def.clusters.clusters.push_back({c[1], c[2], c[4], c[7]});
      }
  def.pinned = {id(0, 0, 0), id(0, ny - 1, 0), id(0, 0, nz - 1), id(0, ny - 1, nz - 1)};
  const BodyHandle b = world.addBody(def);
  state.counters["clusters"] = world.clusterCount(b);
  runSteps(state, world, double(def.positions.size()), double(def.clusters.clusters.size()) * 4.0);
  setThreadCount(0);
}
BENCHMARK(BM_TetBar)->Arg(1)->Arg(2)->Iterations(600)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace
}  // namespace sb

BENCHMARK_MAIN();
