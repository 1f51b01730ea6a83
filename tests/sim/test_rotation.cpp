// Rotation extraction: always a proper rotation, and the closest one where it is defined.
#include <gtest/gtest.h>

#include <random>

#include "sim/world/matching/rotation.h"
#include "test_util.h"

namespace sb {
namespace {

void expectProperRotation(const Mat3& R) {
  ASSERT_TRUE(R.allFinite());
  EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-9);
}

// tr(RᵀA) of R must reach the maximum over rotations (the SVD reference attains it).
void expectClosest(const Mat3& R, const Mat3& A) {
  const Mat3 ref = closestRotationSvd(A);
  EXPECT_GE((R.transpose() * A).trace(), (ref.transpose() * A).trace() - 1e-8 * (1 + A.norm()));
}

TEST(Rotation, MatchesSvdOnRandomDeformations) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.3, 2.0);
  for (int k = 0; k < 500; ++k) {
    const Mat3 R0 = test::randomRotation(rng);
    const Mat3 Q = test::randomRotation(rng);
    const Mat3 S = Q * test::drawVector<Vec3>([&] { return u(rng); }).asDiagonal() * Q.transpose();
    const Mat3 A = R0 * S;
    const Eigen::Quaterniond warm(test::randomRotation(rng));
    const Mat3 R = closestRotation(A, warm).matrix();
    expectProperRotation(R);
    EXPECT_LT((R - R0).norm(), 1e-7) << k;
  }
}

TEST(Rotation, ScaleInvariant) {
  std::mt19937 rng(2);
  const Mat3 R0 = test::randomRotation(rng);
  const Mat3 A = R0 * Vec3(1.0, 2.0, 0.5).asDiagonal();
  for (double s : {1e-8, 1e-4, 1.0, 1e4, 1e8}) {
    const Mat3 R = closestRotation(s * A, Eigen::Quaterniond::Identity()).matrix();
    EXPECT_LT((R - R0).norm(), 1e-7) << s;
  }
}

TEST(Rotation, InvertedGivesProperRotationNotReflection) {
  std::mt19937 rng(3);
  for (int k = 0; k < 200; ++k) {
    const Mat3 R0 = test::randomRotation(rng);
    Mat3 A = R0 * Vec3(1.0, 1.5, 0.7).asDiagonal();
    A.col(k % 3) *= -1.0;  // det A < 0
    ASSERT_LT(A.determinant(), 0.0);
    for (const Eigen::Quaterniond& warm : {Eigen::Quaterniond::Identity(), Eigen::Quaterniond(R0),
                                           Eigen::Quaterniond(test::randomRotation(rng))}) {
      const Mat3 R = closestRotation(A, warm).matrix();
      expectProperRotation(R);
      expectClosest(R, A);
    }
  }
}

// A warm start sitting exactly on a saddle of tr(RᵀA) (here the identity for a half-turn) would
// stall the iteration; the verification must catch it.
TEST(Rotation, EscapesSaddleWarmStart) {
  const Mat3 A = Vec3(-1.0, -2.0, 3.0).asDiagonal();
  const Mat3 R = closestRotation(A, Eigen::Quaterniond::Identity()).matrix();
  expectProperRotation(R);
  expectClosest(R, A);
  EXPECT_LT((R - Mat3(Vec3(-1, -1, 1).asDiagonal())).norm(), 1e-9);
}

TEST(Rotation, DegenerateInputs) {
  std::mt19937 rng(4);
  std::normal_distribution<double> g;
  for (int k = 0; k < 200; ++k) {
    auto draw = [&] { return g(rng); };
    const Vec3 a = test::drawVector<Vec3>(draw), b = test::drawVector<Vec3>(draw),
               c = test::drawVector<Vec3>(draw), d = test::drawVector<Vec3>(draw);
    const Mat3 planar = a * b.transpose() + c * d.transpose();  // rank 2
    const Mat3 collinear = a * b.transpose();                   // rank 1
    const Eigen::Quaterniond warm(test::randomRotation(rng));
    for (const Mat3& A : {planar, collinear, Mat3(-planar), Mat3(-collinear)}) {
      const Mat3 R = closestRotation(A, warm).matrix();
      expectProperRotation(R);
      expectClosest(R, A);
    }
    // Rank 2 has a unique closest rotation: it must be found.
    const Mat3 Rp = closestRotation(planar, warm).matrix();
    EXPECT_LT((Rp - closestRotationSvd(planar)).norm(), 1e-6) << k;
  }
  // Zero (a single particle, or all particles at one point) keeps the warm start.
  const Eigen::Quaterniond warm(test::randomRotation(rng));
  EXPECT_TRUE(closestRotation(Mat3::Zero(), warm).isApprox(warm));
  // Not finite: the warm start, never NaN.
  Mat3 nan = Mat3::Identity();
  nan(1, 2) = std::numeric_limits<double>::quiet_NaN();
  expectProperRotation(closestRotation(nan, warm).matrix());
}

TEST(Rotation, SvdReferenceIsProper) {
  std::mt19937 rng(5);
  for (int k = 0; k < 100; ++k) {
    Mat3 A = Mat3::Random();
    if (k % 2) A.col(0) *= -1;
    expectProperRotation(closestRotationSvd(A));
  }
}

TEST(Rotation, VerifierRejectsWrongAnswers) {
  const Mat3 A = Vec3(1.0, 2.0, 3.0).asDiagonal();
  EXPECT_TRUE(isClosestRotation(Mat3::Identity(), A, 1e-9));
  EXPECT_FALSE(isClosestRotation(Mat3(Vec3(-1, -1, 1).asDiagonal()), A, 1e-9));  // saddle
  EXPECT_FALSE(
      isClosestRotation(Eigen::AngleAxisd(0.1, Vec3::UnitZ()).toRotationMatrix(), A, 1e-9));
}

}  // namespace
}  // namespace sb
