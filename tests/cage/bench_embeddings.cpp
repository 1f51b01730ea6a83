// Every embedding side by side (issue 14's figures; run by hand, Release build; not a CTest test):
//   bench_embeddings --benchmark_filter=Bind    bind of the bunny (1839 vertices) to bunny_cage
//                                               (164 vertices); FFD: a 6×6×7 B-spline lattice
//                                               around the mesh. Counters: weights kept,
//                                               negative share, locality (share of |w| < 1e-6),
//                                               linear-precision error (fraction of the
//                                               controls' diagonal).
//   bench_embeddings --benchmark_filter=Deform  one frame for ~100k points inside the cage, 1 and
//                                               2 threads; counter ns per vertex per control
//                                               (per stored weight for sparse storage).
//   bench_embeddings --benchmark_filter=Bent    a 4:1:1 bar cage bent a quarter turn, its
//                                               controls moved by the exact bend: counters are,
//                                               at interior samples, the mean volume error
//                                               |det J / det J_bend − 1|, the mean shape error
//                                               |J J_bend⁻¹ − I| (Frobenius; 0 = the map bends
//                                               like the exact bend there), the mean anisotropy
//                                               σmax/σmin of J J_bend⁻¹ − 1 (0 = conformal to
//                                               it), and the folded share.
//   bench_embeddings --benchmark_filter=QuadCage  bind of 8000 random points inside a box cage of
//                                               216 planar quads (218 vertices, a 6×6 grid per
//                                               side) with triangle MVC over the reader's fan
//                                               triangles (polygon=0) and with polygon MVC
//                                               (polygon=1), 1 and 2 threads; counter ns per
//                                               point per cage vertex.
// Methods: 0 mvc, 1 harmonic (resolution 32), 2 rbf (shape 1), 3 ffd-bspline.
#include <benchmark/benchmark.h>

#include <Eigen/SVD>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/cage/bind.h"
#include "sim/cage/ffd_lattice.h"
#include "sim/cage/fold_check.h"
#include "sim/cage/interior_points.h"
#include "sim/mesh/mesh_io.h"
#include "tests/mesh/mesh_fixtures.h"

namespace {

using namespace sb::cage;
using sb::mesh::TriangleMesh;
using Vec3 = Eigen::Vector3d;
using MatX3d = Eigen::Matrix<double, Eigen::Dynamic, 3>;

const char* kNames[] = {"mvc", "harmonic", "rbf", "ffd-bspline"};

// An embedding of `points` and its controls' rest positions (cage vertices or lattice nodes).
struct Bound {
  Embedding embedding;
  MatX3d controls;
};

Bound bindWith(int method, const std::vector<Vec3>& points, const TriangleMesh& cage,
               std::array<int, 3> latticeNodes) {
  Bound b;
  if (method == 3) {
    const FfdLattice lattice = ffdLatticeAround(points, latticeNodes, FfdBasis::BSpline);
    b.embedding = bindFfd(points, lattice);
    b.controls = lattice.restNodes();
    return b;
  }
  EmbeddingMethod m;
  m.kind = method == 0   ? EmbeddingKind::MeanValue
           : method == 1 ? EmbeddingKind::Harmonic
                         : EmbeddingKind::Rbf;
  BindOptions o;
  o.storage = WeightStorage::Dense;  // the same storage for every cage method
  b.embedding = bindToCage(points, cage, m, o);
  b.controls.resize(Eigen::Index(cage.vertices.size()), 3);
  for (size_t j = 0; j < cage.vertices.size(); ++j)
    b.controls.row(Eigen::Index(j)) = cage.vertices[j].transpose();
  return b;
}

const TriangleMesh& bunnyCage() {
  static const TriangleMesh c =
      sb::mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny_cage.obj");
  return c;
}

void BM_Bind(benchmark::State& state) {
  const int method = int(state.range(0));
  const TriangleMesh mesh = sb::mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj");
  Bound b;
  for (auto _ : state) {
    b = bindWith(method, mesh.vertices, bunnyCage(), {6, 6, 7});
    benchmark::DoNotOptimize(b.embedding.nonZeros());
  }
  const BindStats& st = b.embedding.stats();
  std::int64_t local = 0;
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < b.embedding.meshVertexCount(); ++i) {
    b.embedding.rowWeights(i, row);
    for (const auto& [j, w] : row) local += std::abs(w) < 1e-6;
  }
  const double all = double(b.embedding.meshVertexCount()) * b.embedding.cageVertexCount();
  state.SetLabel(kNames[method]);
  state.counters["controls"] = b.embedding.cageVertexCount();
  state.counters["stored_share"] = double(b.embedding.nonZeros()) / all;
  state.counters["negative_share"] = double(st.negativeCount) / all;
  // Weights |w| < 1e-6: those stored plus those a sparse matrix does not store.
  state.counters["local_share"] = (double(local) + all - double(b.embedding.nonZeros())) / all;
  state.counters["lin_err"] = st.maxLinearError;
}
BENCHMARK(BM_Bind)
    ->DenseRange(0, 3)
    ->ArgName("method")
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// ~100k points on a lattice inside the bunny cage, bound once per method.
const Bound& deformCase(int method) {
  static std::map<int, std::unique_ptr<Bound>> cache;
  auto& slot = cache[method];
  if (!slot) {
    static const std::vector<Vec3> points = [] {
      const TriangleMesh& c = bunnyCage();
      Eigen::AlignedBox3d box;
      for (const Vec3& v : c.vertices) box.extend(v);
      // Spacing for ~100k points in roughly a third of the box's volume.
      const double spacing = std::cbrt(box.volume() / 3.0 / 1e5);
      return interiorLattice(c, spacing);
    }();
    slot = std::make_unique<Bound>(bindWith(method, points, bunnyCage(), {6, 6, 7}));
  }
  return *slot;
}

