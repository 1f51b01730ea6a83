#include "sim/particle_groups.h"

#include <map>

namespace sb {

ParticleGroups buildParticleGroups(int particleCount, const std::vector<int>& particleStart,
                                   const std::vector<int>& particleClusters, int clusterCount,
                                   const float* const rest[3], const float* w) {
  ParticleGroups g;
  if (clusterCount < 2) return g;  // one cluster: nothing to share
  // Group ids in order of first appearance, keyed by the particle's cluster list.
  std::map<std::vector<int>, int> ids;
  std::vector<int> groupOf(static_cast<size_t>(particleCount));
  for (int i = 0; i < particleCount; ++i) {
    std::vector<int> list(particleClusters.begin() + particleStart[size_t(i)],
                          particleClusters.begin() + particleStart[size_t(i) + 1]);
    groupOf[size_t(i)] = ids.emplace(std::move(list), static_cast<int>(ids.size())).first->second;
  }
  const int count = static_cast<int>(ids.size());
  if (2 * count > particleCount) return g;
  g.groupOf = std::move(groupOf);
  g.clusterStart.assign(size_t(count) + 1, 0);
  std::vector<const std::vector<int>*> listOf(static_cast<size_t>(count));
  for (const auto& [list, id] : ids) listOf[size_t(id)] = &list;
  for (int k = 0; k < count; ++k) {
    g.clusters.insert(g.clusters.end(), listOf[size_t(k)]->begin(), listOf[size_t(k)]->end());
    g.clusterStart[size_t(k) + 1] = static_cast<int>(g.clusters.size());
  }
  // Particles by group (counting sort keeps them ascending within a group).
  g.particleStart.assign(size_t(count) + 1, 0);
  for (int i = 0; i < particleCount; ++i) ++g.particleStart[size_t(g.groupOf[size_t(i)]) + 1];
  for (int k = 0; k < count; ++k) g.particleStart[size_t(k) + 1] += g.particleStart[size_t(k)];
  g.particles.resize(size_t(particleCount));
  std::vector<int> fill(g.particleStart.begin(), g.particleStart.end() - 1);
  for (int i = 0; i < particleCount; ++i)
    g.particles[size_t(fill[size_t(g.groupOf[size_t(i)])]++)] = i;
  // Groups by cluster.
  g.clusterGroupStart.assign(size_t(clusterCount) + 1, 0);
  for (int c : g.clusters) ++g.clusterGroupStart[size_t(c) + 1];
  for (int c = 0; c < clusterCount; ++c)
    g.clusterGroupStart[size_t(c) + 1] += g.clusterGroupStart[size_t(c)];
  g.clusterGroups.resize(g.clusters.size());
  std::vector<int> next(g.clusterGroupStart.begin(), g.clusterGroupStart.end() - 1);
  for (int k = 0; k < count; ++k)
    for (int e = g.clusterStart[size_t(k)]; e < g.clusterStart[size_t(k) + 1]; ++e)
      g.clusterGroups[size_t(next[size_t(g.clusters[size_t(e)])]++)] = k;
  // Rest data.
  g.mass.assign(size_t(count), 0.0);
  g.restCentre.resize(size_t(count));
  g.sumWq.assign(size_t(count), Vec3::Zero());
  g.memberRest.resize(particleCount, 3);
  g.memberWeight.resize(particleCount);
  for (int k = 0; k < count; ++k) {
    Vec3 weighted = Vec3::Zero();
    for (int e = g.particleStart[size_t(k)]; e < g.particleStart[size_t(k) + 1]; ++e) {
      const int i = g.particles[size_t(e)];
      g.mass[size_t(k)] += w[i];
      weighted += double(w[i]) * Vec3(rest[0][i], rest[1][i], rest[2][i]);
    }
    g.restCentre[size_t(k)] = (weighted / g.mass[size_t(k)]).cast<float>();
    for (int e = g.particleStart[size_t(k)]; e < g.particleStart[size_t(k) + 1]; ++e) {
      const int i = g.particles[size_t(e)];
      for (int a = 0; a < 3; ++a) {
        g.memberRest(e, a) = rest[a][i] - g.restCentre[size_t(k)][a];  // as the kernels do
        g.sumWq[size_t(k)][a] += double(w[i]) * double(g.memberRest(e, a));
      }
      g.memberWeight[e] = w[i];
    }
  }
  return g;
}

ClusterMoments clusterMomentsFromGroups(const ParticleGroups& groups, int c,
                                        const ClusterMoments* groupMoments,
                                        const Eigen::Vector3f* groupRef, const Eigen::Vector3f& ref,
                                        const Eigen::Vector3f& rc) {
  // With d = x − ref = (x − x_g) + Δx and q = r − rc = (r − r_g) + Δr, Δx = x_g − ref,
  // Δr = r_g − rc:  Σ w d = S_x + W Δx;  Σ w d qᵀ = S_xq + S_x Δrᵀ + Δx S_qᵀ + W Δx Δrᵀ,
  // with S_x = Σ w (x − x_g), S_xq = Σ w (x − x_g)(r − r_g)ᵀ (the group's moments), S_q = Σ w
  // (r − r_g), W = Σ w.
  ClusterMoments out;
  const Vec3 refD = ref.cast<double>(), rcD = rc.cast<double>();
  for (int e = groups.clusterGroupStart[size_t(c)]; e < groups.clusterGroupStart[size_t(c) + 1];
       ++e) {
    const size_t g = size_t(groups.clusterGroups[size_t(e)]);
    const ClusterMoments& m = groupMoments[g];
    const Vec3 dx = groupRef[g].cast<double>() - refD;
    const Vec3 dr = groups.restCentre[g].cast<double>() - rcD;
    const double W = groups.mass[g];
    out.wd += m.wd + W * dx;
    out.wdq += m.wdq + m.wd * dr.transpose() + dx * groups.sumWq[g].transpose() +
               (W * dx) * dr.transpose();
  }
  return out;
}

}  // namespace sb
