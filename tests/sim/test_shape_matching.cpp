// Shape matching: the goals of each mode reproduce the deformations they claim to, computed
// independently here from the closed forms.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "sim/world/matching/cluster_layout.h"
#include "sim/world/matching/cluster_rest.h"
#include "sim/world/matching/goal_projection.h"
#include "sim/world/matching/shape_matching.h"
#include "sim/world/substep_material.h"
#include "test_util.h"
#include "tests/draws.h"

namespace sb {
namespace {

using test::jitteredGrid;
using test::noGravity;
using test::toMatrix;

// Goals of the body for positions x (the Goals phase of one step, read back), at the reference
// sub-step, where β applies as given (substep_material.h).
Eigen::MatrixX3d goalsFor(const BodyDef& def, const Eigen::MatrixX3d& x) {
  World world(noGravity(kReferenceSubstep));
  const BodyHandle b = world.addBody(def);
  world.setState(b, x, Eigen::MatrixX3d::Zero(x.rows(), 3));
  world.step();
  return world.goals(b);
}

Eigen::MatrixX3d applyAffine(const std::vector<Vec3>& rest, const Mat3& A, const Vec3& t) {
  Eigen::MatrixX3d x(static_cast<int>(rest.size()), 3);
  for (size_t i = 0; i < rest.size(); ++i) x.row(int(i)) = (A * rest[i] + t).transpose();
  return x;
}

BodyDef gridBody(Mode mode, bool clustered) {
  BodyDef def;
  def.positions = jitteredGrid(5, 1.0, Vec3(0.3, -0.2, 0.1), 17);
  def.params.mode = mode;
  def.params.beta = 1.0;
  def.params.preserveVolume = false;
  if (clustered) {
    def.clusters.kind = ClusterDef::Kind::Grid;
    def.clusters.cellSize = 0.5;
    def.clusters.overlap = 0.3;
  }
  return def;
}

// Goals at β = 1 for positions x whose full fit is `fit`: the World applies β as kBetaMax·β, so
// the goal is kBetaMax of the way from the rigid goal to the fit.
Eigen::MatrixX3d betaOneGoals(const BodyDef& def, const Eigen::MatrixX3d& x,
                              const Eigen::MatrixX3d& fit) {
  BodyDef rigid = def;
  rigid.params.mode = Mode::Rigid;
  return kBetaMax * fit + (1.0 - kBetaMax) * goalsFor(rigid, x);
}

double relError(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return (a - b).rowwise().norm().maxCoeff() /
         (b.colwise().maxCoeff() - b.colwise().minCoeff()).norm();
}

TEST(ShapeMatching, LinearWithBetaZeroEqualsRigid) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  for (bool clustered : {false, true}) {
    BodyDef rigid = gridBody(Mode::Rigid, clustered);
    BodyDef linear = gridBody(Mode::Linear, clustered);
    linear.params.beta = 0.0;
    Eigen::MatrixX3d x = toMatrix(rigid.positions);
    for (int i = 0; i < x.rows(); ++i)
      x.row(i) += test::drawVector<Eigen::RowVector3d>([&] { return u(rng); });
    EXPECT_LT(relError(goalsFor(linear, x), goalsFor(rigid, x)), 1e-6) << clustered;
  }
}

TEST(ShapeMatching, LinearReproducesAnyAffineMap) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (bool clustered : {false, true})
    for (int k = 0; k < 5; ++k) {
      Mat3 A = Mat3::Identity();
      for (int i = 0; i < 9; ++i) A(i / 3, i % 3) += u(rng);
      if (A.determinant() < 0.1) continue;
      const Vec3 t = test::drawVector<Vec3>([&] { return u(rng); });
      const BodyDef def = gridBody(Mode::Linear, clustered);
      const Eigen::MatrixX3d x = applyAffine(def.positions, A, t);
      EXPECT_LT(relError(goalsFor(def, x), betaOneGoals(def, x, x)), 2e-6)
          << "clustered " << clustered << " k " << k;
    }
}

