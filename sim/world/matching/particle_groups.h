// Particle groups: the particles of a body that belong to exactly the same clusters.
//
// With grid clusters every particle of a grid cell lies in the same clusters (27 of them with a
// one-cell overlap), and every cluster is a union of whole groups. Work that runs over particles
// and their clusters, or over clusters and their particles, can then run once per group:
//   - the integration sums a particle's cluster goals: once per group (same bits);
//   - the Goals phase sums each cluster's moments over its particles: each group's moments are
//     summed once, about the group's own reference point, and a cluster adds up its groups'
//     moments shifted to its reference point (parallel-axis terms, in double).
// For a 64-particle cell in 27 clusters that is 27× less work per step. Stateless kernels.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "sim/base/csr.h"
#include "sim/base/types.h"
#include "sim/world/matching/shape_matching.h"

namespace sb {

struct ParticleGroups {
  // groupOf[i]: group of particle i (#P). Group g holds the particles particles.row(g) and lies
  // in the clusters clusters.row(g), both ascending. Cluster c is the union of the groups
  // clusterGroups.row(c), ascending.
  std::vector<int> groupOf;
  Csr particles, clusters, clusterGroups;
  // Per group: Σ w (kg), rest centre r_g (body frame, m; float as the kernels use it) and
  // Σ w (r − r_g) as the kernels evaluate it (≈ 0).
  std::vector<double> mass;
  std::vector<Eigen::Vector3f> restCentre;
  std::vector<Vec3> sumWq;
  // Per entry of `particles`: q = r − r_g (m) and the particle's weight w (kg), streamed by the
  // moment kernel (accumulateMoments with ParticleColumns::memberQ/memberW).
  Eigen::Matrix<float, Eigen::Dynamic, 3> memberRest;
  Eigen::VectorXf memberWeight;

  int count() const { return static_cast<int>(mass.size()); }
  bool empty() const { return mass.empty(); }
};

// Groups of a body with `particleCount` particles whose clusters are given per particle
// (particleClusters: one row per particle, ascending), with rest positions
// rest[0..2] (#P each, body frame, m) and matching weights w (#P, kg). Returns no groups when
// they would hold fewer than two particles on average: nothing to share then.
ParticleGroups buildParticleGroups(int particleCount, const Csr& particleClusters, int clusterCount,
                                   const float* const rest[3], const float* w);

// Moments of cluster `c` about its reference point `ref` (m) and rest centre `rc`, from the
// moments of its groups, each summed about the group's reference point groupRef[g] and its rest
// centre (linear moments only: wd and wdq).
ClusterMoments clusterMomentsFromGroups(const ParticleGroups& groups, int c,
                                        const ClusterMoments* groupMoments,
                                        const Eigen::Vector3f* groupRef, const Eigen::Vector3f& ref,
                                        const Eigen::Vector3f& rc);

}  // namespace sb
