// symmetricPseudoInverse against its defining properties.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "sim/base/linalg.h"

namespace sb {
namespace {

TEST(Linalg, PseudoInverseOfAnInvertibleMatrixIsItsInverse) {
  Eigen::Matrix3d A;
  A << 4, 1, 0.5, 1, 3, 0.2, 0.5, 0.2, 2;
  EXPECT_LT((symmetricPseudoInverse<3>(A, 1e-9) * A - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  Eigen::Matrix<double, 9, 9> B = Eigen::Matrix<double, 9, 9>::Random();
  B = B * B.transpose() + Eigen::Matrix<double, 9, 9>::Identity();
  EXPECT_LT(
      (symmetricPseudoInverse<9>(B, 1e-12) * B - Eigen::Matrix<double, 9, 9>::Identity()).norm(),
      1e-9);
}

TEST(Linalg, PseudoInverseOfASingularMatrixSatisfiesThePenroseConditions) {
  // Rank 2 (a flat point set's second moments).
  const Eigen::Vector3d u(1, 2, 0), v(0, 1, 1);
  const Eigen::Matrix3d A = u * u.transpose() + 2 * v * v.transpose();
  const Eigen::Matrix3d P = symmetricPseudoInverse<3>(A, 1e-9);
  EXPECT_LT((A * P * A - A).norm(), 1e-12);
  EXPECT_LT((P * A * P - P).norm(), 1e-12);
  EXPECT_LT((A * P - (A * P).transpose()).norm(), 1e-12);
  EXPECT_EQ(symmetricPseudoInverse<3>(Eigen::Matrix3d::Zero(), 1e-9), Eigen::Matrix3d::Zero());
  const Eigen::Matrix3d flat = Eigen::Vector3d(1.0, 2.0, 0.0).asDiagonal();
  EXPECT_LT((symmetricPseudoInverse<3>(flat, 1e-9) -
             Eigen::Matrix3d(Eigen::Vector3d(1.0, 0.5, 0.0).asDiagonal()))
                .norm(),
            1e-12);
}

}  // namespace
}  // namespace sb
