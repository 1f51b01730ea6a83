// Plasticity: yield threshold, creep, c_max bound, volume, time-step independence.
#include <gtest/gtest.h>

#include "sim/world/matching/plasticity.h"
#include "sim/world/matching/shape_matching.h"
#include "test_util.h"

namespace sb {
namespace {

using test::jitteredGrid;
using test::noGravity;
using test::toMatrix;

PlasticityParams params(double yield, double creep, double max) {
  return {yield, creep, max};
}

TEST(Plasticity, NoChangeBelowYield) {
  Mat3 Sp = Mat3::Identity();
  const Mat3 S = Vec3(1.05, 0.97, 0.98).asDiagonal();  // ‖S − I‖₂ = 0.05
  for (int i = 0; i < 1000; ++i)
    EXPECT_FALSE(updatePlasticDeformation(S, 0.01, params(0.06, 5.0, 0.5), Sp));
  EXPECT_EQ(Sp, Mat3::Identity());
  EXPECT_TRUE(updatePlasticDeformation(S, 0.01, params(0.04, 5.0, 0.5), Sp));
}

TEST(Plasticity, BoundedByCmaxWithUnitDeterminant) {
  Mat3 Sp = Mat3::Identity();
  const Mat3 S = Vec3(1.8, 0.7, 0.9).asDiagonal();
  for (int i = 0; i < 2000; ++i) {
    updatePlasticDeformation(S, 0.01, params(0.01, 10.0, 0.3), Sp);
    ASSERT_LE(spectralNorm(Sp - Mat3::Identity()), 0.3 + 1e-9);
    ASSERT_NEAR(Sp.determinant(), 1.0, 1e-9);
  }
  EXPECT_GT(spectralNorm(Sp - Mat3::Identity()), 0.29);  // it did go to the bound
}

// The creep over a simulated time T must not depend on how T is cut into steps (beyond the
// O(h) of the explicit update). The cluster is held in a stretched pose; each step measures the
// stretch relative to the current plastic rest shape exactly as the World does.
TEST(Plasticity, SameTotalCreepForHalfTheStep) {
  const std::vector<Vec3> rest = jitteredGrid(4, 1.0, Vec3::Zero(), 2);
  const int n = static_cast<int>(rest.size());
  Eigen::Matrix<float, Eigen::Dynamic, 3> r(n, 3), x(n, 3);
  Eigen::VectorXf w = Eigen::VectorXf::Ones(n);
  const Mat3 F = Vec3(1.4, 1.0 / std::sqrt(1.4), 1.0 / std::sqrt(1.4)).asDiagonal();
  for (int i = 0; i < n; ++i) {
    r.row(i) = rest[size_t(i)].transpose().cast<float>();
    x.row(i) = (F * rest[size_t(i)]).transpose().cast<float>();
  }
  std::vector<int> members(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) members[size_t(i)] = i;
  const ClusterRestModel model = buildClusterRest(members.data(), n, r.col(0).data(),
                                                  r.col(1).data(), r.col(2).data(), w.data());
  ParticleColumns cols{{x.col(0).data(), x.col(1).data(), x.col(2).data()},
                       {r.col(0).data(), r.col(1).data(), r.col(2).data()},
                       w.data()};
  auto creep = [&](double h) {
    Mat3 Sp = Mat3::Identity();
    Eigen::Quaterniond rot = Eigen::Quaterniond::Identity();
    const int steps = static_cast<int>(std::lround(1.0 / h));
    for (int s = 0; s < steps; ++s) {
      const ClusterShape shape = deriveClusterShape(model, Sp, false);
      const ClusterMoments m =
          accumulateMoments(cols, nullptr, 0, n, Eigen::Vector3f::Zero(), model.centre, false);
      const ClusterFit fit = fitCluster(m, Eigen::Vector3f::Zero(), model, shape, Sp, rot);
      rot = fit.rotation;
      const Mat3 S = fit.rotation.matrix().transpose() * fit.linear;
      updatePlasticDeformation(0.5 * (S + S.transpose()), h, params(0.02, 1.5, 10.0), Sp);
    }
    return spectralNorm(Sp - Mat3::Identity());
  };
  const double coarse = creep(0.01), fine = creep(0.005);
  EXPECT_GT(coarse, 0.1);  // a real, large permanent change
  EXPECT_NEAR(coarse / fine, 1.0, 0.05);
}

// In the World: a body squashed and held there creeps; released, it keeps part of the squash.
TEST(Plasticity, SustainedDeformationLeavesAPermanentChange) {
  for (Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic}) {
    World world(noGravity(0.01));
    BodyDef def;
    def.positions = jitteredGrid(4, 1.0, Vec3::Zero(), 6);
    def.params.mode = mode;
    def.params.alpha = 0.05;
    def.params.beta = 0.5;
    def.params.damping = 0.2;
    def.params.plasticity = params(0.05, 3.0, 0.4);
    const BodyHandle b = world.addBody(def);
    Eigen::MatrixX3d squashed = toMatrix(def.positions);
    squashed.col(1) *= 0.6;
    squashed.col(0) *= 1.0 / std::sqrt(0.6);
    squashed.col(2) *= 1.0 / std::sqrt(0.6);
    for (int s = 0; s < 50; ++s) {  // hold the squash for 0.5 s
      world.setState(b, squashed, Eigen::MatrixX3d::Zero(squashed.rows(), 3));
      world.step();
    }
    const Mat3 Sp = world.plasticDeformation(b, 0);
    EXPECT_GT(spectralNorm(Sp - Mat3::Identity()), 0.1) << modeName(mode);
    EXPECT_LE(spectralNorm(Sp - Mat3::Identity()), 0.4 + 1e-9);
    EXPECT_NEAR(Sp.determinant(), 1.0, 1e-9);
    for (int s = 0; s < 1500; ++s) world.step();  // released: settles to the new rest shape
    const Eigen::MatrixX3d x = world.positions(b).cast<double>();
    const Eigen::RowVector3d extent = x.colwise().maxCoeff() - x.colwise().minCoeff();
    const Eigen::RowVector3d restExtent =
        toMatrix(def.positions).colwise().maxCoeff() - toMatrix(def.positions).colwise().minCoeff();
    if (mode != Mode::Rigid) {
      // Still flatter than the original (in the rotated frame the flattest extent is smaller).
      EXPECT_LT(extent.minCoeff(), 0.95 * restExtent.minCoeff()) << modeName(mode);
    }
    world.reset();
    EXPECT_EQ(world.plasticDeformation(b, 0), Mat3::Identity());
  }
}

TEST(Plasticity, NeverBelowYieldInTheWorld) {
  World world(noGravity(0.01));
  BodyDef def;
  def.positions = jitteredGrid(3, 1.0, Vec3::Zero(), 6);
  def.params.alpha = 0.2;
  def.params.plasticity = params(0.5, 5.0, 0.4);
  const BodyHandle b = world.addBody(def);
  Eigen::MatrixX3d x = toMatrix(def.positions);
  x.col(1) *= 0.8;  // 20 % squash < 50 % yield
  world.setState(b, x, Eigen::MatrixX3d::Zero(x.rows(), 3));
  for (int s = 0; s < 300; ++s) world.step();
  EXPECT_EQ(world.plasticDeformation(b, 0), Mat3::Identity());
}

}  // namespace
}  // namespace sb