TEST(ShapeMatching, VolumePreservingLinearNormalisesDeterminant) {
  std::mt19937 rng(3);
  BodyDef def = gridBody(Mode::Linear, false);
  def.params.preserveVolume = true;
  // det A = 1: reproduced exactly.
  const Mat3 shear = (Mat3() << 1, 0.4, 0, 0, 1, 0.2, 0, 0, 1).finished();
  const Mat3 R = test::randomRotation(rng);
  Eigen::MatrixX3d x = applyAffine(def.positions, R * shear, Vec3(1, 2, 3));
  EXPECT_LT(relError(goalsFor(def, x), betaOneGoals(def, x, x)), 2e-6);
  // det A = 1.5: goals follow A / ∛1.5 about the centre of mass; det A = 8: the restoring scale
  // is capped at 1.25 per step (a crushed or blown-up cluster recovers over several steps).
  for (const auto& [det, divisor] : {std::pair<double, double>{1.5, std::cbrt(1.5)}, {8.0, 1.25}}) {
    const Mat3 A = std::cbrt(det) * R * shear;
    x = applyAffine(def.positions, A, Vec3::Zero());
    Eigen::MatrixX3d expected = applyAffine(def.positions, A / divisor, Vec3::Zero());
    const Eigen::RowVector3d shift =
        x.colwise().mean() - expected.colwise().mean();  // equal masses
    expected.rowwise() += shift;
    EXPECT_LT(relError(goalsFor(def, x), betaOneGoals(def, x, expected)), 2e-6) << det;
  }
}

TEST(ShapeMatching, QuadraticReproducesAnyQuadraticMap) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (bool clustered : {false, true})
    for (int k = 0; k < 4; ++k) {
      Mat3 A = Mat3::Identity();
      for (int i = 0; i < 9; ++i) A(i / 3, i % 3) += 0.5 * u(rng);
      Eigen::Matrix<double, 3, 6> Q;
      for (int i = 0; i < 18; ++i) Q(i / 6, i % 6) = u(rng);
      const Vec3 t = test::drawVector<Vec3>([&] { return u(rng); });
      const BodyDef def = gridBody(Mode::Quadratic, clustered);
      Eigen::MatrixX3d x(static_cast<int>(def.positions.size()), 3);
      for (size_t i = 0; i < def.positions.size(); ++i)
        x.row(int(i)) =
            (A * def.positions[i] + Q * monomials<double>(def.positions[i]) + t).transpose();
      EXPECT_LT(relError(goalsFor(def, x), betaOneGoals(def, x, x)), 2e-5)
          << "clustered " << clustered << " k " << k;
      // Linear mode cannot: the bend is really there.
      EXPECT_GT(relError(goalsFor(gridBody(Mode::Linear, clustered), x), x), 1e-3);
    }
}

TEST(ShapeMatching, FlatAndCollinearBodiesGiveFiniteRigidGoals) {
  std::mt19937 rng(5);
  std::vector<Vec3> flat, line;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) flat.push_back(Vec3(0.2 * i, 0.2 * j, 0.0));
  for (int i = 0; i < 8; ++i) line.push_back(Vec3(0.1 * i, 0.0, 0.0));
  for (const auto& shape : {flat, line})
    for (Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic}) {
      BodyDef def;
      def.positions = shape;
      def.params.mode = mode;
      def.params.beta = 1.0;
      const Mat3 R = test::randomRotation(rng);
      const Eigen::MatrixX3d x = applyAffine(shape, R, Vec3(1, 0, 0));
      const Eigen::MatrixX3d g = goalsFor(def, x);
      ASSERT_TRUE(g.allFinite());
      EXPECT_LT(relError(g, x), 1e-5) << modeName(mode);  // a rotated rest shape is its own goal
    }
}

// The reach: x + α(g − x) when that is within `reach` of g (the same bits as without a reach),
// else the point at distance `reach` from g on the segment from g towards x + α(g − x).
TEST(GoalProjection, ReachKeepsParticlesWithinReachOfTheirGoals) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const int n = 200;
  std::vector<float> x(n), y(n), z(n);
  for (int i = 0; i < n; ++i) x[size_t(i)] = u(rng), y[size_t(i)] = u(rng), z[size_t(i)] = u(rng);
  const std::vector<float> x0 = x, y0 = y, z0 = z;
  const float g[3] = {0.1f, -0.2f, 0.3f}, alpha = 0.25f, reach = 0.5f;
  int inside = 0, capped = 0;
  for (int i = 0; i < n; ++i) {
    float fx[1] = {x0[size_t(i)]}, fy[1] = {y0[size_t(i)]}, fz[1] = {z0[size_t(i)]};
    projectParticle(fx, fy, fz, 0, g[0], g[1], g[2], alpha);  // without a reach
    EXPECT_EQ(projectParticleWithin(x.data(), y.data(), z.data(), i, g[0], g[1], g[2], alpha,
                                    reach * reach),
              0);
    const Eigen::Vector3d free(fx[0], fy[0], fz[0]), got(x[size_t(i)], y[size_t(i)], z[size_t(i)]);
    const Eigen::Vector3d goal(g[0], g[1], g[2]);
    if ((free - goal).norm() <= reach) {
      ++inside;
      EXPECT_EQ(x[size_t(i)], fx[0]);
      EXPECT_EQ(y[size_t(i)], fy[0]);
      EXPECT_EQ(z[size_t(i)], fz[0]);
    } else {
      ++capped;
      EXPECT_NEAR((got - goal).norm(), reach, 1e-6);
      EXPECT_NEAR((got - goal).normalized().dot((free - goal).normalized()), 1.0, 1e-6);
    }
  }
  EXPECT_GT(inside, 20);
  EXPECT_GT(capped, 20);
  // A non-finite position is still reported.
  x[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(projectParticleWithin(x.data(), y.data(), z.data(), 0, g[0], g[1], g[2], alpha, 0.25f),
            0);
}

