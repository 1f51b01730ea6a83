#include "sim/world/contact/rolling_resistance.h"

#include <Eigen/Eigenvalues>

namespace sb {

Vec3 rollingCouple(const Mat3& invInertiaA, const Mat3& invInertiaB, const Vec3& relativeSpin,
                   double maxCouple) {
  if (!(maxCouple > 0.0) || relativeSpin == Vec3::Zero()) return Vec3::Zero();
  // K⁺ by eigen-decomposition: K is symmetric positive semi-definite (a flat or a line-shaped
  // body turns freely about some axis: zero there, and no couple is taken along it).
  const Mat3 k = invInertiaA + invInertiaB;
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(k);
  const Vec3 kEigen = eig.eigenvalues();
  const double largest = kEigen.cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) return Vec3::Zero();
  Vec3 coordinates = eig.eigenvectors().transpose() * relativeSpin;
  for (int a = 0; a < 3; ++a)
    coordinates[a] = kEigen[a] > 1e-9 * largest ? coordinates[a] / kEigen[a] : 0.0;
  const Vec3 stop = -(eig.eigenvectors() * coordinates);
  const double size = stop.norm();
  return size <= maxCouple ? stop : stop * (maxCouple / size);
}

}  // namespace sb
