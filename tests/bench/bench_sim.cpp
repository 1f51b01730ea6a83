// Simulation benchmarks (Google Benchmark). Run a Release build:
//   build/release/tests/bench/bench_sim
// Counters: ns_per_particle = seconds per particle per step; ns_per_membership = seconds per
// particle–cluster membership per step (displayed with SI prefixes, e.g. "4.1n" = 4.1 ns).
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>
#include <string>

#include "../sim/tet_bar.h"
#include "sim/base/parallel.h"
#include "sim/world/matching/cluster_batch.h"
#include "sim/world/step_phases.h"
#include "sim/world/world.h"
#include "tests/draws.h"

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
  // Exactly `substeps` sub-steps per step (not split to the default 1/120 s): the figures stay
  // per sub-step of the kernels, comparable with earlier runs.
  s.maxSubstep = s.timeStep / substeps;
  s.sleep = false;  // measure the work of awake bodies (a pinned bar at rest would fall asleep)
  return s;
}

// Deform the start so the goals do real work (not an identity fit).
void squash(World& world, BodyHandle b) {
  Eigen::MatrixX3d x = world.positions(b).cast<double>();
  x.col(0) *= 1.1;
  x.col(1) *= 0.9;
  world.setState(b, x, Eigen::MatrixX3d::Zero(x.rows(), 3));
}

// Counters: the totals below, and every phase that was timed as "<phase>_ns" (ns per particle per
// step), so a change to one phase shows where it went.
void runSteps(benchmark::State& state, World& world, double particles, double memberships) {
  StepProfile phases;
  double steps = 0;
  for (auto _ : state) {
    world.step();
    phases += world.lastProfile();
    ++steps;
  }
  for (Phase phase : kPhases)
    if (phases[phase] > 0)
      state.counters[std::string(phaseName(phase)) + "_ns"] =
          1e9 * phases[phase] / (steps * particles);
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
  BodyDef def = test::tetBar(30, 5, 5, 0.02);
  def.params.mode = Mode::Linear;
  const BodyHandle b = world.addBody(def);
  state.counters["clusters"] = world.clusterCount(b);
  runSteps(state, world, double(def.positions.size()), double(def.clusters.clusters.size()) * 4.0);
  setThreadCount(0);
}
BENCHMARK(BM_TetBar)->Arg(1)->Arg(2)->Iterations(600)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The batched small-cluster kernel alone (no World): 2,320 tetrahedral clusters of the tet bar's
// rest shape, each turned by its own rotation and stretched up to 10 %, warm-started 0.03 rad
// from the answer (about one sub-step of a fast-spinning cluster). Counter: ns per cluster.
void BM_SmallClusterKernel(benchmark::State& state) {
  const BodyDef bar = test::tetBar(30, 5, 5, 0.02);
  const std::vector<Vec3>& rest = bar.positions;
  std::vector<int> memberStart{0}, members;
  for (const std::vector<int>& tet : bar.clusters.clusters) {
    members.insert(members.end(), tet.begin(), tet.end());
    memberStart.push_back(static_cast<int>(members.size()));
  }
  const int clusters = static_cast<int>(memberStart.size()) - 1;
  std::vector<float> r[3], w(rest.size(), 1.0f);
  for (const Vec3& p : rest)
    for (int a = 0; a < 3; ++a) r[a].push_back(float(p[a]));
  // Current positions: each cluster's own copy (no sharing), so every cluster has its own fit.
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> stretch(0.9, 1.1);
  std::vector<float> x[3];
  std::vector<int> copies;
  std::vector<ClusterRestModel> restModels;
  std::vector<float> memberRest[3], memberWeight;
  std::vector<Eigen::Quaternionf> warm;
  for (int c = 0; c < clusters; ++c) {
    Eigen::Quaterniond q = test::drawQuaternion([&] { return g(rng); });
    q.normalize();
    const Mat3 F =
        q.toRotationMatrix() *
        test::drawVector<Vec3>([&] { return stretch(rng); }).asDiagonal().toDenseMatrix();
    const int* list = &members[size_t(memberStart[size_t(c)])];
    restModels.push_back(
        buildClusterRest(list, 4, r[0].data(), r[1].data(), r[2].data(), w.data()));
    for (int k = 0; k < 4; ++k) {
      const Vec3 p = F * rest[size_t(list[k])];
      copies.push_back(static_cast<int>(x[0].size()));
      for (int a = 0; a < 3; ++a) {
        x[a].push_back(float(p[a]));
        memberRest[a].push_back(r[a][size_t(list[k])] - restModels.back().centre[a]);
      }
      memberWeight.push_back(1.0f);
    }
    const Eigen::Quaterniond nudge(
        Eigen::AngleAxisd(0.03, test::drawVector<Vec3>([&] { return g(rng); }).normalized()));
    warm.push_back((nudge * q).cast<float>());
  }
  const float* memberRestCols[3] = {memberRest[0].data(), memberRest[1].data(),
                                    memberRest[2].data()};
  // Batches index the private copies.
  std::vector<ClusterBatch> batches = buildClusterBatches(Csr{memberStart, copies}, memberRestCols,
                                                          memberWeight.data(), restModels);
  std::vector<ClusterBatchShape> shapes(batches.size());
  std::vector<ClusterBatchLanes> start(batches.size());
  for (size_t b = 0; b < batches.size(); ++b)
    for (int l = 0; l < kBatchLanes; ++l) {
      const int c = batches[b].cluster[l];
      setBatchShapeLane(shapes[b], l, Mat3::Identity(),
                        deriveClusterShape(restModels[size_t(c)], Mat3::Identity(), false),
                        restModels[size_t(c)].centre);
      for (int a = 0; a < 3; ++a) start[b].ref[a][l] = x[a][size_t(copies[size_t(4 * c)])];
      const Eigen::Quaternionf& q = warm[size_t(c)];
      start[b].rotation[0][l] = q.w();
      start[b].rotation[1][l] = q.x();
      start[b].rotation[2][l] = q.y();
      start[b].rotation[3][l] = q.z();
    }
  const float* xs[3] = {x[0].data(), x[1].data(), x[2].data()};
  BodyParams params;  // linear, β 0.5, volume preserved
  std::uint32_t fallbacks = 0;
  for (auto _ : state) {
    for (size_t b = 0; b < batches.size(); ++b) {
      ClusterBatchLanes lanes = start[b];
      const ClusterBatchGoals goals = matchClusterBatch(batches[b], shapes[b], xs, params, lanes);
      fallbacks |= goals.fallback;
      benchmark::DoNotOptimize(goals);
    }
  }
  state.counters["clusters"] = clusters;
  state.counters["ns_per_cluster"] = benchmark::Counter(
      clusters, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["any_fallback"] = fallbacks != 0;
}
BENCHMARK(BM_SmallClusterKernel)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace sb

BENCHMARK_MAIN();