void BM_Deform(benchmark::State& state) {
  const int method = int(state.range(0));
  sb::setThreadCount(int(state.range(1)));
  const Bound& b = deformCase(method);
  std::mt19937 rng(1);
  std::normal_distribution<float> g(0.0f, 0.05f);
  Eigen::Matrix<float, Eigen::Dynamic, 3> controls = b.controls.cast<float>();
  controls += Eigen::Matrix<float, Eigen::Dynamic, 3>::NullaryExpr(controls.rows(), 3,
                                                                   [&] { return g(rng); });
  sb::PointsRowMajor out;
  for (auto _ : state) {
    b.embedding.deform(controls, out);
    benchmark::DoNotOptimize(out.data());
  }
  sb::setThreadCount(0);
  state.SetLabel(kNames[method]);
  state.counters["points"] = b.embedding.meshVertexCount();
  state.counters["controls"] = b.embedding.cageVertexCount();
  state.counters["weights"] = double(b.embedding.nonZeros());
  // ns per stored weight: the time per frame over the weights it multiplies.
  state.counters["ns_per_weight"] = benchmark::Counter(
      double(b.embedding.nonZeros()) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Deform)
    ->ArgsProduct({{0, 1, 2, 3}, {1, 2}})
    ->ArgNames({"method", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// A bar 4 × 1 × 1 (x along its length) bent a quarter turn about the z axis through
// (0, −R, ·): (x, y, z) → ((R + y) sin(x/R), (R + y) cos(x/R) − R, z), and its Jacobian.
Vec3 bend(const Vec3& p, double R) {
  const double a = p.x() / R;
  return Vec3((R + p.y()) * std::sin(a), (R + p.y()) * std::cos(a) - R, p.z());
}
Eigen::Matrix3d bendJacobian(const Vec3& p, double R) {
  const double a = p.x() / R, k = (R + p.y()) / R;
  Eigen::Matrix3d J;
  J << k * std::cos(a), std::sin(a), 0, -k * std::sin(a), std::cos(a), 0, 0, 0, 1;
  return J;
}

void BM_BentBar(benchmark::State& state) {
  const int method = int(state.range(0));
  const TriangleMesh bar = sb::mesh::testing::makeBox(8, 2, 2, Vec3(4, 1, 1), Vec3(-2, -0.5, -0.5));
  const double R = 4.0 / (M_PI / 2);  // a quarter turn over the bar's length
  const FoldSampling s = foldSamples(bar, 2000);
  FoldProbes probes;
  MatX3d rest;
  for (auto _ : state) {
    probes = makeFoldProbes(s.samples, s.step, [&](const std::vector<Vec3>& p) {
      Bound b = bindWith(method, p, bar, {10, 4, 4});
      rest = b.controls;
      return std::move(b.embedding);
    });
  }
  MatX3d bent = rest;
  for (Eigen::Index j = 0; j < rest.rows(); ++j)
    bent.row(j) = bend(rest.row(j).transpose(), R).transpose();
  MatX3d moved;
  probes.embedding.deformDouble(bent, moved);
  double volume = 0.0, shape = 0.0, anisotropy = 0.0;
  int folded = 0;
  const int n = int(s.samples.size());
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d J;
    for (int k = 0; k < 3; ++k)
      J.col(k) = (moved.row(4 * i + 1 + k) - moved.row(4 * i)).transpose() / probes.step;
    const Eigen::Matrix3d ideal = bendJacobian(s.samples[size_t(i)], R);
    const Eigen::Matrix3d relative = J * ideal.inverse();
    const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(relative).singularValues();
    volume += std::abs(relative.determinant() - 1.0) / n;
    shape += (relative - Eigen::Matrix3d::Identity()).norm() / n;
    anisotropy += (sv[0] / sv[2] - 1.0) / n;
    folded += J.determinant() <= 0.0;
  }
  state.SetLabel(kNames[method]);
  state.counters["samples"] = n;
  state.counters["volume_err"] = volume;
  state.counters["shape_err"] = shape;
  state.counters["anisotropy"] = anisotropy;
  state.counters["folded_share"] = double(folded) / n;
}
BENCHMARK(BM_BentBar)
    ->DenseRange(0, 3)
    ->ArgName("method")
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// A box [0,2]×[0,1.5]×[0,1] with an n×n grid of quads on each side, as an OBJ read by the
// project's reader (so it carries its polygons).
TriangleMesh quadBox(int n) {
  std::map<std::array<int, 3>, int> index;
  std::string obj;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, added] = index.emplace(g, int(index.size()) + 1);
    if (added)
      obj += "v " + std::to_string(2.0 * g[0] / n) + " " + std::to_string(1.5 * g[1] / n) + " " +
             std::to_string(1.0 * g[2] / n) + "\n";
    return it->second;
  };
  // Each side: axis a fixed at 0 or n, the other two (u, v) running; corners counter-clockwise
  // seen from outside.
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const int u = (a + 1) % 3, v = (a + 2) % 3;
          auto at = [&](int di, int dj) {
            std::array<int, 3> g{};
            g[size_t(a)] = side * n;
            g[size_t(u)] = i + di;
            g[size_t(v)] = j + dj;
            return vertex(g);
          };
          const int c[4] = {at(0, 0), at(1, 0), at(1, 1), at(0, 1)};
          obj += side ? "f " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " +
                            std::to_string(c[2]) + " " + std::to_string(c[3]) + "\n"
                      : "f " + std::to_string(c[0]) + " " + std::to_string(c[3]) + " " +
                            std::to_string(c[2]) + " " + std::to_string(c[1]) + "\n";
        }
  return sb::mesh::parseMesh(obj, sb::mesh::MeshFormat::Obj, "quad_box.obj");
}

void BM_QuadCageBind(benchmark::State& state) {
  const bool polygon = state.range(0) != 0;
  const int threads = int(state.range(1));
  TriangleMesh cage = quadBox(6);
  if (!polygon) cage.polygonOf.clear();  // the same triangles, bound by triangle MVC
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.02, 0.98);
  std::vector<Vec3> points(8000);
  for (Vec3& p : points) p = Vec3(2.0 * u(rng), 1.5 * u(rng), u(rng));
  BindOptions o;
  o.storage = WeightStorage::Dense;
  o.threads = threads;
  double seconds = 0.0;
  Embedding e;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    e = bindToCage(points, cage, EmbeddingMethod{}, o);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    benchmark::DoNotOptimize(e.nonZeros());
  }
  state.SetLabel(polygon ? "polygon mvc" : "triangle mvc");
  state.counters["cage_vertices"] = double(cage.vertices.size());
  state.counters["ns_per_point_vertex"] =
      seconds * 1e9 / (double(points.size()) * double(cage.vertices.size()));
  state.counters["lin_err"] = e.stats().maxLinearError;
}
BENCHMARK(BM_QuadCageBind)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"polygon", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
