// Multiquadric RBF deformation (sim/cage/rbf.h): interpolation of the handles, partition of unity
// and affine reproduction, the weights against an independent solve of the interpolation
// problem, thread invariance, the kind kept through a weight file, and refused input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include <Eigen/Dense>

#include "sim/cage/rbf.h"
#include "sim/mesh/mesh_io.h"
#include "tests/cage/cage_test_data.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::cage {
namespace {

using MatX3d = Eigen::Matrix<double, Eigen::Dynamic, 3>;
using namespace test_data;

std::vector<Vec3> randomPoints(int n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Vec3> p(static_cast<std::size_t>(n));
  for (Vec3& x : p) x = Vec3(u(rng), u(rng), u(rng));
  return p;
}

TEST(Rbf, InterpolatesTheHandles) {
  const auto& handles = bunnyCage().vertices;
  const Embedding e = bindRbf(handles, handles);
  EXPECT_EQ(e.kind(), EmbeddingKind::Rbf);
  ASSERT_EQ(e.meshVertexCount(), int(handles.size()));
  ASSERT_EQ(e.cageVertexCount(), int(handles.size()));
  std::vector<std::pair<int, double>> row;
  double worst = 0.0;
  for (int i = 0; i < e.meshVertexCount(); ++i) {
    e.rowWeights(i, row);
    for (const auto& [j, w] : row) worst = std::max(worst, std::abs(w - (i == j ? 1.0 : 0.0)));
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Rbf, SumsToOneAndReproducesAffineMaps) {
  const auto& handles = bunnyCage().vertices;
  const auto& points = bunny().vertices;
  for (double shape : {0.0, 1.0, 3.0}) {
    RbfOptions o;
    o.shape = shape;
    const Embedding e = bindRbf(points, handles, o);
    EXPECT_LT(e.stats().maxSumError, 1e-10) << "shape " << shape;
    EXPECT_LT(e.stats().maxLinearError, 1e-10) << "shape " << shape;
    const Eigen::Matrix3d A =
        (Eigen::Matrix3d() << 1.2, 0.3, -0.1, -0.2, 0.9, 0.4, 0.15, -0.25, 1.1).finished();
    const Vec3 t(0.5, -1.0, 2.0);
    MatX3d moved = toMatrix(handles);
    for (Eigen::Index j = 0; j < moved.rows(); ++j)
      moved.row(j) = (A * moved.row(j).transpose() + t).transpose();
    MatX3d out;
    e.deformDouble(moved, out);
    double err = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i)
      err = std::max(err, (out.row(Eigen::Index(i)).transpose() - (A * points[i] + t)).norm());
    EXPECT_LT(err, 1e-9) << "shape " << shape;
  }
}

// The interpolant computed directly — λ and the affine part solved from the textbook system in
// world coordinates (no centring or scaling) by a different factorisation — and evaluated at
// points, for a displacement that is not affine: W · q must give the same values.
TEST(Rbf, WeightsEqualAnIndependentSolveOfTheInterpolation) {
  const std::vector<Vec3> handles = {{0, 0, 0}, {1, 0, 0},       {0, 1, 0},      {0, 0, 1},
                                     {1, 1, 1}, {0.3, 0.4, 0.2}, {0.8, 0.1, 0.6}};
  const int n = int(handles.size());
  const std::vector<Vec3> points = randomPoints(50, -0.2, 1.2, 5);
  const MatX3d moved = toMatrix(handles) + toMatrix(randomPoints(n, -0.3, 0.3, 6));
  for (double shape : {0.0, 0.7, 2.0}) {
    // s = shape × mean nearest-handle distance, computed here by brute force.
    double mean = 0.0;
    for (int i = 0; i < n; ++i) {
      double best = 1e300;
      for (int j = 0; j < n; ++j)
        if (j != i) best = std::min(best, (handles[size_t(i)] - handles[size_t(j)]).norm());
      mean += best / n;
    }
    const double s = shape * mean;
    auto phi = [&](const Vec3& a, const Vec3& b) { return std::hypot((a - b).norm(), s); };
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 4, n + 4);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n + 4, 3);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) M(i, j) = phi(handles[size_t(i)], handles[size_t(j)]);
      M(i, n) = M(n, i) = 1.0;
      for (int d = 0; d < 3; ++d) M(i, n + 1 + d) = M(n + 1 + d, i) = handles[size_t(i)][d];
      rhs.row(i) = moved.row(i);
    }
    const Eigen::MatrixXd coef = M.colPivHouseholderQr().solve(rhs);
    RbfOptions o;
    o.shape = shape;
    const Embedding e = bindRbf(points, handles, o);
    MatX3d out;
    e.deformDouble(moved, out);
    for (std::size_t p = 0; p < points.size(); ++p) {
      Eigen::RowVector3d f = coef.row(n) + points[p].transpose() * coef.bottomRows(3);
      for (int i = 0; i < n; ++i) f += phi(points[p], handles[size_t(i)]) * coef.row(i);
      EXPECT_LT((out.row(Eigen::Index(p)) - f).norm(), 1e-10)
          << "point " << p << " shape " << shape;
    }
  }
}

