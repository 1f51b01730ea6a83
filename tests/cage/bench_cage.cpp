// Benchmarks of the cage deformer (run by hand, Release build; not a CTest test):
//   bench_cage --benchmark_filter=Bind     ns per cage triangle per query point, 1 and 2 threads
//   bench_cage --benchmark_filter=Deform   ms per frame for 100k vertices, dense and pruned
//   bench_cage --benchmark_filter=AutoCage automatic cages: time and Hausdorff distance (% of the
//                                          diagonal) vs input triangles (bunny, flat box) and
//                                          vs vertex budget
#include <benchmark/benchmark.h>
#include <omp.h>

#include "sim/base/parallel.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sim/cage/auto_cage.h"
#include "sim/cage/embedding.h"
#include "sim/cage/mvc.h"
#include "sim/mesh/mesh_io.h"
#include "sim/mesh/normals.h"
#include "tests/draws.h"
#include "tests/mesh/mesh_fixtures.h"

namespace {

using namespace sb::cage;
using namespace sb::mesh;
using Vec3 = Eigen::Vector3d;

std::vector<Vec3> randomPointsInBox(int n, const Vec3& lo, const Vec3& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<Vec3> p(n);
  for (auto& x : p)
    x = lo + (hi - lo).cwiseProduct(sb::test::drawVector<Vec3>([&] { return U(rng); }));
  return p;
}

// Evaluates the weights of every point (what bind does, without validation, pruning or stats).
void runKernel(benchmark::State& state, const TriangleMesh& cage, const std::vector<Vec3>& points) {
  const int threads = static_cast<int>(state.range(1));
  const MeanValueCage mc(cage);
  const int m = mc.vertexCount();
  std::vector<double> sink(points.size());
  for (auto _ : state) {
#pragma omp parallel num_threads(threads)
    {
      MeanValueCage::Scratch scratch;
      std::vector<double> w(m);
#pragma omp for schedule(static)
      for (int i = 0; i < static_cast<int>(points.size()); ++i) {
        mc.weights(points[i], w.data(), scratch);
        sink[i] = w[i % m];
      }
    }
    benchmark::DoNotOptimize(sink.data());
    benchmark::ClobberMemory();
  }
  const double work =
      static_cast<double>(cage.triangles.size()) * static_cast<double>(points.size());
  state.counters["ns_per_tri_point"] = benchmark::Counter(
      work, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["cage_vertices"] = static_cast<double>(m);
  state.counters["cage_triangles"] = static_cast<double>(cage.triangles.size());
  state.counters["points"] = static_cast<double>(points.size());
}

// Box cages 0.3 × 0.3 × 1 with 6k × 6k × 20k segments: 554, 2210, 4970, 8834 vertices.
void BM_BindBox(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  const TriangleMesh cage = testing::makeBox(6 * k, 6 * k, 20 * k, Vec3(0.3, 0.3, 1.0));
  const int npts = 2048 / (k * k);
  const auto points = randomPointsInBox(npts, Vec3(0.01, 0.01, 0.01), Vec3(0.29, 0.29, 0.99), 1);
  runKernel(state, cage, points);
}
BENCHMARK(BM_BindBox)
    ->ArgsProduct({{1, 2, 3, 4}, {1, 2}})
    ->ArgNames({"k", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_BindRealMesh(benchmark::State& state) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  const bool bunny = state.range(0) == 0;
  const TriangleMesh mesh = readMesh(dir + (bunny ? "/bunny.obj" : "/suzanne.obj"));
  const TriangleMesh cage = readMesh(dir + (bunny ? "/bunny_cage.obj" : "/suzanne_cage.obj"));
  state.SetLabel(bunny ? "bunny in bunny_cage" : "suzanne in suzanne_cage");
  runKernel(state, cage, mesh.vertices);
}
BENCHMARK(BM_BindRealMesh)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"mesh", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The full bind (validation, weights, statistics, storage) of the real meshes.
void BM_BindMeanValueFull(benchmark::State& state) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  const TriangleMesh mesh = readMesh(dir + "/bunny.obj");
  const TriangleMesh cage = readMesh(dir + "/bunny_cage.obj");
  BindOptions o;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    Embedding e = bindMeanValue(mesh.vertices, cage, o);
    benchmark::DoNotOptimize(e.nonZeros());
  }
  const double work =
      static_cast<double>(cage.triangles.size()) * static_cast<double>(mesh.vertices.size());
  state.counters["ns_per_tri_point"] = benchmark::Counter(
      work, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_BindMeanValueFull)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------------------------------------
// Deform: 100k points inside a 242-vertex box cage (6×6×7 segments).

struct DeformSetup {
  TriangleMesh cage;
  std::vector<Vec3> points;
  Embedding dense;
  std::vector<std::pair<double, Embedding>> sparse;  // threshold, embedding
  sb::PointsRowMajor movedCage;                      // a non-affine pose (twist + bend)
  Eigen::Matrix<double, Eigen::Dynamic, 3> exact;    // dense double result for that pose
};

DeformSetup& deformSetup() {
  static std::unique_ptr<DeformSetup> s;
  if (!s) {
    s = std::make_unique<DeformSetup>();
    s->cage = testing::makeBox(6, 6, 7, Vec3(1.0, 1.0, 1.2));
    s->points = randomPointsInBox(100000, Vec3(0.02, 0.02, 0.02), Vec3(0.98, 0.98, 1.18), 2);
    BindOptions o;
    o.storage = WeightStorage::Dense;
    s->dense = bindMeanValue(s->points, s->cage, o);
    for (double thr : {1e-2, 3e-2, 1e-1}) {
      BindOptions so;
      so.storage = WeightStorage::Sparse;
      so.pruneThreshold = thr;
      so.keepDoublePrecision = true;
      s->sparse.emplace_back(thr, bindMeanValue(s->points, s->cage, so));
    }
    const int m = static_cast<int>(s->cage.vertices.size());
    s->movedCage.resize(m, 3);
    Eigen::Matrix<double, Eigen::Dynamic, 3> moved(m, 3);
    for (int j = 0; j < m; ++j) {
      const Vec3 v = s->cage.vertices[j];
      const double a = 0.8 * v.z();  // twist about z, plus a bend in x
      const Vec3 c(0.5, 0.5, 0.0);
      const Vec3 r = v - c;
      const Vec3 tw(c.x() + std::cos(a) * r.x() - std::sin(a) * r.y(),
                    c.y() + std::sin(a) * r.x() + std::cos(a) * r.y(), v.z());
      moved.row(j) = (tw + Vec3(0.3 * v.z() * v.z(), 0.0, 0.0)).transpose();
    }
    s->movedCage = moved.cast<float>();
    s->dense.deformDouble(moved, s->exact);
  }
  return *s;
}

double maxError(const sb::PointsRowMajor& out,
                const Eigen::Matrix<double, Eigen::Dynamic, 3>& exact, double L) {
  return (out.cast<double>() - exact).rowwise().norm().maxCoeff() / L;
}

void BM_DeformDense(benchmark::State& state) {
  DeformSetup& s = deformSetup();
  sb::setThreadCount(static_cast<int>(state.range(0)));
  sb::PointsRowMajor out;
  const Eigen::Matrix<float, Eigen::Dynamic, 3> cage = s.movedCage;
  for (auto _ : state) {
    s.dense.deform(cage, out);
    benchmark::DoNotOptimize(out.data());
  }
  const double L = testing::diagonal(s.cage);
  state.counters["max_err_rel"] = maxError(out, s.exact, L);
  state.counters["nonzeros"] = static_cast<double>(s.dense.nonZeros());
  state.counters["MB_weights"] = static_cast<double>(s.dense.nonZeros()) * 4e-6;
}
BENCHMARK(BM_DeformDense)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_DeformSparse(benchmark::State& state) {
  DeformSetup& s = deformSetup();
  sb::setThreadCount(static_cast<int>(state.range(1)));
  const auto& [thr, emb] = s.sparse[static_cast<std::size_t>(state.range(0))];
  sb::PointsRowMajor out;
  const Eigen::Matrix<float, Eigen::Dynamic, 3> cage = s.movedCage;
  for (auto _ : state) {
    emb.deform(cage, out);
    benchmark::DoNotOptimize(out.data());
  }
  const double L = testing::diagonal(s.cage);
  state.SetLabel("prune " + std::to_string(thr));
  state.counters["max_err_rel"] = maxError(out, s.exact, L);  // twisted pose, vs dense double
  state.counters["rest_err_rel"] = emb.stats().pruningError;
  state.counters["nonzeros"] = static_cast<double>(emb.nonZeros());
  state.counters["max_row_L1"] = emb.stats().maxPrunedL1;
}
BENCHMARK(BM_DeformSparse)
    ->ArgsProduct({{0, 1, 2}, {1, 2}})
    ->ArgNames({"thr", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_Normals(benchmark::State& state) {
  const TriangleMesh mesh = readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj");
  sb::PointsRowMajor pos(static_cast<Eigen::Index>(mesh.vertices.size()), 3), nrm;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    pos.row(static_cast<Eigen::Index>(i)) = mesh.vertices[i].cast<float>().transpose();
  for (auto _ : state) {
    computeVertexNormals(mesh.triangles, pos, nrm);
    benchmark::DoNotOptimize(nrm.data());
  }
  state.counters["vertices"] = static_cast<double>(mesh.vertices.size());
}
BENCHMARK(BM_Normals)->Unit(benchmark::kMicrosecond);

// Splits every triangle into four at its edge midpoints (the shape stays the same).
TriangleMesh subdivided(const TriangleMesh& m, int levels) {
  TriangleMesh out = m;
  for (int l = 0; l < levels; ++l) {
    TriangleMesh next;
    next.vertices = out.vertices;
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      next.vertices.push_back(0.5 * (out.vertices[std::size_t(a)] + out.vertices[std::size_t(b)]));
      return mid[key] = static_cast<int>(next.vertices.size()) - 1;
    };
    for (const auto& t : out.triangles) {
      const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.triangles.push_back({t[0], ab, ca});
      next.triangles.push_back({ab, t[1], bc});
      next.triangles.push_back({ca, bc, t[2]});
      next.triangles.push_back({ab, bc, ca});
    }
    out = std::move(next);
  }
  return out;
}

void runAutoCage(benchmark::State& state, const TriangleMesh& m, int budget, double tightness) {
  CageOptions o;
  o.vertexBudget = budget;
  o.tightness = tightness;
  CageReport report;
  for (auto _ : state) report = makeCage(m, o).report;
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  state.counters["cage_vertices"] = report.vertices;
  state.counters["hausdorff_pct"] = 100.0 * report.hausdorffRelative;
}

// The bunny (3,674 triangles) subdivided 1, 3 and 4 times: 14.7k, 235k and 940k triangles;
// second argument: tightness in tenths.
void BM_AutoCageVsTriangles(benchmark::State& state) {
  const TriangleMesh m = subdivided(readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj"),
                                    static_cast<int>(state.range(0)));
  runAutoCage(state, m, 250, 0.1 * static_cast<double>(state.range(1)));
}
BENCHMARK(BM_AutoCageVsTriangles)
    ->Args({1, 2})
    ->Args({1, 5})
    ->Args({3, 2})
    ->Args({3, 5})
    ->Args({4, 2})
    ->Args({4, 5})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

// Flat faces: a unit box with n × n segments per face (12n² triangles; 10: 1.2k, 100: 120k). On
// flat parts every collapse costs ~0 and only the tie-break keeps the fans small.
void BM_AutoCageFlatBox(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  runAutoCage(state, testing::makeBox(n, n, n), 250, CageOptions{}.tightness);
}
BENCHMARK(BM_AutoCageFlatBox)->Arg(10)->Arg(100)->Unit(benchmark::kSecond)->Iterations(1);

void BM_AutoCageVsBudget(benchmark::State& state) {
  const TriangleMesh m = readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj");
  runAutoCage(state, m, static_cast<int>(state.range(0)), CageOptions{}.tightness);
}
BENCHMARK(BM_AutoCageVsBudget)
    ->Arg(100)
    ->Arg(250)
    ->Arg(500)
    ->Arg(1000)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
