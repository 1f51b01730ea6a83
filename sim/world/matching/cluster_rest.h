// Per-cluster rest data: what shape matching needs to know about a cluster's rest shape.
//
// Notation (docs/design.md §5.1): rᵢ is a particle's rest position in its body's frame, rc the
// cluster's mass-weighted rest centre, q⁰ᵢ = rᵢ − rc the original rest offset, Sᵖ the cluster's
// plastic deformation and qᵢ = Sᵖ q⁰ᵢ the current rest offset. mono(q) are the quadratic
// monomials [qx², qy², qz², qx·qy, qy·qz, qz·qx].
//
// Everything that depends on Sᵖ is derived in closed form from moments of q⁰ gathered once, so a
// plastic update costs O(1) per cluster instead of a pass over its particles.
#pragma once

#include <Eigen/Core>

#include "sim/base/types.h"

namespace sb {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec9 = Eigen::Matrix<double, 9, 1>;

// Never changes after the cluster is built.
struct ClusterRestModel {
  double mass = 0;             // Σ wᵢ over members (kg); wᵢ = particle mass / #clusters
  Eigen::Vector3f centre;      // rc, body frame (m); float because kernels use it so
  Vec3 sumWq0 = Vec3::Zero();  // Σ w q⁰ as the float kernels evaluate q⁰ (≈ 0, kept exact)
  Vec6 sumWmono0 = Vec6::Zero();  // Σ w mono(q⁰) (kg·m²)
  Mat9 moments0 = Mat9::Zero();   // Σ w y yᵀ with y = [q⁰, mono(q⁰)]
  double scale = 1.0;             // RMS radius of q⁰ (m, > 0): normalises quadratic terms
};

// Depends on Sᵖ; rebuilt when Sᵖ changes. The quadratic part (a 9×9 eigen-decomposition) is
// only derived when a body is in quadratic mode.
struct ClusterShape {
  bool hasQuadratic = false;   // AqqTildeInv and monoMean are valid
  Mat3 AqqInv = Mat3::Zero();  // (Σ w q qᵀ)⁺, pseudo-inverse: flat/collinear clusters are fine
  // The members lie on a plane or a line (AqqInv dropped a direction): every linear fit
  // A = Apq·AqqInv is singular, so it has no volume to restore and the linear goal is the
  // rotation (goalTransform). Decided here, once, in double: the float batch kernel cannot tell
  // such a fit's determinant (round-off, either sign) from a small real one.
  bool flat = false;
  Mat9 AqqTildeInv = Mat9::Zero();  // (Σ w q̃ q̃ᵀ)⁺ with q̃ = [q/s, (mono(q) − mean)/s²]
  Vec6 monoMean = Vec6::Zero();     // mass-weighted mean of mono(q) (m²)
  Mat6 mono = Mat6::Identity();     // mono(Sᵖ q⁰) = mono · mono(q⁰)
};

// Quadratic monomials of q, in the order documented above.
template <typename T>
inline Eigen::Matrix<T, 6, 1> monomials(const Eigen::Matrix<T, 3, 1>& q) {
  Eigen::Matrix<T, 6, 1> m;
  m << q.x() * q.x(), q.y() * q.y(), q.z() * q.z(), q.x() * q.y(), q.y() * q.z(), q.z() * q.x();
  return m;
}

// The linear map M with mono(S·q) = M·mono(q) for all q.
Mat6 monomialMap(const Mat3& S);

// Builds the rest model of a cluster from its members' rest positions r (body frame, float as
// stored) and matching weights w (kg). `count` members.
ClusterRestModel buildClusterRest(const int* members, int count, const float* rx, const float* ry,
                                  const float* rz, const float* w);

// Derives the Sᵖ-dependent data; the quadratic part only when `quadratic`.
ClusterShape deriveClusterShape(const ClusterRestModel& rest, const Mat3& plastic, bool quadratic);

}  // namespace sb
