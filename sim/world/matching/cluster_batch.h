// Shape matching of many small clusters at once (docs/design.md §5.6; rigid and linear modes).
//
// A tetrahedral split of a body gives thousands of clusters of four particles. Per cluster the
// general path (shape_matching.h + rotation.h) spends ~400 ns, most of it in double-precision
// rotation extraction with its branches. Here eight clusters sit side by side in the lanes of
// float vectors and go through the same steps together: moments, a warm-started Newton rotation
// (fixed arithmetic, no sin/cos), the linear goal with volume restoration and its bounds, and the
// goal transform g = L·r + t. Lanes never mix, so a cluster's result does not depend on which
// clusters share its batch.
//
// A lane whose rotation the batch cannot certify as the global maximum (Hessian not positive
// definite: inverted or degenerate fits; no convergence within the iteration budget; zero
// moments) is reported in `fallback`: the caller runs the general path for that cluster, which
// handles those cases. A lane with NaN/Inf in its result is reported in `nonFinite`.
//
// Stateless kernel; the World owns the data.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/base/csr.h"
#include "sim/base/types.h"
#include "sim/world/body_def.h"
#include "sim/world/matching/cluster_rest.h"

namespace sb {

constexpr int kBatchLanes = 8;       // clusters per batch
constexpr int kBatchMaxMembers = 8;  // clusters with at most this many members are batched

// Rest data of up to eight clusters of one body; arrays are [member slot][lane]. Member slots
// past a cluster's size (and lanes past `count`) have weight 0 and point at a valid particle.
struct ClusterBatch {
  int count = 0;                  // clusters in the batch, 1..kBatchLanes
  int memberSlots = 0;            // largest member count in the batch, 1..kBatchMaxMembers
  int cluster[kBatchLanes] = {};  // cluster index per lane (lanes ≥ count repeat lane 0)
  int particle[kBatchMaxMembers][kBatchLanes] = {};
  float q0[3][kBatchMaxMembers][kBatchLanes] = {};  // rest offsets r − rc (m), as the kernels use
  float w[kBatchMaxMembers][kBatchLanes] = {};      // matching weights (kg)
  float mass[kBatchLanes] = {};                     // Σ w per cluster (kg)
  float sumWq0[3][kBatchLanes] = {};                // Σ w q⁰ (≈ 0; kept for exactness)
};

// The part of a batch that depends on the clusters' plastic deformation Sᵖ (refreshed when Sᵖ
// changes). Matrices row-major: element (a, b) at [3a + b].
struct ClusterBatchShape {
  float AqqInv[9][kBatchLanes];  // (Σ w q qᵀ)⁺ with q = Sᵖ q⁰ (1/kg/m²)
  float S[9][kBatchLanes];       // Sᵖ
  float s0[3][kBatchLanes];      // Sᵖ·rc (m)
  float flat[kBatchLanes];       // 1: ClusterShape::flat (the linear goal is the rotation), else 0
};

// Per-step state of the lanes: read as the warm start, written with the result.
struct ClusterBatchLanes {
  float ref[3][kBatchLanes];       // reference point of the float sums (m), then the new centre
  float rotation[4][kBatchLanes];  // unit quaternion (w, x, y, z): warm start, then the result
};

// Goal transforms g = L·r + t (r: rest position in the body frame) of the batch's lanes.
struct ClusterBatchGoals {
  float L[9][kBatchLanes];      // row-major
  float t[3][kBatchLanes];      // m
  std::uint32_t fallback = 0;   // bit per lane: use the general path for this cluster
  std::uint32_t nonFinite = 0;  // bit per lane: NaN/Inf in the positions or the result
};

// Groups the clusters with at most kBatchMaxMembers members, in cluster order, into batches.
// clusterMembers: the clusters' particle lists (M memberships in all); memberRest (#M×3 column
// pointers) and memberWeight (#M): each membership's q⁰ and weight; rest: per-cluster rest models.
std::vector<ClusterBatch> buildClusterBatches(const Csr& clusterMembers,
                                              const float* const memberRest[3],
                                              const float* memberWeight,
                                              const std::vector<ClusterRestModel>& rest);

// Fills lane `lane` of `shape` from one cluster's plastic deformation and derived shape.
void setBatchShapeLane(ClusterBatchShape& shape, int lane, const Mat3& plastic,
                       const ClusterShape& derived, const Eigen::Vector3f& restCentre);

// Goals of one batch for a body in `params.mode` (Rigid or Linear; Quadratic is not batched).
// x: particle position columns (m). `lanes` advances for every lane with a result; lanes in
// `fallback` or `nonFinite` keep their input. Goals are valid for lanes in neither.
ClusterBatchGoals matchClusterBatch(const ClusterBatch& batch, const ClusterBatchShape& shape,
                                    const float* const x[3], const BodyParams& params,
                                    ClusterBatchLanes& lanes);

}  // namespace sb
