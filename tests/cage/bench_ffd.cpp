// Benchmarks of the FFD lattices (run by hand, Release build; not a CTest test). The thesis'
// comparison (ffd-methods: de Boor's algorithm per point per frame against precomputed basis
// products), for 100k points in the unit cube and lattices of 4×4×4, 8×8×8 and 6×6×7 nodes
// (cubic B-spline) and 4×4×4 (Bernstein, degree 3: the thesis' case), one thread:
//   BM_FfdDeBoor           ffdDeformDeBoor: recursive evaluation of every point, every frame
//                          (de Boor; de Casteljau, its Bézier case, for Bernstein)
//   BM_FfdPrecomputed      Embedding::deform (float) with the bindFfd weights: W · nodes
//   BM_FfdPrecomputedDouble Embedding::deformDouble (Eigen product, double)
//   BM_FfdBind             bindFfd: the per-point basis products (the precomputation) and the
//                          Embedding built from them
//   BM_FfdWeights          the per-point products alone (ffdWeights, reused buffer)
// Counter per_vertex = time per frame / 100k (seconds, SI prefix).
#include <benchmark/benchmark.h>

#include <array>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/cage/ffd_lattice.h"
#include "tests/draws.h"

namespace {

using namespace sb::cage;
using Vec3 = Eigen::Vector3d;

constexpr int kPoints = 100000;

struct Config {
  const char* name;
  FfdBasis basis;
  std::array<int, 3> nodes;
};
const Config kConfigs[] = {{"bspline 4x4x4 (64)", FfdBasis::BSpline, {4, 4, 4}},
                           {"bspline 8x8x8 (512)", FfdBasis::BSpline, {8, 8, 8}},
                           {"bspline 6x6x7 (252)", FfdBasis::BSpline, {6, 6, 7}},
                           {"bernstein 4x4x4 (64)", FfdBasis::Bernstein, {4, 4, 4}}};

struct Setup {
  FfdLattice lattice;
  std::vector<Vec3> points;
  FfdNodes nodes;  // rest + random displacements of 0.3 spacings (a deformed, unfolded pose)
  Embedding embedding;
};

const std::vector<Vec3>& points() {
  static const std::vector<Vec3> p = [] {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::vector<Vec3> q(kPoints);
    for (auto& x : q) x = sb::test::drawVector<Vec3>([&] { return U(rng); });
    return q;
  }();
  return p;
}

Setup& setup(int config) {
  static std::vector<std::unique_ptr<Setup>> cache(std::size(kConfigs));
  auto& s = cache[static_cast<std::size_t>(config)];
  if (!s) {
    s = std::make_unique<Setup>();
    const Config& c = kConfigs[config];
    s->lattice.origin = Vec3::Zero();
    s->lattice.size = Vec3::Ones();
    s->lattice.nodes = c.nodes;
    s->lattice.basis = c.basis;
    s->points = points();
    s->nodes = s->lattice.restNodes();
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> U(-0.3, 0.3);
    const Vec3 h = s->lattice.spacing();
    for (Eigen::Index n = 0; n < s->nodes.rows(); ++n)
      for (int a = 0; a < 3; ++a) s->nodes(n, a) += U(rng) * h[a];
    s->embedding = bindFfd(s->points, s->lattice);
  }
  return *s;
}

void perVertex(benchmark::State& state, int config) {
  state.SetLabel(kConfigs[config].name);
  // Seconds per vertex (shown with an SI prefix: "23n" = 23 ns).
  state.counters["per_vertex"] = benchmark::Counter(
      kPoints, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_FfdDeBoor(benchmark::State& state) {
  const int c = static_cast<int>(state.range(0));
  Setup& s = setup(c);
  Eigen::Matrix<double, Eigen::Dynamic, 3> out;
  for (auto _ : state) {
    ffdDeformDeBoor(s.lattice, s.nodes, s.points, out);
    benchmark::DoNotOptimize(out.data());
  }
  perVertex(state, c);
}

void BM_FfdPrecomputed(benchmark::State& state) {
  const int c = static_cast<int>(state.range(0));
  Setup& s = setup(c);
  sb::setThreadCount(1);
  const Eigen::Matrix<float, Eigen::Dynamic, 3> nodes = s.nodes.cast<float>();
  sb::PointsRowMajor out;
  for (auto _ : state) {
    s.embedding.deform(nodes, out);
    benchmark::DoNotOptimize(out.data());
  }
  // Agreement with de Boor on this pose (float deform), in units of the box size.
  Eigen::Matrix<double, Eigen::Dynamic, 3> ref;
  ffdDeformDeBoor(s.lattice, s.nodes, s.points, ref);
  state.counters["max_err"] = (out.cast<double>() - ref).cwiseAbs().maxCoeff();
  state.counters["nonzeros_per_row"] =
      static_cast<double>(s.embedding.nonZeros()) / s.embedding.meshVertexCount();
  perVertex(state, c);
}

void BM_FfdPrecomputedDouble(benchmark::State& state) {
  const int c = static_cast<int>(state.range(0));
  Setup& s = setup(c);
  Eigen::Matrix<double, Eigen::Dynamic, 3> out;
  for (auto _ : state) {
    s.embedding.deformDouble(s.nodes, out);
    benchmark::DoNotOptimize(out.data());
  }
  perVertex(state, c);
}

void BM_FfdBind(benchmark::State& state) {
  const int c = static_cast<int>(state.range(0));
  Setup& s = setup(c);
  for (auto _ : state) {
    Embedding e = bindFfd(s.points, s.lattice);
    benchmark::DoNotOptimize(&e);
  }
  perVertex(state, c);
}

// The per-point work of the bind alone (ffdWeights into a reused vector: validation, per-axis
// bases, 64 or #nodes products), without building the Embedding.
void BM_FfdWeights(benchmark::State& state) {
  const int c = static_cast<int>(state.range(0));
  Setup& s = setup(c);
  std::vector<std::pair<int, double>> w;
  double sink = 0.0;
  for (auto _ : state) {
    for (const Vec3& x : s.points) {
      ffdWeights(s.lattice, x, w);
      sink += w[w.size() / 2].second;
    }
    benchmark::DoNotOptimize(sink);
  }
  perVertex(state, c);
}

#define FFD_CONFIGS DenseRange(0, static_cast<int>(std::size(kConfigs)) - 1)->ArgName("lattice")
BENCHMARK(BM_FfdDeBoor)->FFD_CONFIGS->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FfdPrecomputed)->FFD_CONFIGS->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FfdPrecomputedDouble)->FFD_CONFIGS->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FfdBind)->FFD_CONFIGS->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FfdWeights)->FFD_CONFIGS->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
