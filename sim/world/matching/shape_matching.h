// Shape-matching kernels (docs/design.md §5.1): gather a cluster's moments, turn them into a goal
// transform. Stateless; the World calls them per cluster and per block of members.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sim/world/body_def.h"
#include "sim/world/matching/cluster_rest.h"

namespace sb {

// Sums over (part of) a cluster, relative to a reference point `ref` near the centre of mass
// (keeps float sums accurate far from the origin). d = x − ref, q⁰ = r − rc.
struct ClusterMoments {
  Vec3 wd = Vec3::Zero();                                                 // Σ w d
  Mat3 wdq = Mat3::Zero();                                                // Σ w d q⁰ᵀ
  Eigen::Matrix<double, 3, 6> wdm = Eigen::Matrix<double, 3, 6>::Zero();  // Σ w d mono(q⁰)ᵀ
  ClusterMoments& operator+=(const ClusterMoments& o) {
    wd += o.wd;
    wdq += o.wdq;
    wdm += o.wdm;
    return *this;
  }
};

// Where a kernel reads particle data: column pointers of #P-long float arrays.
struct ParticleColumns {
  const float* x[3];  // current positions (m), indexed by particle
  const float* r[3];  // rest positions in the body frame (m), indexed by particle
  const float* w;     // matching weights (kg), indexed by particle
  // Optional, indexed by membership k (parallel to `members`): the rest offset q⁰ = r − rc and the
  // weight of members[k], evaluated exactly as from r, rc and w. Streaming them instead of
  // gathering r and w leaves only x to gather in clusters that are not the whole body.
  const float* memberQ[3] = {nullptr, nullptr, nullptr};
  const float* memberW = nullptr;
};

// Accumulates members [begin, end) of a cluster: particle k is members[k], or k itself when
// members is null (a cluster that is the whole body, in order). Sums are formed in blocks of 8
// lanes of float and then in double, in an order that depends only on begin/end.
ClusterMoments accumulateMoments(const ParticleColumns& p, const int* members, int begin, int end,
                                 const Eigen::Vector3f& ref, const Eigen::Vector3f& restCentre,
                                 bool quadratic);

// Bounds of the linear goal (goalTransform and the batched kernel, cluster_batch.h): restoring
// the volume never scales a fit by more than 1/kMinVolumeScale (nor less than kMinVolumeScale),
// and ‖A − R‖_F is capped at kMaxFitDeparture (stretches up to about ×3 along an axis).
constexpr double kMinVolumeScale = 0.8;
constexpr double kMaxFitDeparture = 2.0;

// The blend β of the goal toward the linear/quadratic fit is applied as kBetaMax·β: even at
// β = 1 the goal keeps a tenth of the rotation's, so no deformation is free of restoring force.
// With the whole fit as goal (β exactly 1) every deformation the fit can represent costs
// nothing, and energy put into one (an impact, the stretch of a turning body) made bodies drift
// to unbounded sizes (docs/design.md §5.1).
constexpr double kBetaMax = 0.9;
inline double appliedBeta(double beta) {
  return kBetaMax * beta;
}

// Goal of a cluster for particle i, as a polynomial of its rest position rᵢ (body frame):
//   gᵢ = L·rᵢ + Q·mono(rᵢ) + t.
// Expressing goals in rᵢ (not in per-cluster offsets) lets a particle average the goals of all its
// clusters by averaging their (L, Q, t), with no per-membership data in the integration pass.
struct GoalTransform {
  Eigen::Matrix3f L = Eigen::Matrix3f::Identity();
  Eigen::Matrix<float, 3, 6> Q = Eigen::Matrix<float, 3, 6>::Zero();
  Eigen::Vector3f t = Eigen::Vector3f::Zero();
};

// Everything computeGoalTransform derives, for plasticity and diagnostics.
struct ClusterFit {
  Vec3 centre;  // x_cm (m)
  Mat3 Apq;     // Σ w p qᵀ
  Eigen::Quaterniond rotation;
  Mat3 linear;         // A = A_pq·A_qq (not volume-normalised)
  bool finite = true;  // false when the moments held NaN/Inf
};

ClusterFit fitCluster(const ClusterMoments& m, const Eigen::Vector3f& ref,
                      const ClusterRestModel& rest, const ClusterShape& shape, const Mat3& plastic,
                      const Eigen::Quaterniond& warmRotation);

// The goal transform for `mode` with blend β (linear/quadratic) and optional volume
// preservation (linear). Falls back to the rotation when the linear fit is inverted or flat.
GoalTransform goalTransform(const ClusterFit& fit, const ClusterMoments& m,
                            const ClusterRestModel& rest, const ClusterShape& shape,
                            const Mat3& plastic, const BodyParams& params);

}  // namespace sb
