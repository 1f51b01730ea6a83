#include "sim/base/linalg.h"

#include <Eigen/Eigenvalues>
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

}  // namespace sb
