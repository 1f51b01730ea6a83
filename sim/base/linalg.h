// Small dense linear-algebra helpers shared by the fits (shape matching) and the mass
// properties (damping, contacts).
#pragma once

#include <Eigen/Core>

namespace sb {

// Moore–Penrose pseudo-inverse of a symmetric positive semi-definite N×N matrix (N = 3 or 9),
// dropping eigenvalues below relTol·λmax, so singular moment matrices (flat or collinear point
// sets) never divide by zero. A zero or non-finite matrix gives zero.
template <int N>
Eigen::Matrix<double, N, N> symmetricPseudoInverse(const Eigen::Matrix<double, N, N>& M,
                                                   double relTol);

}  // namespace sb
