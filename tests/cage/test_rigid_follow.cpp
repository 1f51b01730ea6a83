// RigidFollow (sim/cage/rigid_follow.h): a render mesh whose cage moved as a whole follows it
// without the weights, within the stated bound of the weights' own result.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "cage_test_data.h"
#include "sim/cage/embedding.h"
#include "sim/cage/rigid_follow.h"

namespace sb::cage {
namespace {

struct Bound {
  Embedding embedding;
  PointsRowMajor cage, mesh;  // rest, float
  RigidFollow follow;
};

PointsRowMajor asFloat(const std::vector<Vec3>& v) {
  PointsRowMajor p(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) p.row(Eigen::Index(i)) = v[i].transpose().cast<float>();
  return p;
}

const Bound& bunnyBound() {
  static const Bound b = [] {
    Bound r;
    BindOptions o;
    o.storage = WeightStorage::Dense;
    r.embedding = bindMeanValue(test_data::bunny().vertices, test_data::bunnyCage(), o);
    r.cage = asFloat(test_data::bunnyCage().vertices);
    r.mesh = asFloat(test_data::bunny().vertices);
    r.follow = *RigidFollow::make(r.embedding, r.cage, r.mesh);
    return r;
  }();
  return b;
}

double diagonalOf(const PointsRowMajor& p) {
  return double((p.colwise().maxCoeff() - p.colwise().minCoeff()).norm());
}

PointsRowMajor moved(const PointsRowMajor& p, double s, const Mat3& R, const Vec3& t) {
  PointsRowMajor out(p.rows(), 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    out.row(i) = (s * R * p.row(i).transpose().cast<double>() + t).transpose().cast<float>();
  return out;
}

// The embedding's float weights reproduce affine maps (MVC: partition of unity and linear
// precision), so make() accepts it, and its measured parts are what the weights give.
TEST(RigidFollow, MeasuresHowTheWeightsReproduceTheirRest) {
  const Bound& b = bunnyBound();
  const double diagonal = diagonalOf(b.cage);
  EXPECT_LT(b.follow.restError(), 1e-5 * diagonal);
  EXPECT_LT(b.follow.unityError(), 1e-5);
  // L = max Σ|w| ≥ 1, more where MVC has negative weights; recomputed from the weights here.
  double lebesgue = 0;
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < b.embedding.meshVertexCount(); ++i) {
    b.embedding.rowWeights(i, row);
    double sum = 0;
    for (const auto& w : row) sum += std::abs(w.second);
    lebesgue = std::max(lebesgue, sum);
  }
  EXPECT_DOUBLE_EQ(b.follow.lebesgue(), lebesgue);
  EXPECT_GE(b.follow.lebesgue(), 1.0);
  // An embedding of other rows, or a cage of other vertices, has no follow.
  EXPECT_FALSE(RigidFollow::make(b.embedding, b.cage, b.mesh.topRows(10)));
  EXPECT_FALSE(RigidFollow::make(b.embedding, b.cage.topRows(10), b.mesh));
  // A rest mesh the weights do not reproduce (moved off its cage) has none either.
  PointsRowMajor off = b.mesh;
  off.col(0).array() += float(0.01 * diagonal);
  EXPECT_FALSE(RigidFollow::make(b.embedding, b.cage, off));
}

// Cages moved by random similarities (any rotation, scale 0.05–3, translation up to 3 m) are
// followed, and the result is within the stated bound of W·x (float, as deform computes it) and
// closer still to W·x in double.
TEST(RigidFollow, CageMovedAsAWholeIsFollowedWithinTheBound) {
  const Bound& b = bunnyBound();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  const float eps = std::numeric_limits<float>::epsilon();
  for (int trial = 0; trial < 60; ++trial) {
    const Mat3 R = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized())
                       .toRotationMatrix();
    const double s = 0.05 * std::pow(60.0, 0.5 * (u(rng) + 1.0));
    const Vec3 t(3 * u(rng), 3 * u(rng), 3 * u(rng));
    const PointsRowMajor cage = moved(b.cage, s, R, t);
    PointsRowMajor followed, weighted;
    ASSERT_TRUE(b.follow.follow(cage, followed)) << "trial " << trial << ", scale " << s;
    b.embedding.deform(cage, weighted);
    ASSERT_EQ(followed.rows(), weighted.rows());
    const double diagonal = diagonalOf(cage);
    const double largest = double(cage.cwiseAbs().maxCoeff());
    // The bound, plus the float rounding of both products (a few ulp of the coordinates each,
    // W·x summing ~160 products of at most L·|x|).
    const double rounding = 16.0 * eps * b.follow.lebesgue() * largest;
    const double difference = double((followed - weighted).rowwise().norm().maxCoeff());
    EXPECT_LE(difference, RigidFollow::kTolerance * diagonal + rounding) << "trial " << trial;
    Eigen::Matrix<double, Eigen::Dynamic, 3> exact;
    b.embedding.deformDouble(cage.cast<double>(), exact);
    const double fromExact = (followed.cast<double>() - exact).rowwise().norm().maxCoeff();
    EXPECT_LE(fromExact, RigidFollow::kTolerance * diagonal + rounding) << "trial " << trial;
  }
}

// A cage that is not a similarity of its rest takes the weights: bent by 1e-4 of its size, a
// mirror image, one vertex moved past the bound (but not one moved well within it), NaN.
TEST(RigidFollow, CageNotMovedAsAWholeIsNotFollowed) {
  const Bound& b = bunnyBound();
  const double diagonal = diagonalOf(b.cage);
  PointsRowMajor out(2, 3);
  out.setConstant(7.0f);
  const PointsRowMajor untouched = out;
  PointsRowMajor bent = b.cage;
  for (Eigen::Index i = 0; i < bent.rows(); ++i)
    bent(i, 1) += float(1e-4 * diagonal * std::sin(3.0 * bent(i, 0) / diagonal));
  EXPECT_FALSE(b.follow.follow(bent, out));
  PointsRowMajor stretched = b.cage;
  stretched.col(0) *= 1.001f;
  EXPECT_FALSE(b.follow.follow(stretched, out));
  PointsRowMajor mirrored = b.cage;
  mirrored.col(2) *= -1.0f;
  EXPECT_FALSE(b.follow.follow(mirrored, out));
  EXPECT_EQ(out, untouched);
  // One vertex off by p: the fit leaves it about p away (the others move by p/n), so the bound
  // is about L·p: twice the tolerance is turned down, half of it followed.
  const double limit = RigidFollow::kTolerance * diagonal / b.follow.lebesgue();
  PointsRowMajor nudged = b.cage;
  nudged(5, 0) += float(2.0 * limit);
  EXPECT_FALSE(b.follow.follow(nudged, out));
  nudged = b.cage;
  nudged(5, 0) += float(0.5 * limit);
  EXPECT_TRUE(b.follow.follow(nudged, out));
  PointsRowMajor broken = b.cage;
  broken(3, 1) = std::numeric_limits<float>::quiet_NaN();
  PointsRowMajor kept = out;
  EXPECT_FALSE(b.follow.follow(broken, out));
  EXPECT_EQ(out, kept);
  EXPECT_FALSE(b.follow.follow(b.cage.topRows(20), out));
}

}  // namespace
}  // namespace sb::cage
