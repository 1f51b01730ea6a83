#include "sim/world/matching/shape_matching.h"

#include <algorithm>
#include <cmath>

#include "sim/world/matching/rotation.h"

namespace sb {

namespace {

constexpr int kLanes = 8;    // independent float partial sums per accumulator (SIMD width)
constexpr int kBlock = 512;  // members summed in float before the block total goes to double

// Inlined into each target variant of accumulateMoments (below).
template <bool kGather, bool kQuadratic>
[[gnu::always_inline]] inline ClusterMoments accumulate(const ParticleColumns& p,
                                                        const int* members, int begin, int end,
                                                        const Eigen::Vector3f& ref,
                                                        const Eigen::Vector3f& rc) {
  constexpr int kCount = kQuadratic ? 30 : 12;
  double total[kCount] = {};
  const float refx = ref.x(), refy = ref.y(), refz = ref.z();
  const float rcx = rc.x(), rcy = rc.y(), rcz = rc.z();
  const float *px = p.x[0], *py = p.x[1], *pz = p.x[2];
  const float *rx = p.r[0], *ry = p.r[1], *rz = p.r[2];
  const float* pw = p.w;
  const float *mqx = p.memberQ[0], *mqy = p.memberQ[1], *mqz = p.memberQ[2], *mw = p.memberW;

  for (int blockBegin = begin; blockBegin < end; blockBegin += kBlock) {
    const int blockEnd = std::min(end, blockBegin + kBlock);
    alignas(32) float acc[kCount][kLanes] = {};
    auto addMember = [&](int k, int lane) {
      const int i = kGather ? members[k] : k;
      const float w = kGather ? mw[k] : pw[i];
      const float dx = px[i] - refx, dy = py[i] - refy, dz = pz[i] - refz;
      const float qx = kGather ? mqx[k] : rx[i] - rcx;
      const float qy = kGather ? mqy[k] : ry[i] - rcy;
      const float qz = kGather ? mqz[k] : rz[i] - rcz;
      const float wdx = w * dx, wdy = w * dy, wdz = w * dz;
      acc[0][lane] += wdx;
      acc[1][lane] += wdy;
      acc[2][lane] += wdz;
      acc[3][lane] += wdx * qx;
      acc[4][lane] += wdx * qy;
      acc[5][lane] += wdx * qz;
      acc[6][lane] += wdy * qx;
      acc[7][lane] += wdy * qy;
      acc[8][lane] += wdy * qz;
      acc[9][lane] += wdz * qx;
      acc[10][lane] += wdz * qy;
      acc[11][lane] += wdz * qz;
      if constexpr (kQuadratic) {
        const float m[6] = {qx * qx, qy * qy, qz * qz, qx * qy, qy * qz, qz * qx};
        for (int j = 0; j < 6; ++j) {
          acc[12 + j][lane] += wdx * m[j];
          acc[18 + j][lane] += wdy * m[j];
          acc[24 + j][lane] += wdz * m[j];
        }
      }
    };
    int k = blockBegin;
    for (; k + kLanes <= blockEnd; k += kLanes)
      for (int lane = 0; lane < kLanes; ++lane) addMember(k + lane, lane);
    for (; k < blockEnd; ++k) addMember(k, 0);
    for (int n = 0; n < kCount; ++n)
      for (int lane = 0; lane < kLanes; ++lane) total[n] += double(acc[n][lane]);
  }

  ClusterMoments out;
  out.wd = Vec3(total[0], total[1], total[2]);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out.wdq(a, b) = total[3 + 3 * a + b];
  if constexpr (kQuadratic) {
    for (int a = 0; a < 3; ++a)
      for (int j = 0; j < 6; ++j) out.wdm(a, j) = total[12 + 6 * a + j];
  }
  return out;
}

// Small clusters (a tetrahedron, a handful of particles): straight float sums, no lane
// bookkeeping, which for a few members costs more than the sums themselves.
ClusterMoments accumulateSmall(const ParticleColumns& p, const int* members, int begin, int end,
                               const Eigen::Vector3f& ref, const Eigen::Vector3f& rc,
                               bool quadratic) {
  Eigen::Vector3f wdSum = Eigen::Vector3f::Zero();
  Eigen::Matrix3f wdq = Eigen::Matrix3f::Zero();
  Eigen::Matrix<float, 3, 6> wdm = Eigen::Matrix<float, 3, 6>::Zero();
  for (int k = begin; k < end; ++k) {
    const int i = members ? members[k] : k;
    const float w = p.w[i];
    const Eigen::Vector3f wd =
        w * Eigen::Vector3f(p.x[0][i] - ref.x(), p.x[1][i] - ref.y(), p.x[2][i] - ref.z());
    const Eigen::Vector3f q(p.r[0][i] - rc.x(), p.r[1][i] - rc.y(), p.r[2][i] - rc.z());
    wdSum += wd;
    wdq.noalias() += wd * q.transpose();
    if (quadratic) wdm.noalias() += wd * monomials<float>(q).transpose();
  }
  ClusterMoments out;
  out.wd = wdSum.cast<double>();
  out.wdq = wdq.cast<double>();
  if (quadratic) out.wdm = wdm.cast<double>();
  return out;
}

}  // namespace

// Compiled for x86-64-v4 (AVX-512VL: 32 registers of eight lanes, so most of the quadratic fit's
// thirty accumulators stay in registers too; goals of BM_QuadraticOneCluster ~1.24 → ~1.09 ns per
// particle), x86-64-v3 (AVX2: eight lanes per register and sixteen registers, so the twelve
// linear accumulators stay in registers instead of spilling) and the baseline; the loader picks
// by CPU. Same bits on each: lane-wise IEEE operations, fixed summation order, no FMA.
// (A test defines SB_SHAPE_MATCHING_BASELINE to build the baseline alone and compare the bits.)
#ifndef SB_SHAPE_MATCHING_BASELINE
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
ClusterMoments
accumulateMoments(const ParticleColumns& p, const int* members, int begin, int end,
                  const Eigen::Vector3f& ref, const Eigen::Vector3f& restCentre, bool quadratic) {
  if (end - begin < 2 * kLanes)
    return accumulateSmall(p, members, begin, end, ref, restCentre, quadratic);
  if (members) {
    return quadratic ? accumulate<true, true>(p, members, begin, end, ref, restCentre)
                     : accumulate<true, false>(p, members, begin, end, ref, restCentre);
  }
  return quadratic ? accumulate<false, true>(p, members, begin, end, ref, restCentre)
                   : accumulate<false, false>(p, members, begin, end, ref, restCentre);
}

ClusterFit fitCluster(const ClusterMoments& m, const Eigen::Vector3f& ref,
                      const ClusterRestModel& rest, const ClusterShape& shape, const Mat3& plastic,
                      const Eigen::Quaterniond& warmRotation) {
  ClusterFit fit;
  const Vec3 dc = m.wd / rest.mass;
  fit.centre = ref.cast<double>() + dc;
  // Σ w p q⁰ᵀ with p = x − x_cm, from sums taken about ref; then q = Sᵖ q⁰.
  const Mat3 Apq0 = m.wdq - dc * rest.sumWq0.transpose();
  fit.Apq = Apq0 * plastic.transpose();
  fit.finite = fit.centre.allFinite() && fit.Apq.allFinite() && m.wdm.allFinite();
  if (!fit.finite) {
    fit.rotation = warmRotation;
    fit.linear = Mat3::Identity();
    return fit;
  }
  fit.rotation = closestRotation(fit.Apq, warmRotation);
  fit.linear = fit.Apq * shape.AqqInv;
  return fit;
}

GoalTransform goalTransform(const ClusterFit& fit, const ClusterMoments& m,
                            const ClusterRestModel& rest, const ClusterShape& shape,
                            const Mat3& plastic, const BodyParams& params) {
  const Mat3 R = fit.rotation.matrix();
  const double beta = appliedBeta(params.beta);
  Mat3 Tlin = R;                                                            // acts on q
  Eigen::Matrix<double, 3, 6> Tquad = Eigen::Matrix<double, 3, 6>::Zero();  // acts on mono(q) − μ
  switch (params.mode) {
    case Mode::Rigid:
      break;
    case Mode::Linear: {
      Mat3 A = fit.linear;
      const double det = A.determinant();
      const double size = A.norm();
      // An inverted or flat fit (or a flat cluster: ClusterShape::flat) has no volume to
      // preserve (and no real cube root to take): the rotation is the only meaningful goal then.
      if (shape.flat || !(det > 1e-12 * size * size * size)) {
        A = R;
      } else if (params.preserveVolume) {
        // Restoring the volume scales the fit isotropically by 1/∛det. For a cluster crushed
        // almost flat that factor is unbounded and would fling the goals (and all the energy)
        // far away, so the restoring scale is capped: volume comes back over several steps.
        A /= std::clamp(std::cbrt(det), kMinVolumeScale, 1.0 / kMinVolumeScale);
      }
      // Bound how far the fit may depart from the rotation. With volume restored, β near 1
      // leaves directions with no restoring force (any needle of the rest volume is a fixed
      // point), and the goals could wander to unbounded sizes, taking the energy with them.
      const double departure = (A - R).norm();
      if (departure > kMaxFitDeparture) A = R + (kMaxFitDeparture / departure) * (A - R);
      Tlin = beta * A + (1.0 - beta) * R;
      break;
    }
    case Mode::Quadratic: {
      const double invS = 1.0 / rest.scale;
      const Vec3 dc = m.wd / rest.mass;
      Eigen::Matrix<double, 3, 9> Apq;  // Σ w p q̃ᵀ in normalised coordinates
      Apq.leftCols<3>() = fit.Apq * invS;
      Apq.rightCols<6>() =
          (m.wdm - dc * rest.sumWmono0.transpose()) * shape.mono.transpose() * (invS * invS);
      const Eigen::Matrix<double, 3, 9> A = Apq * shape.AqqTildeInv;
      Tlin = beta * A.leftCols<3>() * invS + (1.0 - beta) * R;
      Tquad = beta * A.rightCols<6>() * (invS * invS);
      break;
    }
  }
  // Re-express g = Tlin·q + Tquad·(mono(q) − μ) + x_cm in the body-frame rest position r, where
  // q = Sᵖ r − s0 with s0 = Sᵖ rc, and mono(q) = mono(Sᵖ)·mono(r) + N·r + k.
  const Mat3& S = plastic;
  const Vec3 s0 = S * rest.centre.cast<double>();
  GoalTransform g;
  if (params.mode != Mode::Quadratic) {
    g.L = (Tlin * S).cast<float>();
    g.t = (fit.centre - Tlin * s0).cast<float>();
    return g;
  }
  static constexpr int kA[6] = {0, 1, 2, 0, 1, 2};
  static constexpr int kB[6] = {0, 1, 2, 1, 2, 0};
  Eigen::Matrix<double, 6, 3> N;
  Vec6 k;
  for (int j = 0; j < 6; ++j) {
    N.row(j) = -(s0[kA[j]] * S.row(kB[j]) + s0[kB[j]] * S.row(kA[j]));
    k[j] = s0[kA[j]] * s0[kB[j]];
  }
  g.L = (Tlin * S + Tquad * N).cast<float>();
  g.Q = (Tquad * shape.mono).cast<float>();
  g.t = (fit.centre - Tlin * s0 + Tquad * (k - shape.monoMean)).cast<float>();
  return g;
}

}  // namespace sb
