#include "sim/world/matching/cluster_rest.h"

#include "sim/base/linalg.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace sb {

namespace {
// Index pairs of the monomials, in order.
constexpr int kPairA[6] = {0, 1, 2, 0, 1, 2};
constexpr int kPairB[6] = {0, 1, 2, 1, 2, 0};
}  // namespace

Mat6 monomialMap(const Mat3& S) {
  // (Sq)_a (Sq)_b = Σ_cd S_ac S_bd q_c q_d; the q_c q_d and q_d q_c terms share a monomial.
  Mat6 M = Mat6::Zero();
  for (int row = 0; row < 6; ++row) {
    const int a = kPairA[row], b = kPairB[row];
    for (int col = 0; col < 6; ++col) {
      const int c = kPairA[col], d = kPairB[col];
      M(row, col) = (c == d) ? S(a, c) * S(b, c) : S(a, c) * S(b, d) + S(a, d) * S(b, c);
    }
  }
  return M;
}

ClusterRestModel buildClusterRest(const int* members, int count, const float* rx, const float* ry,
                                  const float* rz, const float* w) {
  ClusterRestModel c;
  Vec3 weighted = Vec3::Zero();
  for (int k = 0; k < count; ++k) {
    const int i = members[k];
    c.mass += w[i];
    weighted += double(w[i]) * Vec3(rx[i], ry[i], rz[i]);
  }
  c.centre = (weighted / c.mass).cast<float>();
  double radius2 = 0;
  for (int k = 0; k < count; ++k) {
    const int i = members[k];
    // Evaluate q⁰ exactly as the float kernels do, so Σ w q⁰ matches them bit for bit.
    const Eigen::Vector3f q0f(rx[i] - c.centre.x(), ry[i] - c.centre.y(), rz[i] - c.centre.z());
    const Eigen::Matrix<float, 6, 1> m0f = monomials<float>(q0f);
    Vec9 y;
    y << q0f.cast<double>(), m0f.cast<double>();
    c.sumWq0 += double(w[i]) * y.head<3>();
    c.sumWmono0 += double(w[i]) * y.tail<6>();
    c.moments0 += double(w[i]) * y * y.transpose();
    radius2 += double(w[i]) * y.head<3>().squaredNorm();
  }
  const double rms = std::sqrt(radius2 / c.mass);
  c.scale = rms > 0.0 ? rms : 1.0;
  return c;
}

ClusterShape deriveClusterShape(const ClusterRestModel& rest, const Mat3& plastic, bool quadratic) {
  ClusterShape s;
  s.mono = monomialMap(plastic);
  s.monoMean = s.mono * rest.sumWmono0 / rest.mass;
  const Mat3 Aqq = plastic * rest.moments0.topLeftCorner<3, 3>() * plastic.transpose();
  // Float rest positions carry ~1e-7 relative noise: directions weaker than that are flat.
  s.AqqInv = symmetricPseudoInverse<3>(Aqq, 1e-6);
  s.flat = (s.AqqInv * Aqq).trace() < 2.5;  // the rank the pseudo-inverse kept: 3, 2, 1 or 0
  if (!quadratic) return s;
  s.hasQuadratic = true;
  const double invS = 1.0 / rest.scale;
  // B maps y⁰ = [q⁰, mono(q⁰)] to [q/s, mono(q)/s²].
  Mat9 B = Mat9::Zero();
  B.topLeftCorner<3, 3>() = plastic * invS;
  B.bottomRightCorner<6, 6>() = s.mono * (invS * invS);
  const Vec9 sumY = (Vec9() << rest.sumWq0, rest.sumWmono0).finished();
  const Vec9 sumBy = B * sumY;
  Vec9 shift = Vec9::Zero();  // subtract the mean of the normalised monomials
  shift.tail<6>() = sumBy.tail<6>() / rest.mass;
  // Σ w (B y − shift)(B y − shift)ᵀ, expanded.
  const Mat9 second = B * rest.moments0 * B.transpose() - sumBy * shift.transpose() -
                      shift * sumBy.transpose() + rest.mass * shift * shift.transpose();
  s.AqqTildeInv = symmetricPseudoInverse<9>(second, 1e-7);
  return s;
}

}  // namespace sb