TEST(Rbf, ResultDoesNotDependOnTheThreadCount) {
  const auto& handles = bunnyCage().vertices;
  const auto& points = bunny().vertices;  // 2,048: several blocks of rows
  ASSERT_GT(points.size(), 1024u);
  RbfOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const Embedding a = bindRbf(points, handles, one), b = bindRbf(points, handles, two);
  std::vector<std::pair<int, double>> ra, rb;
  for (int i = 0; i < a.meshVertexCount(); ++i) {
    a.rowWeights(i, ra);
    b.rowWeights(i, rb);
    ASSERT_EQ(ra, rb) << "row " << i;
  }
}

class RbfFile : public test_support::TempDirTest {};

TEST_F(RbfFile, AWeightFileKeepsTheKind) {
  const Embedding e = bindRbf(randomPoints(20, 0.0, 1.0, 3), bunnyCage().vertices);
  e.save(path("rbf.sbw"), {1, 2});
  std::array<std::uint64_t, 2> key{};
  const Embedding back = Embedding::load(path("rbf.sbw"), &key);
  EXPECT_EQ(back.kind(), EmbeddingKind::Rbf);
  EXPECT_EQ(key, (std::array<std::uint64_t, 2>{1, 2}));
  std::vector<std::pair<int, double>> ra, rb;
  for (int i = 0; i < e.meshVertexCount(); ++i) {
    e.rowWeights(i, ra);
    back.rowWeights(i, rb);
    ASSERT_EQ(ra, rb);
  }
}

void expectRefusal(const std::vector<Vec3>& points, const std::vector<Vec3>& handles,
                   const RbfOptions& o, const std::string& words) {
  try {
    (void)bindRbf(points, handles, o);
    ADD_FAILURE() << "accepted; expected: " << words;
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(Rbf, RefusesBadInputNamingTheProblem) {
  const std::vector<Vec3> tet = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<Vec3> pts = {{0.2, 0.2, 0.2}};
  const RbfOptions o;
  expectRefusal(pts, {tet[0], tet[1], tet[2]}, o, "at least 4 handles");
  expectRefusal(pts, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.2, 0}}, o,
                "lie in one plane");
  expectRefusal(pts, {tet[0], tet[1], tet[2], tet[3], tet[1]}, o,
                "handles 1 and 4 are at the same place");
  expectRefusal(pts, {tet[0], tet[1], Vec3(0, std::nan(""), 0), tet[3]}, o,
                "handle 2 is not finite");
  expectRefusal({pts[0], Vec3(INFINITY, 0, 0)}, tet, o, "point 1 is not finite");
  RbfOptions wide;
  wide.shape = 11.0;
  expectRefusal(pts, tet, wide, "shape must be in [0, 10]");
  wide.shape = std::nan("");
  expectRefusal(pts, tet, wide, "shape must be in [0, 10]");
  expectRefusal(pts, std::vector<Vec3>(kMaxRbfHandles + 1, Vec3::Zero()), o, "more than the");
}

}  // namespace
}  // namespace sb::cage
