// Benchmarks of harmonic coordinates (run by hand, Release build; not a CTest test):
//   bench_harmonic --benchmark_filter=Bind     bind of the bunny (1839 vertices) in bunny_cage
//                                              (164 vertices) at resolutions 32, 48, 64, 1 and
//                                              2 threads; counters: the phases (s), grid
//                                              unknowns, factor non-zeros, linear-precision error
//                                              (fraction of the cage diagonal); amd:1 = Eigen's
//                                              AMD ordering (default), amd:0 = nested dissection;
//                                              cut:0 = HarmonicBoundary::ClosestPoint; cg:0 =
//                                              HarmonicSolver::Direct, cg:1 = MultigridCg
//                                              (counter cg_its: most CG iterations)
//   bench_harmonic --benchmark_filter=Deform   ms per frame for 100k points (dense W)
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>

#include <random>
#include <string>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/cage/harmonic.h"
#include "sim/cage/interior_points.h"
#include "sim/mesh/mesh_io.h"

namespace {

using namespace sb::cage;
using namespace sb::mesh;
using Vec3 = Eigen::Vector3d;

void BM_BindHarmonicBunny(benchmark::State& state) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  const TriangleMesh mesh = readMesh(dir + "/bunny.obj");
  const TriangleMesh cage = readMesh(dir + "/bunny_cage.obj");
  HarmonicOptions o;
  o.resolution = static_cast<int>(state.range(0));
  o.threads = static_cast<int>(state.range(1));
  o.ordering = state.range(2) == 1 ? HarmonicOrdering::Amd : HarmonicOrdering::NestedDissection;
  o.boundary = state.range(3) == 1 ? HarmonicBoundary::CutCell : HarmonicBoundary::ClosestPoint;
  o.solver = state.range(4) == 1 ? HarmonicSolver::MultigridCg : HarmonicSolver::Direct;
  HarmonicReport r;
  for (auto _ : state) {
    Embedding e = bindHarmonic(mesh.vertices, cage, o, &r);
    benchmark::DoNotOptimize(e.nonZeros());
  }
  state.counters["classify_s"] = r.classifySeconds;
  state.counters["factor_s"] = r.factorSeconds;
  state.counters["solve_s"] = r.solveSeconds;
  state.counters["lookup_s"] = r.lookupSeconds;
  state.counters["total_s"] = r.totalSeconds;
  state.counters["cg_its"] = r.maxCgIterations;
  state.counters["unknowns"] = static_cast<double>(r.interiorNodes);
  state.counters["L_nnz"] = static_cast<double>(r.factorNonZeros);
  state.counters["lin_err"] = r.maxLinearError;
  state.counters["sum_err"] = r.maxSumError;
  state.counters["min_w"] = r.minWeight;
  state.counters["points"] = static_cast<double>(mesh.vertices.size());
  state.counters["cage_vertices"] = static_cast<double>(cage.vertices.size());
}
BENCHMARK(BM_BindHarmonicBunny)
    ->ArgsProduct({{32, 48, 64}, {1, 2}, {1}, {1}, {0, 1}})
    ->ArgsProduct({{32, 48, 64}, {1}, {0}, {1}, {0, 1}})
    ->ArgsProduct({{32, 48, 64}, {1}, {1}, {0}, {0}})
    ->ArgNames({"res", "threads", "amd", "cut", "cg"})
    ->UseRealTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Deform of 100k points inside bunny_cage (dense W, 164 columns): the same product as the mean
// value coordinates' dense deform (bench_cage BM_Deform*).
void BM_DeformHarmonic100k(benchmark::State& state) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  const TriangleMesh cage = readMesh(dir + "/bunny_cage.obj");
  Eigen::AlignedBox3d box;
  for (const Vec3& v : cage.vertices) box.extend(v);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<Vec3> points(100000);
  for (Vec3& p : points) p = box.min() + box.sizes().cwiseProduct(Vec3(U(rng), U(rng), U(rng)));
  HarmonicOptions o;
  o.resolution = 32;
  o.keepDoublePrecision = false;
  const Embedding e = bindHarmonic(points, cage, o);
  Eigen::Matrix<float, Eigen::Dynamic, 3> moved(cage.vertices.size(), 3);
  for (std::size_t j = 0; j < cage.vertices.size(); ++j)
    moved.row(Eigen::Index(j)) = (1.1 * cage.vertices[j]).cast<float>().transpose();
  sb::PointsRowMajor out;
  sb::setThreadCount(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    e.deform(moved, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  sb::setThreadCount(0);
}
BENCHMARK(BM_DeformHarmonic100k)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
