#include "sim/world/contact/friction_cone.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace sb {

namespace {

Eigen::Vector2f intoDisc(const Eigen::Vector2f& f, float radius) {
  const float len = f.norm();
  if (!(len > radius)) return f;
  return len > 0.0f ? Eigen::Vector2f(f * (radius / len)) : Eigen::Vector2f::Zero();
}

}  // namespace

// f(ν) = (K + νI)⁻¹ K·outside is the minimiser of ½(f − outside)ᵀK(f − outside) + ½ν|f|²; |f(ν)|
// falls monotonically in ν, and ν with |f(ν)| = radius is found by Newton's method on
// 1/radius − 1/|f(ν)|, which from ν = 0 converges monotonically from below (Moré and Sorensen
// 1983, the trust-region subproblem). The result is then put exactly on the circle.
Eigen::Vector2f projectOntoDisc(const Eigen::Matrix2f& K, const Eigen::Vector2f& outside,
                                float radius) {
  if (!(radius > 0.0f)) return Eigen::Vector2f::Zero();
  const Eigen::Vector2f Kf = K * outside;
  float nu = 0;
  Eigen::Vector2f f = outside;
  for (int iteration = 0; iteration < 12; ++iteration) {
    const Eigen::Matrix2f inverse = (K + nu * Eigen::Matrix2f::Identity()).inverse();
    f = inverse * Kf;
    const float len = f.norm();
    if (!(len > 0.0f) || std::abs(len - radius) <= 1e-5f * radius) break;
    // d/dν (1/|f|) = fᵀ(K + νI)⁻¹f / |f|³.
    const float slope = f.dot(inverse * f) / (len * len * len);
    if (!(slope > 0.0f)) break;
    nu = std::max(nu + (1.0f / radius - 1.0f / len) / slope, 0.0f);
  }
  const float len = f.norm();
  return len > 0.0f ? Eigen::Vector2f(f * (radius / len)) : Eigen::Vector2f::Zero();
}

Eigen::Vector2f frictionImpulse(const Eigen::Matrix2f& K, const Eigen::Vector2f& slip,
                                const Eigen::Vector2f& before, float limit) {
  const Eigen::Vector2f start = intoDisc(before, limit);
  // The slip with `start` applied instead of `before`.
  const Eigen::Vector2f s = slip + K * (start - before);
  const Eigen::Vector2f free = start - K.inverse() * s;
  return free.norm() > limit ? projectOntoDisc(K, free, limit) : free;
}

}  // namespace sb
