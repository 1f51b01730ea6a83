#include "sim/world/body.h"

#include <Eigen/Geometry>
#include <algorithm>

#include "sim/world/matching/cluster_layout.h"

namespace sb {

namespace {

constexpr int kMembersPerTask = 8192;        // cluster members per moment task
constexpr double kSleepSpeedPerSize = 0.05;  // 1/s: sleep speed per metre of size
constexpr double kMaxSleepSpeed = 0.05;      // m/s
// The reach per rest radius of gyration (docs/design.md §5.3): a particle may end a goal
// projection at most that far from its goal (a bunny of 0.55 m: ~0.16 m). The soak's bodies at
// α ≥ 0.05 never came near it (they grew at most 1.41×); without it, a bunny at α 0.004 under
// the large scene's pile spread to 10× its size, and one at α 0 under three heavy bunnies to 27×.
constexpr double kReachOfGyration = 1.0;

// Everything that depends on the clusters: membership both ways, particle groups, matching
// weights, rest models, moment tasks, member rest offsets and batches.
void buildClusters(BodyModel& m, const ClusterDef& clusters) {
  m.clusterDef = clusters;
  std::vector<Vec3> restWorld(static_cast<size_t>(m.particleCount()));
  for (int i = 0; i < m.particleCount(); ++i)
    restWorld[size_t(i)] = m.rest.row(i).transpose().cast<double>() + m.origin;
  const std::vector<std::vector<int>> lists = buildClusterMembers(clusters, restWorld);

  const int n = m.particleCount();
  const int nc = static_cast<int>(lists.size());
  buildCsr(
      nc,
      [&](const auto& emit) {
        for (int c = 0; c < nc; ++c)
          for (int p : lists[size_t(c)]) emit(c, p);
      },
      m.clusterMembers);
  buildCsr(
      n,
      [&](const auto& emit) {
        for (int c = 0; c < nc; ++c)
          for (int p : lists[size_t(c)]) emit(p, c);
      },
      m.particleClusters);
  m.matchWeight.resize(n);
  m.invCount.resize(n);
  for (int i = 0; i < n; ++i) {
    m.invCount[i] = 1.0f / float(m.particleClusters.size(i));
    m.matchWeight[i] = m.mass[i] * m.invCount[i];
  }
  for (int p : m.pinned) m.matchWeight[p] *= kPinnedWeightFactor;
  m.wholeBodyLevel = nc > 1;
  if (m.wholeBodyLevel) {
    std::vector<int> all(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) all[size_t(i)] = i;
    m.bodyRest = buildClusterRest(all.data(), n, m.rest.col(0).data(), m.rest.col(1).data(),
                                  m.rest.col(2).data(), m.bodyWeight.data());
    m.bodyShape = deriveClusterShape(m.bodyRest, Mat3::Identity(), /*quadratic=*/true);
  }
  const float* restCols[3] = {m.rest.col(0).data(), m.rest.col(1).data(), m.rest.col(2).data()};
  m.groups = buildParticleGroups(n, m.particleClusters, nc, restCols, m.matchWeight.data());
  m.wholeBodyCluster = nc == 1 && int(m.clusterMembers.items.size()) == n;
  m.clusterRest.resize(size_t(nc));
  m.tasks.clear();
  m.taskStart.assign(1, 0);
  for (int c = 0; c < nc; ++c) {
    const int b = m.clusterMembers.start[size_t(c)], e = m.clusterMembers.start[size_t(c) + 1];
    m.clusterRest[size_t(c)] =
        buildClusterRest(m.clusterMembers.items.data() + b, e - b, m.rest.col(0).data(),
                         m.rest.col(1).data(), m.rest.col(2).data(), m.matchWeight.data());
    for (int k = b; k < e; k += kMembersPerTask)
      m.tasks.push_back({c, k, std::min(e, k + kMembersPerTask)});
    m.taskStart.push_back(static_cast<int>(m.tasks.size()));
  }
  const int memberCount = static_cast<int>(m.clusterMembers.items.size());
  m.memberRest.resize(memberCount, 3);
  m.memberWeight.resize(memberCount);
  for (int c = 0; c < nc; ++c) {
    const Eigen::Vector3f rc = m.clusterRest[size_t(c)].centre;
    for (int k = m.clusterMembers.start[size_t(c)]; k < m.clusterMembers.start[size_t(c) + 1];
         ++k) {
      const int i = m.clusterMembers.items[size_t(k)];
      for (int a = 0; a < 3; ++a) m.memberRest(k, a) = m.rest(i, a) - rc[a];  // as the kernels do
      m.memberWeight[k] = m.matchWeight[i];
    }
  }
  const float* memberRest[3] = {m.memberRest.col(0).data(), m.memberRest.col(1).data(),
                                m.memberRest.col(2).data()};
  m.batches =
      buildClusterBatches(m.clusterMembers, memberRest, m.memberWeight.data(), m.clusterRest);
}

}  // namespace

std::shared_ptr<BodyModel> buildBodyModel(const BodyDef& def,
                                          mesh::SurfaceTopology surfaceTopology) {
  auto m = std::make_shared<BodyModel>();
  const int n = static_cast<int>(def.positions.size());
  m->name = def.name;
  m->mass.resize(n);
  for (int i = 0; i < n; ++i)
    m->mass[i] = def.masses.empty() ? float(def.totalMass / n) : float(def.masses[size_t(i)]);
  m->totalMass = 0;
  Vec3 weighted = Vec3::Zero();
  for (int i = 0; i < n; ++i) {
    m->totalMass += m->mass[i];
    weighted += double(m->mass[i]) * def.positions[size_t(i)];
  }
  m->origin = weighted / m->totalMass;
  m->rest.resize(n, 3);
  m->startPositions.resize(n, 3);
  m->startVelocities.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    m->rest.row(i) = (def.positions[size_t(i)] - m->origin).transpose().cast<float>();
    m->startPositions.row(i) = def.positions[size_t(i)].transpose().cast<float>();
    m->startVelocities.row(i) = def.velocity.transpose().cast<float>();
  }
  m->pinned = def.pinned;
  m->surface = def.surface;
  m->surfaceTopology = std::move(surfaceTopology);
  m->spacing = float(mesh::meanEdgeLength(m->surface, def.positions));
  m->contactInvMass = m->mass.cwiseInverse();
  for (int p : m->pinned) m->contactInvMass[p] = 0.0f;
  // Sleep speed: 5 % of the body's size (its rest bounding-box diagonal) per second, at most
  // 5 cm/s (Box2D's 0.05 m/s and Jolt's 0.03 m/s are for bodies of about a metre): a 0.1 m body
  // sleeps below 9 mm/s, a 0.4 m box below 3.5 cm/s. Anything slower moves less than 2.5 % of
  // its size over the half second it must stay that slow.
  Eigen::AlignedBox3d box;
  for (const Vec3& p : def.positions) box.extend(p);
  m->sleepSpeed = float(std::min(kMaxSleepSpeed, kSleepSpeedPerSize * box.diagonal().norm()));
  double inertia = 0;  // Σ m|r|², r from the rest centre of mass (the body frame's origin)
  for (int i = 0; i < n; ++i) inertia += double(m->mass[i]) * double(m->rest.row(i).squaredNorm());
  m->gyrationRadius = float(std::sqrt(inertia / m->totalMass));
  m->reach = float(kReachOfGyration) * m->gyrationRadius;
  m->bodyWeight = m->mass;
  for (int p : m->pinned) m->bodyWeight[p] *= kPinnedWeightFactor;
  buildClusters(*m, def.clusters);
  return m;
}

std::shared_ptr<BodyModel> withClusters(const BodyModel& base, const ClusterDef& clusters) {
  auto m = std::make_shared<BodyModel>(base);
  buildClusters(*m, clusters);
  return m;
}

void resetBodyState(const BodyModel& model, BodyState& state) {
  state.x = model.startPositions;
  state.v = model.startVelocities;
  state.clusters.reset(model, state.x);
}

}  // namespace sb
