// Small dense linear-algebra helpers shared by the fits (shape matching, the render meshes of
// cages that move as a whole) and the mass properties (damping, contacts).
#pragma once

#include <Eigen/Core>

namespace sb {

// Moore–Penrose pseudo-inverse of a symmetric positive semi-definite N×N matrix (N = 3 or 9),
// dropping eigenvalues below relTol·λmax, so singular moment matrices (flat or collinear point
// sets) never divide by zero. A zero or non-finite matrix gives zero.
template <int N>
Eigen::Matrix<double, N, N> symmetricPseudoInverse(const Eigen::Matrix<double, N, N>& M,
                                                   double relTol);

// The proper rotation closest to A in the Frobenius norm (maximising tr(RᵀA)), by the
// sign-corrected SVD: R = U·diag(1, 1, det(UVᵀ))·Vᵀ (the reference solution of
// sim/world/matching/rotation.h; the similarity fit of sim/cage/rigid_follow.h).
Eigen::Matrix3d closestRotationSvd(const Eigen::Matrix3d& A);

}  // namespace sb
