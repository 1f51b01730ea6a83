#include "sim/world/matching/particle_groups.h"

#include <map>

namespace sb {

ParticleGroups buildParticleGroups(int particleCount, const Csr& particleClusters, int clusterCount,
                                   const float* const rest[3], const float* w) {
  ParticleGroups g;
  if (clusterCount < 2) return g;  // one cluster: nothing to share
  // Group ids in order of first appearance, keyed by the particle's cluster list.
  std::map<std::vector<int>, int> ids;
  std::vector<int> groupOf(static_cast<size_t>(particleCount));
  for (int i = 0; i < particleCount; ++i) {
    std::vector<int> list(particleClusters.begin(i), particleClusters.end(i));
    groupOf[size_t(i)] = ids.emplace(std::move(list), static_cast<int>(ids.size())).first->second;
  }
  const int count = static_cast<int>(ids.size());
  if (2 * count > particleCount) return g;
  g.groupOf = std::move(groupOf);
  std::vector<const std::vector<int>*> listOf(static_cast<size_t>(count));
  for (const auto& [list, id] : ids) listOf[size_t(id)] = &list;
  buildCsr(
      count,
      [&](const auto& emit) {
        for (int k = 0; k < count; ++k)
          for (int c : *listOf[size_t(k)]) emit(k, c);
      },
      g.clusters);
  buildCsr(
      count,
      [&](const auto& emit) {
        for (int i = 0; i < particleCount; ++i) emit(g.groupOf[size_t(i)], i);
      },
      g.particles);
  buildCsr(
      clusterCount,
      [&](const auto& emit) {
        for (int k = 0; k < count; ++k)
          for (const int* c = g.clusters.begin(k); c != g.clusters.end(k); ++c) emit(*c, k);
      },
      g.clusterGroups);
  // Rest data.
  g.mass.assign(size_t(count), 0.0);
  g.restCentre.resize(size_t(count));
  g.sumWq.assign(size_t(count), Vec3::Zero());
  g.memberRest.resize(particleCount, 3);
  g.memberWeight.resize(particleCount);
  for (int k = 0; k < count; ++k) {
    Vec3 weighted = Vec3::Zero();
    for (int e = g.particles.start[size_t(k)]; e < g.particles.start[size_t(k) + 1]; ++e) {
      const int i = g.particles.items[size_t(e)];
      g.mass[size_t(k)] += w[i];
      weighted += double(w[i]) * Vec3(rest[0][i], rest[1][i], rest[2][i]);
    }
    g.restCentre[size_t(k)] = (weighted / g.mass[size_t(k)]).cast<float>();
    for (int e = g.particles.start[size_t(k)]; e < g.particles.start[size_t(k) + 1]; ++e) {
      const int i = g.particles.items[size_t(e)];
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
  for (const int* e = groups.clusterGroups.begin(c); e != groups.clusterGroups.end(c); ++e) {
    const size_t g = size_t(*e);
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