TEST(ClusterRest, MonomialMapTransformsQuadraticTerms) {
  std::mt19937 rng(6);
  std::normal_distribution<double> g;
  for (int k = 0; k < 20; ++k) {
    Mat3 S;
    for (int i = 0; i < 9; ++i) S(i / 3, i % 3) = g(rng);
    const Vec3 q = test::drawVector<Vec3>([&] { return g(rng); });
    EXPECT_LT((monomialMap(S) * monomials<double>(q) - monomials<double>(Vec3(S * q))).norm(),
              1e-12 * (1 + (S * q).squaredNorm()));
  }
}

TEST(ClusterLayout, GridCoversEveryParticleAndOverlapSharesThem) {
  const std::vector<Vec3> rest = jitteredGrid(9, 2.0, Vec3::Zero(), 3);
  ClusterDef def;
  def.kind = ClusterDef::Kind::Grid;
  def.cellSize = 0.5;
  def.overlap = 0.5;  // one whole cell on every side: interior particles are in 27 clusters
  std::vector<int> count(rest.size(), 0);
  for (const auto& c : buildClusterMembers(def, rest))
    for (int p : c) ++count[size_t(p)];
  EXPECT_EQ(*std::max_element(count.begin(), count.end()), 27);
  EXPECT_GE(*std::min_element(count.begin(), count.end()), 1);
}

// Disjoint cells (or explicit clusters that share no particle) would let the body come apart:
// such layouts are refused, naming the field.
TEST(ClusterLayout, RejectsLayoutsThatDoNotHoldTheBodyTogether) {
  const std::vector<Vec3> rest = jitteredGrid(9, 2.0, Vec3::Zero(), 3);  // spacing 0.25 m
  ClusterDef def;
  def.kind = ClusterDef::Kind::Grid;
  def.cellSize = 0.5;
  for (double overlap : {0.0, 0.01}) {
    def.overlap = overlap;
    try {
      buildClusterMembers(def, rest);
      ADD_FAILURE() << "accepted overlap " << overlap;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("clusters.overlap"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("come apart"), std::string::npos) << e.what();
    }
  }
  def.overlap = 0.15;  // more than half the spacing: neighbouring cells share particles
  EXPECT_NO_THROW(buildClusterMembers(def, rest));
  ClusterDef split;
  split.kind = ClusterDef::Kind::Explicit;
  split.clusters = {{0, 1, 2, 3}, {3, 4, 5, 6}, {7, 8, 9, 10}};
  for (int p = 11; p < int(rest.size()); ++p) split.clusters[2].push_back(p);
  EXPECT_THROW(buildClusterMembers(split, rest), std::invalid_argument);
  split.clusters[1].push_back(7);  // now the three are joined
  EXPECT_NO_THROW(buildClusterMembers(split, rest));
}

TEST(ClusterLayout, RejectsBadDefinitions) {
  const std::vector<Vec3> rest = jitteredGrid(3, 1.0, Vec3::Zero(), 3);
  ClusterDef def;
  def.kind = ClusterDef::Kind::Grid;
  def.cellSize = -1;
  EXPECT_THROW(buildClusterMembers(def, rest), std::invalid_argument);
  def.cellSize = 1e-9;
  EXPECT_THROW(buildClusterMembers(def, rest), std::invalid_argument);
  def.kind = ClusterDef::Kind::Explicit;
  def.clusters = {{0, 1, 2}, {3, 99}};
  try {
    buildClusterMembers(def, rest);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("clusters.clusters[1]"), std::string::npos) << e.what();
  }
  def.clusters = {{0, 1, 2}};
  EXPECT_THROW(buildClusterMembers(def, rest), std::invalid_argument);  // particles left out
}

}  // namespace
}  // namespace sb
