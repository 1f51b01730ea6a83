// Rotational part of a 3×3 deformation: the proper rotation R (det R = +1) that maximises
// tr(Rᵀ A), i.e. the rotation closest to A in the Frobenius norm. Stateless kernels.
#pragma once

#include <Eigen/Geometry>

#include "sim/types.h"

namespace sb {

// Robust closest rotation, warm-started. Runs the iterative extraction of Müller, Bender,
// Chentanez and Macklin (2016) from `warm`, verifies that the result is the global maximiser
// (RᵀA symmetric and tr(S)·I − S positive semi-definite), and falls back to a sign-corrected SVD
// when it is not. Degenerate A (planar, collinear, rank one, zero) still yields a proper rotation;
// where the maximiser is not unique the one nearest the warm start is kept where possible.
// A that is zero or not finite returns `warm` unchanged. Scale-invariant.
Eigen::Quaterniond closestRotation(const Mat3& A, const Eigen::Quaterniond& warm);

// Müller et al. 2016 iterations only (no verification): the fast path, exposed for tests.
Eigen::Quaterniond extractRotationIterative(const Mat3& A, Eigen::Quaterniond q, int maxIterations);

// Sign-corrected SVD: R = U·diag(1, 1, det(UVᵀ))·Vᵀ. The reference solution.
Mat3 closestRotationSvd(const Mat3& A);

// True when R is (to a relative tolerance) a global maximiser of tr(RᵀA) over rotations.
bool isClosestRotation(const Mat3& R, const Mat3& A, double relativeTolerance);

}  // namespace sb
