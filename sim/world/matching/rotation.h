// Rotational part of a 3×3 deformation: the proper rotation R (det R = +1) that maximises
// tr(Rᵀ A), i.e. the rotation closest to A in the Frobenius norm. Stateless kernels.
#pragma once

#include <Eigen/Geometry>

#include "sim/base/linalg.h"
#include "sim/base/types.h"

namespace sb {

// Robust closest rotation, warm-started: Newton's method on the rotation group from `warm` (the
// exact-Hessian form of the iteration of Müller, Bender, Chentanez and Macklin 2016; typically one
// or two steps per simulation step), which also proves the result is the global maximiser
// (RᵀA symmetric and tr(S)·I − S positive definite). When it cannot (saddle, rank-deficient A) the
// result is verified and otherwise replaced by the sign-corrected SVD. Degenerate A (planar,
// collinear, rank one) still yields a proper rotation; A that is zero or not finite returns
// `warm` unchanged. Scale-invariant.
Eigen::Quaterniond closestRotation(const Mat3& A, const Eigen::Quaterniond& warm);

// The reference solution, the sign-corrected SVD: closestRotationSvd (sim/base/linalg.h).

// True when R is (to a relative tolerance) a global maximiser of tr(RᵀA) over rotations.
bool isClosestRotation(const Mat3& R, const Mat3& A, double relativeTolerance);

}  // namespace sb
