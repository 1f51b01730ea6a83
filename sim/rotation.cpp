#include "sim/rotation.h"

#include <Eigen/SVD>
#include <cmath>

namespace sb {

Eigen::Quaterniond extractRotationIterative(const Mat3& A, Eigen::Quaterniond q,
                                            int maxIterations) {
  for (int it = 0; it < maxIterations; ++it) {
    const Mat3 R = q.matrix();
    // ω is a damped Newton step toward alignment of R's columns with A's columns.
    const Vec3 torque =
        R.col(0).cross(A.col(0)) + R.col(1).cross(A.col(1)) + R.col(2).cross(A.col(2));
    const double alignment =
        std::abs(R.col(0).dot(A.col(0)) + R.col(1).dot(A.col(1)) + R.col(2).dot(A.col(2)));
    // A is normalised by the caller (‖A‖_F = 1), so this floor is relative, not absolute.
    const Vec3 omega = torque / (alignment + 1e-9);
    const double angle = omega.norm();
    if (!(angle > 1e-13)) break;  // converged (or NaN: stop, the caller verifies)
    q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle)) * q;
    q.normalize();
  }
  return q;
}

Mat3 closestRotationSvd(const Mat3& A) {
  Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3 U = svd.matrixU();
  const Mat3 V = svd.matrixV();
  // Flip the direction of the smallest singular value when UVᵀ would be a reflection.
  Vec3 d(1.0, 1.0, (U * V.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  return U * d.asDiagonal() * V.transpose();
}

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

Eigen::Quaterniond closestRotation(const Mat3& A, const Eigen::Quaterniond& warm) {
  const double scale = A.norm();
  if (!(scale > 0.0) || !std::isfinite(scale)) return warm;
  const Mat3 An = A / scale;
  Eigen::Quaterniond q = extractRotationIterative(An, warm, 64);
  if (isClosestRotation(q.matrix(), An, 1e-9)) return q;
  // The iteration stalled at a saddle (e.g. an inverted configuration seen from a warm start
  // on the other side) or converged too slowly: take the SVD answer.
  q = Eigen::Quaterniond(closestRotationSvd(An));
  q.normalize();
  return q;
}

}  // namespace sb
