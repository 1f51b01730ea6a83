// Bind and deform: affine reproduction (double and float paths), pruning rule and its reported
// error (recomputed independently), storage, save/load, cache reuse and invalidation, progress,
// determinism across thread counts, normals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <Eigen/Dense>

#include "sim/base/parallel.h"
#include "sim/cage/embedding.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "sim/mesh/normals.h"
#include "tests/draws.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::cage {
using namespace sb::mesh;  // meshes, mesh files, surfaces
namespace {

namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;
using MatX3d = Eigen::Matrix<double, Eigen::Dynamic, 3>;

MatX3d toMatrix(const std::vector<Vec3>& v) {
  MatX3d m(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return m;
}

Eigen::MatrixXd denseOf(const Embedding& e) {
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(e.meshVertexCount(), e.cageVertexCount());
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < e.meshVertexCount(); ++i) {
    e.rowWeights(i, row);
    for (const auto& [j, w] : row) W(i, j) = w;
  }
  return W;
}

struct RealCase {
  TriangleMesh mesh, cage;
};
const RealCase& bunny() {
  static const RealCase c{readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj"),
                          readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny_cage.obj")};
  return c;
}
const RealCase& suzanne() {
  static const RealCase c{readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/suzanne.obj"),
                          readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/suzanne_cage.obj")};
  return c;
}

// A moved cage under x -> A x + t reproduces A x + t at every mesh vertex.
void checkAffine(const RealCase& rc, const Embedding& e, double tolDouble, double tolFloat) {
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 1.2, 0.3, -0.1, -0.2, 0.9, 0.4, 0.15, -0.25, 1.1).finished();
  const Vec3 t(0.5, -1.0, 2.0);
  MatX3d moved = toMatrix(rc.cage.vertices);
  for (Eigen::Index j = 0; j < moved.rows(); ++j)
    moved.row(j) = (A * moved.row(j).transpose() + t).transpose();
  const double L = testing::diagonal(rc.cage) * A.norm();
  MatX3d out;
  e.deformDouble(moved, out);
  PointsRowMajor outF;
  const Eigen::Matrix<float, Eigen::Dynamic, 3> movedF = moved.cast<float>();
  e.deform(movedF, outF);
  double errD = 0.0, errF = 0.0;
  for (std::size_t i = 0; i < rc.mesh.vertices.size(); ++i) {
    const Vec3 expect = A * rc.mesh.vertices[i] + t;
    errD = std::max(errD, (out.row(static_cast<Eigen::Index>(i)).transpose() - expect).norm() / L);
    errF = std::max(
        errF,
        (outF.row(static_cast<Eigen::Index>(i)).transpose().cast<double>() - expect).norm() / L);
  }
  EXPECT_LT(errD, tolDouble);
  EXPECT_LT(errF, tolFloat);
}

TEST(Bind, DenseRealMeshesReproduceAffineMaps) {
  for (const RealCase* rc : {&bunny(), &suzanne()}) {
    BindOptions o;
    o.storage = WeightStorage::Dense;
    const Embedding e = bindMeanValue(rc->mesh.vertices, rc->cage, o);
    EXPECT_FALSE(e.isSparse());
    EXPECT_EQ(e.meshVertexCount(), static_cast<int>(rc->mesh.vertices.size()));
    EXPECT_EQ(e.cageVertexCount(), static_cast<int>(rc->cage.vertices.size()));
    EXPECT_LT(e.stats().maxSumError, 1e-10);
    EXPECT_LT(e.stats().maxLinearError, 1e-10);
    EXPECT_GT(e.stats().negativeCount, 0);  // non-convex cages: negative weights kept
    EXPECT_LT(e.stats().minWeight, 0.0);
    checkAffine(*rc, e, 1e-10, 1e-5);
    // The reported statistics agree with the stored matrix.
    const Eigen::MatrixXd W = denseOf(e);
    EXPECT_DOUBLE_EQ(W.minCoeff(), e.stats().minWeight);
    EXPECT_DOUBLE_EQ(W.maxCoeff(), e.stats().maxWeight);
    EXPECT_EQ((W.array() < 0).count(), e.stats().negativeCount);
  }
}

TEST(Bind, SparsePruningKeepsPartitionOfUnityAndLinearPrecision) {
  const RealCase& rc = bunny();
  BindOptions dense;
  dense.storage = WeightStorage::Dense;
  const Embedding ed = bindMeanValue(rc.mesh.vertices, rc.cage, dense);
  const Eigen::MatrixXd Wd = denseOf(ed);
  const MatX3d V = toMatrix(rc.cage.vertices);
  const double L = testing::diagonal(rc.cage);
  for (double thr : {1e-3, 1e-2, 1e-1}) {
    BindOptions o;
    o.storage = WeightStorage::Sparse;
    o.pruneThreshold = thr;
    const Embedding es = bindMeanValue(rc.mesh.vertices, rc.cage, o);
    ASSERT_TRUE(es.isSparse());
    const Eigen::MatrixXd Ws = denseOf(es);
    EXPECT_LT(es.nonZeros(), Wd.size());
    EXPECT_EQ(es.nonZeros(), es.stats().nonZeros);
    // Rows still sum to one and reproduce x (the correction restores both).
    EXPECT_LT((Ws.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
    const MatX3d X = toMatrix(rc.mesh.vertices);
    EXPECT_LT(((Ws * V - X).rowwise().norm() / L).maxCoeff(), 1e-12);
    checkAffine(rc, es, 1e-10, 1e-5);
    // Dropped weights are the smallest ones and carry at most thr · Σ|w| of the row.
    for (Eigen::Index i = 0; i < Wd.rows(); i += 7) {
      double droppedMass = 0.0, maxDropped = 0.0, minKept = 1e300;
      for (Eigen::Index j = 0; j < Wd.cols(); ++j) {
        if (Ws(i, j) == 0.0) {
          droppedMass += std::abs(Wd(i, j));
          maxDropped = std::max(maxDropped, std::abs(Wd(i, j)));
        } else {
          minKept = std::min(minKept, std::abs(Wd(i, j)));
        }
      }
      EXPECT_LE(droppedMass, thr * Wd.row(i).cwiseAbs().sum() * (1 + 1e-12));
      EXPECT_LE(maxDropped, minKept);
    }
    // The reported figures, recomputed independently from the dense weights.
    const double restErr = (((Ws - Wd) * V).rowwise().norm() / L).maxCoeff();
    EXPECT_NEAR(es.stats().pruningError, restErr, 1e-13);
    const double l1 = (Ws - Wd).cwiseAbs().rowwise().sum().maxCoeff();
    EXPECT_NEAR(es.stats().maxPrunedL1, l1, 1e-9 * std::max(1.0, l1));
    // Error bound for a non-affine pose: |ΔW c| ≤ L1 · max|c_j − affine(v_j)|.
    MatX3d bent = V;
    for (Eigen::Index j = 0; j < bent.rows(); ++j) bent(j, 0) += 0.2 * bent(j, 1) * bent(j, 1);
    const double nonAffine = 0.2 * V.col(1).cwiseAbs2().maxCoeff();
    const double poseErr = ((Ws - Wd) * bent).rowwise().norm().maxCoeff();
    EXPECT_LE(poseErr, l1 * nonAffine + 1e-12);
  }
}

TEST(Bind, AutoStorageRule) {
  // Small cage: dense.
  const RealCase& rc = suzanne();
  const Embedding a = bindMeanValue(rc.mesh.vertices, rc.cage);
  EXPECT_FALSE(a.isSparse());
  // A cage above the dense limit: sparse when pruning pays, with all invariants.
  const TriangleMesh box = testing::makeBox(12, 12, 12);  // 866 vertices
  std::vector<Vec3> pts;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(0.05, 0.95);
  for (int i = 0; i < 40; ++i) pts.push_back(test::drawVector<Vec3>([&] { return U(rng); }));
  BindOptions o;
  o.pruneThreshold = 0.1;
  const Embedding b = bindMeanValue(pts, box, o);
  EXPECT_TRUE(b.isSparse());
  EXPECT_LT(b.stats().maxSumError, 1e-12);
  EXPECT_LT(b.stats().maxLinearError, 1e-12);
  EXPECT_LT(2 * b.nonZeros(), static_cast<std::int64_t>(pts.size()) * 866);
  // When pruning would keep more than half of the entries: dense, unpruned.
  o.pruneThreshold = 1e-4;
  const Embedding c = bindMeanValue(pts, box, o);
  EXPECT_FALSE(c.isSparse());
  EXPECT_EQ(c.stats().maxPrunedL1, 0.0);
}

TEST(Bind, InvalidCageBindsNothing) {
  TriangleMesh cage = testing::makeBox(1, 1, 1);
  std::swap(cage.triangles[3][0], cage.triangles[3][1]);
  EXPECT_THROW(bindMeanValue({Vec3(0.5, 0.5, 0.5)}, cage), SurfaceError);
}

TEST(Bind, DeterministicAcrossThreadCounts) {
  const RealCase& rc = suzanne();
  BindOptions o1, o2;
  o1.threads = 1;
  o2.threads = 2;
  const Eigen::MatrixXd W1 = denseOf(bindMeanValue(rc.mesh.vertices, rc.cage, o1));
  const Eigen::MatrixXd W2 = denseOf(bindMeanValue(rc.mesh.vertices, rc.cage, o2));
  EXPECT_EQ((W1 - W2).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Bind, ProgressIsReported) {
  const RealCase& rc = bunny();
  BindOptions o;
  std::vector<std::pair<std::size_t, std::size_t>> calls;
  o.progress = [&](std::size_t done, std::size_t total) { calls.emplace_back(done, total); };
  bindMeanValue(rc.mesh.vertices, rc.cage, o);
  ASSERT_GE(calls.size(), 2u);
  for (std::size_t k = 1; k < calls.size(); ++k) EXPECT_GT(calls[k].first, calls[k - 1].first);
  EXPECT_EQ(calls.back().first, rc.mesh.vertices.size());
  EXPECT_EQ(calls.back().second, rc.mesh.vertices.size());
}

TEST(Bind, PointsOnTheCageAreCounted) {
  const TriangleMesh cube = testing::makeBox(1, 1, 1);
  const std::vector<Vec3> pts = {{0.5, 0.5, 1.0}, {0, 0, 0}, {0.5, 0.5, 0.5}, {0.25, 0.0, 0.5}};
  const Embedding e = bindMeanValue(pts, cube);
  EXPECT_EQ(e.stats().onCagePoints, 3);
  EXPECT_LT(e.stats().maxLinearError, 1e-14);
}

TEST(Bind, DeformChecksTheCageSize) {
  const TriangleMesh cube = testing::makeBox(1, 1, 1);
  const Embedding e = bindMeanValue({Vec3(0.5, 0.5, 0.5)}, cube);
  Eigen::Matrix<float, Eigen::Dynamic, 3> wrong(7, 3);
  wrong.setZero();
  PointsRowMajor out;
  EXPECT_THROW(e.deform(wrong, out), std::invalid_argument);
}

TEST(Bind, DeformWorksOnStridedViews) {
  // The World stores particles structure-of-arrays: the cage rows can be a strided block.
  const TriangleMesh cube = testing::makeBox(1, 1, 1);
  const std::vector<Vec3> pts = {{0.2, 0.3, 0.4}, {0.9, 0.1, 0.5}};
  const Embedding e = bindMeanValue(pts, cube);
  Eigen::Matrix<float, Eigen::Dynamic, 3> big(20, 3);
  big.setConstant(1e6f);
  for (int j = 0; j < 8; ++j)
    big.row(5 + j) = (cube.vertices[j] * 2.0 + Vec3(1, 2, 3)).cast<float>().transpose();
  PointsRowMajor out;
  e.deform(big.middleRows(5, 8), out);
  for (int i = 0; i < 2; ++i)
    EXPECT_LT((out.row(i).transpose().cast<double>() - (pts[i] * 2.0 + Vec3(1, 2, 3))).norm(),
              1e-5);
}

// Several cages at once (the bodies of a scene that share one binding): each result equals a
// deform of its own, bit for bit, for a dense and a sparse W, on one thread and on two; each
// also matches the double product.
TEST(Bind, DeformManyEqualsOneAtATime) {
  const RealCase& rc = bunny();
  const int m = static_cast<int>(rc.cage.vertices.size());
  for (const WeightStorage storage : {WeightStorage::Dense, WeightStorage::Sparse}) {
    BindOptions o;
    o.storage = storage;
    const Embedding e = bindMeanValue(rc.mesh.vertices, rc.cage, o);
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0.0, 0.05);
    std::vector<Eigen::Matrix<float, Eigen::Dynamic, 3>> cages(5);
    for (auto& c : cages) {  // the cage, each vertex displaced: non-affine poses
      c.resize(m, 3);
      for (int j = 0; j < m; ++j)
        c.row(j) =
            (rc.cage.vertices[size_t(j)] + sb::test::drawVector<Vec3>([&] { return g(rng); }))
                .cast<float>()
                .transpose();
    }
    for (const int threads : {1, 2}) {
      sb::setThreadCount(threads);
      std::vector<ConstPointsRef> in;
      std::vector<PointsRowMajor> many(cages.size());
      std::vector<PointsRowMajor*> outs;
      for (size_t k = 0; k < cages.size(); ++k) {
        in.emplace_back(cages[k]);
        outs.push_back(&many[k]);
      }
      e.deformMany(in, outs);
      for (size_t k = 0; k < cages.size(); ++k) {
        PointsRowMajor one;
        e.deform(cages[k], one);
        EXPECT_TRUE(one == many[k]) << "cage " << k << ", " << threads << " threads";
        MatX3d exact;
        e.deformDouble(cages[k].cast<double>(), exact);
        EXPECT_LT((many[k].cast<double>() - exact).cwiseAbs().maxCoeff(), 1e-5) << "cage " << k;
      }
    }
    sb::setThreadCount(0);
  }
  // Mismatched lists and a wrong cage size are refused before anything is written.
  const Embedding e = bindMeanValue(rc.mesh.vertices, rc.cage);
  Eigen::Matrix<float, Eigen::Dynamic, 3> wrong =
      Eigen::Matrix<float, Eigen::Dynamic, 3>::Zero(7, 3);
  PointsRowMajor out;
  EXPECT_THROW(e.deformMany({ConstPointsRef(wrong)}, {}), std::invalid_argument);
  EXPECT_THROW(e.deformMany({ConstPointsRef(wrong)}, {&out}), std::invalid_argument);
  EXPECT_EQ(out.rows(), 0);
}

// ---------------------------------------------------------------------------------------------
// Save / load / cache

class CacheTest : public sb::test_support::TempDirTest {
 protected:
  std::vector<fs::path> files() const {
    std::vector<fs::path> f;
    for (const auto& e : fs::directory_iterator(dir_)) f.push_back(e.path());
    return f;
  }
};

TEST_F(CacheTest, SaveLoadRoundTrip) {
  const RealCase& rc = suzanne();
  for (auto storage : {WeightStorage::Dense, WeightStorage::Sparse}) {
    BindOptions o;
    o.storage = storage;
    const Embedding e = bindMeanValue(rc.mesh.vertices, rc.cage, o);
    const std::string p = (dir_ / "w.sbw").string();
    e.save(p, {1, 2});
    std::array<std::uint64_t, 2> key{};
    const Embedding l = Embedding::load(p, &key);
    EXPECT_EQ(key, (std::array<std::uint64_t, 2>{1, 2}));
    EXPECT_EQ(l.isSparse(), e.isSparse());
    EXPECT_EQ(l.nonZeros(), e.nonZeros());
    EXPECT_EQ((denseOf(l) - denseOf(e)).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(l.stats().pruningError, e.stats().pruningError);
  }
}

TEST_F(CacheTest, ReuseRebindOnChangeAndCorruption) {
  const TriangleMesh cage = testing::makeBox(1, 1, 1);
  std::vector<Vec3> pts;
  for (int i = 0; i < 30; ++i) pts.emplace_back(0.1 + 0.025 * i, 0.3 + 0.01 * i, 0.7 - 0.015 * i);
  BindOptions o;
  o.cacheDir = dir_.string();
  std::vector<std::string> warnings;
  o.warning = [&](const std::string& w) { warnings.push_back(w); };

  const Embedding first = bindMeanValue(pts, cage, o);
  EXPECT_FALSE(first.stats().fromCache);
  ASSERT_EQ(files().size(), 1u);  // no temp file left behind
  const std::string cacheFile = bindCachePath(dir_.string(), bindCacheKey(pts, cage, o));
  EXPECT_TRUE(fs::exists(cacheFile));

  const Embedding second = bindMeanValue(pts, cage, o);
  EXPECT_TRUE(second.stats().fromCache);
  EXPECT_EQ((denseOf(second) - denseOf(first)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(warnings.empty());

  // Same vertices, different triangles (each face split along the other diagonal): rebind.
  TriangleMesh other = cage;
  for (std::size_t t = 0; t + 1 < other.triangles.size(); t += 2) {
    // The two triangles of a quad: (oa, s1, s2) and one containing s2, s1, ob. Use diagonal oa-ob.
    auto a = other.triangles[t];
    const auto b = other.triangles[t + 1];
    auto inB = [&](int v) { return v == b[0] || v == b[1] || v == b[2]; };
    while (inB(a[0])) std::rotate(a.begin(), a.begin() + 1, a.end());
    int ob = -1;
    for (int v : b)
      if (v != a[1] && v != a[2]) ob = v;
    other.triangles[t] = {a[0], a[1], ob};
    other.triangles[t + 1] = {a[0], ob, a[2]};
  }
  ASSERT_NO_THROW(validateClosedSurface(other, "other"));
  EXPECT_NE(bindCacheKey(pts, other, o), bindCacheKey(pts, cage, o));
  const Embedding third = bindMeanValue(pts, other, o);
  EXPECT_FALSE(third.stats().fromCache);
  EXPECT_GT((denseOf(third) - denseOf(first)).cwiseAbs().maxCoeff(),
            1e-6);  // really different weights
  EXPECT_EQ(files().size(), 2u);

  // Different points or options: different keys.
  std::vector<Vec3> moved = pts;
  moved[3].x() += 1e-12;
  EXPECT_NE(bindCacheKey(moved, cage, o), bindCacheKey(pts, cage, o));
  BindOptions o2 = o;
  o2.pruneThreshold = 0.02;
  EXPECT_NE(bindCacheKey(pts, cage, o2), bindCacheKey(pts, cage, o));
  o2 = o;
  o2.threads = 2;  // results do not depend on the thread count
  EXPECT_EQ(bindCacheKey(pts, cage, o2), bindCacheKey(pts, cage, o));

  // Corrupt the cache file: flip bytes in the middle -> warning, rebind, same weights.
  {
    std::fstream f(cacheFile, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(cacheFile) / 2));
    f.write("\x13\x37\x13\x37", 4);
  }
  const Embedding fourth = bindMeanValue(pts, cage, o);
  EXPECT_FALSE(fourth.stats().fromCache);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("checksum"), std::string::npos) << warnings[0];
  EXPECT_EQ((denseOf(fourth) - denseOf(first)).cwiseAbs().maxCoeff(), 0.0);
  // The rebind rewrote a good file.
  EXPECT_TRUE(bindMeanValue(pts, cage, o).stats().fromCache);

  // Truncated and garbage files.
  fs::resize_file(cacheFile, 100);
  EXPECT_FALSE(bindMeanValue(pts, cage, o).stats().fromCache);
  { std::ofstream(cacheFile, std::ios::trunc) << "garbage"; }
  EXPECT_FALSE(bindMeanValue(pts, cage, o).stats().fromCache);
  EXPECT_EQ(warnings.size(), 3u);
  EXPECT_TRUE(bindMeanValue(pts, cage, o).stats().fromCache);
}

TEST_F(CacheTest, UnwritableCacheDirectoryOnlyWarns) {
  const TriangleMesh cage = testing::makeBox(1, 1, 1);
  BindOptions o;
  // A missing directory is created...
  o.cacheDir = (dir_ / "new" / "dir").string();
  EXPECT_FALSE(bindMeanValue({Vec3(0.5, 0.5, 0.5)}, cage, o).stats().fromCache);
  EXPECT_TRUE(bindMeanValue({Vec3(0.5, 0.5, 0.5)}, cage, o).stats().fromCache);
  // ...but one below a regular file cannot be: warn and carry on.
  { std::ofstream(dir_ / "file") << "x"; }
  o.cacheDir = (dir_ / "file" / "sub").string();
  int warnings = 0;
  o.warning = [&](const std::string&) { ++warnings; };
  const Embedding e = bindMeanValue({Vec3(0.5, 0.5, 0.5)}, cage, o);
  EXPECT_EQ(e.meshVertexCount(), 1);
  EXPECT_EQ(warnings, 1);
}

// ---------------------------------------------------------------------------------------------
// Normals

TEST(Normals, AreaWeightedUnitNormals) {
  const TriangleMesh sphere = testing::makeIcosphere(3);
  PointsRowMajor pos(static_cast<Eigen::Index>(sphere.vertices.size()), 3), n;
  for (std::size_t i = 0; i < sphere.vertices.size(); ++i)
    pos.row(static_cast<Eigen::Index>(i)) = sphere.vertices[i].cast<float>().transpose();
  computeVertexNormals(sphere.triangles, pos, n);
  ASSERT_EQ(n.rows(), pos.rows());
  for (Eigen::Index i = 0; i < n.rows(); ++i) {
    EXPECT_NEAR(n.row(i).norm(), 1.0f, 1e-6f);
    EXPECT_GT(n.row(i).dot(pos.row(i).normalized()), 0.999f);
  }
  // Area weighting: a vertex shared by a big and a small triangle at right angles.
  PointsRowMajor p2(4, 3), n2;
  p2 << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.1f;
  computeVertexNormals({{0, 1, 2}, {0, 3, 1}}, p2, n2);
  // big triangle: +z with 2·area 1; small one: +y with 2·area 0.1; sum (0, 0.1, 1) normalised
  const Eigen::Vector3f expect = Eigen::Vector3f(0, 0.1f, 1).normalized();
  EXPECT_LT((n2.row(0).transpose() - expect).norm(), 1e-6f);
  EXPECT_EQ(n2.row(2).norm(), 1.0f);
}

}  // namespace
}  // namespace sb::cage
