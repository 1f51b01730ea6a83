#include "sim/base/linalg.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>

namespace sb {

template <int N>
Eigen::Matrix<double, N, N> symmetricPseudoInverse(const Eigen::Matrix<double, N, N>& M,
                                                   double relTol) {
  using MatN = Eigen::Matrix<double, N, N>;
  Eigen::SelfAdjointEigenSolver<MatN> eig;
  if constexpr (N == 3) {
    eig.computeDirect(0.5 * (M + M.transpose()));  // closed form: much faster for 3×3
  } else {
    eig.compute(0.5 * (M + M.transpose()));
  }
  const auto& lambda = eig.eigenvalues();
  const double lmax = lambda.cwiseAbs().maxCoeff();
  if (!(lmax > 0.0) || !std::isfinite(lmax)) return MatN::Zero();
  Eigen::Matrix<double, N, 1> inv;
  for (int i = 0; i < N; ++i) inv[i] = lambda[i] > relTol * lmax ? 1.0 / lambda[i] : 0.0;
  return eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}
template Eigen::Matrix<double, 3, 3> symmetricPseudoInverse<3>(const Eigen::Matrix<double, 3, 3>&,
                                                               double);
template Eigen::Matrix<double, 9, 9> symmetricPseudoInverse<9>(const Eigen::Matrix<double, 9, 9>&,
                                                               double);

Eigen::Matrix3d closestRotationSvd(const Eigen::Matrix3d& A) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d V = svd.matrixV();
  // Flip the direction of the smallest singular value when UVᵀ would be a reflection.
  const Eigen::Vector3d d(1.0, 1.0, (U * V.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  return U * d.asDiagonal() * V.transpose();
}

}  // namespace sb
