// Benchmarks of Green coordinates (run by hand, Release build; not a CTest test):
//   bench_green --benchmark_filter=Bind     bind of the bunny (1839 vertices) in bunny_cage
//                                           (164 vertices, 324 faces), 1 and 2 threads;
//                                           ns_per_point_control = time / (points × (V + F))
//   bench_green --benchmark_filter=Deform   one frame for ~100k interior points (dense W, float,
//                                           V + F extended controls), greenControls included;
//                                           counters: controls_us (greenControls alone)
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>

#include <chrono>
#include <string>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/cage/green.h"
#include "sim/cage/interior_points.h"
#include "sim/mesh/mesh_io.h"

namespace {

using namespace sb::cage;
using namespace sb::mesh;
using Vec3 = Eigen::Vector3d;
using MatX3d = Eigen::Matrix<double, Eigen::Dynamic, 3>;

void BM_BindGreenBunny(benchmark::State& state) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  const TriangleMesh mesh = readMesh(dir + "/bunny.obj");
  const TriangleMesh cage = readMesh(dir + "/bunny_cage.obj");
  GreenOptions o;
  o.threads = static_cast<int>(state.range(0));
  double lin = 0.0;
  for (auto _ : state) {
    Embedding e = bindGreen(mesh.vertices, cage, o);
    lin = e.stats().maxLinearError;
    benchmark::DoNotOptimize(e.nonZeros());
  }
  const double cells =
      double(mesh.vertices.size()) * double(cage.vertices.size() + cage.triangles.size());
  state.counters["ns_per_point_control"] = benchmark::Counter(
      cells * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["points"] = double(mesh.vertices.size());
  state.counters["controls"] = double(cage.vertices.size() + cage.triangles.size());
  state.counters["rest_err"] = lin;
}
BENCHMARK(BM_BindGreenBunny)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// ~100k points on a lattice inside bunny_cage; the cage is bent (a non-affine motion) so the
// face rows are not trivial.
void BM_DeformGreen100k(benchmark::State& state) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  const TriangleMesh cage = readMesh(dir + "/bunny_cage.obj");
  Eigen::AlignedBox3d box;
  for (const Vec3& v : cage.vertices) box.extend(v);
  // Lattice spacing for about 100k points: the lattice inside bunny_cage fills about 30 % of the
  // cage's box (measured).
  const double spacing = std::cbrt(box.volume() * 0.3 / 1e5);
  static const std::vector<Vec3> points = interiorLattice(cage, spacing);
  GreenOptions o;
  o.keepDoublePrecision = false;
  static const Embedding e = bindGreen(points, cage, o);
  MatX3d moved(Eigen::Index(cage.vertices.size()), 3);
  const double L = box.diagonal().norm();
  for (std::size_t j = 0; j < cage.vertices.size(); ++j) {
    const Vec3 p = cage.vertices[j];
    const double a = 0.3 * (p.x() - box.center().x()) / L;
    moved.row(Eigen::Index(j)) =
        (Eigen::AngleAxisd(a, Vec3::UnitZ()) * (p - box.center()) + box.center()).transpose();
  }
  const sb::PointsRowMajor movedF = moved.cast<float>();
  // The extension by the face frames alone (part of every deform below).
  const auto c0 = std::chrono::steady_clock::now();
  constexpr int kControlRuns = 100;
  for (int r = 0; r < kControlRuns; ++r)
    benchmark::DoNotOptimize(greenControls(cage, moved).data());
  const double controlsSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count() / kControlRuns;
  sb::PointsRowMajor out;
  sb::setThreadCount(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    e.deform(movedF, out);  // the cage's V vertices, extended by greenControls inside
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  sb::setThreadCount(0);
  const double cells = double(points.size()) * double(e.weightColumns());
  state.counters["ns_per_point_control"] = benchmark::Counter(
      cells * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["controls_us"] = 1e6 * controlsSeconds;
  state.counters["points"] = double(points.size());
  state.counters["controls"] = double(e.weightColumns());
}
BENCHMARK(BM_DeformGreen100k)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
