#include "sim/world/matching/rotation.h"

#include <cmath>

namespace sb {

bool isClosestRotation(const Mat3& R, const Mat3& A, double relativeTolerance) {
  const double scale = A.norm();
  if (!(scale > 0.0)) return true;  // every rotation maximises tr(Rᵀ·0)
  const Mat3 S = R.transpose() * A / scale;
  const double tol = relativeTolerance;
  // Stationary point: S symmetric.
  if ((S - S.transpose()).norm() > tol) return false;
  // Global maximum: the sum of any two eigenvalues of sym(S) is ≥ 0, i.e. M = tr(S)·I − S is
  // positive semi-definite. Checked by an LDLᵀ of M + tol·I (all pivots must be positive).
  const Mat3 Ssym = 0.5 * (S + S.transpose());
  Mat3 M = Ssym.trace() * Mat3::Identity() - Ssym + tol * Mat3::Identity();
  for (int k = 0; k < 3; ++k) {
    const double pivot = M(k, k);
    if (!(pivot > 0.0)) return false;
    for (int i = k + 1; i < 3; ++i) {
      const double f = M(i, k) / pivot;
      for (int j = k + 1; j < 3; ++j) M(i, j) -= f * M(k, j);
    }
  }
  return true;
}

namespace {

// Applies the rotation vector ω (axis·angle, world frame) to q. Small steps, the common case
// near convergence, use the second-order update and skip sin/cos.
Eigen::Quaterniond rotateBy(const Vec3& omega, const Eigen::Quaterniond& q) {
  const double angle = omega.norm();
  Eigen::Quaterniond dq;
  if (angle < 1e-3) {
    dq = Eigen::Quaterniond(1.0 - angle * angle / 8.0, 0.5 * omega.x(), 0.5 * omega.y(),
                            0.5 * omega.z());
  } else {
    dq = Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle));
  }
  Eigen::Quaterniond out = dq * q;
  out.normalize();
  return out;
}

// Solves H·x = b for symmetric H by an LDLᵀ factorisation; false when H is not positive
// definite (pivots above `margin`), i.e. when R is not in the basin of the maximum.
bool solvePositiveDefinite(const Mat3& H, const Vec3& b, double margin, Vec3* x) {
  const double d0 = H(0, 0);
  if (!(d0 > margin)) return false;
  const double l10 = H(1, 0) / d0, l20 = H(2, 0) / d0;
  const double d1 = H(1, 1) - l10 * H(1, 0);
  if (!(d1 > margin)) return false;
  const double l21 = (H(2, 1) - l20 * H(1, 0)) / d1;
  const double d2 = H(2, 2) - l20 * H(2, 0) - l21 * l21 * d1;
  if (!(d2 > margin)) return false;
  const double y0 = b[0], y1 = b[1] - l10 * y0, y2 = b[2] - l20 * y0 - l21 * y1;
  const double x2 = y2 / d2, x1 = y1 / d1 - l21 * x2, x0 = y0 / d0 - l10 * x1 - l20 * x2;
  *x = Vec3(x0, x1, x2);
  return true;
}

}  // namespace

Eigen::Quaterniond closestRotation(const Mat3& A, const Eigen::Quaterniond& warm) {
  const double scale = A.norm();
  if (!(scale > 0.0) || !std::isfinite(scale)) return warm;
  const Mat3 An = A / scale;
  // Newton's method on f(R) = tr(RᵀA) over rotations, from the warm start. With B = A·Rᵀ the
  // gradient (world frame) is τ = axial(B − Bᵀ) and the Hessian is H = tr(B_s)·I − B_s. Müller
  // et al. (2016) take H ≈ tr(B)·I, which converges linearly (slowly for thin clusters); the
  // exact H converges quadratically, and H being positive definite at the end is exactly the
  // condition that R is the global maximum rather than a saddle.
  Eigen::Quaterniond q = warm;
  for (int it = 0; it < 12; ++it) {
    const Mat3 R = q.matrix();
    const Mat3 B = An * R.transpose();
    const Vec3 tau(B(2, 1) - B(1, 2), B(0, 2) - B(2, 0), B(1, 0) - B(0, 1));
    const Mat3 Bs = 0.5 * (B + B.transpose());
    const Mat3 H = Bs.trace() * Mat3::Identity() - Bs;
    Vec3 omega;
    if (solvePositiveDefinite(H, tau, 1e-9, &omega)) {
      // H > 0 proves this is the basin of the maximum. Newton converges quadratically, so after
      // a step of length below 1e-4 the error is ~1e-8 (below float precision of the positions
      // it acts on): take the step and stop. From a warm start this is usually the first step.
      if (omega.squaredNorm() < 1e-8) return rotateBy(omega, q);
      // Newton steps are only trusted locally; longer ones are clipped.
      const double len = omega.norm();
      if (len > 0.5) omega *= 0.5 / len;
    } else {
      // Saddle region: a gradient step (Müller's) moves toward the maximum's basin.
      omega = tau / (std::abs(B.trace()) + 1e-9);
      if (!(omega.squaredNorm() > 1e-24)) break;  // stuck exactly on a saddle
    }
    q = rotateBy(omega, q);
  }
  if (isClosestRotation(q.matrix(), An, 1e-9)) return q;
  // Not converged (rank-deficient A has a non-unique maximum with singular H) or stuck on a
  // saddle: the sign-corrected SVD answer.
  q = Eigen::Quaterniond(closestRotationSvd(An));
  q.normalize();
  return q;
}

}  // namespace sb
