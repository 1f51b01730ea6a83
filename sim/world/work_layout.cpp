#include "sim/world/work_layout.h"

#include <algorithm>

#include "sim/world/mass_properties.h"

namespace sb {

namespace {

constexpr int kParticlesPerBlock = 4096;          // particles per integration block
constexpr int kClusteredParticlesPerBlock = 128;  // the same for bodies with several clusters
// The Project phase sums a body's rigid motion by its blocks (integrate_phase.cpp).
static_assert(kParticlesPerBlock % kRigidMotionBlock == 0);

// Pieces [0, count) of body `slot` in blocks of `size`.
void appendBlocks(std::vector<ParticleBlock>& blocks, int slot, int count, int size) {
  for (int b = 0; b < count; b += size) blocks.push_back({slot, b, std::min(count, b + size)});
}

}  // namespace

WorkLayout buildWorkLayout(const std::vector<BodySlot>& slots, const std::vector<int>& order) {
  WorkLayout layout;
  for (int s : order) {
    const BodyModel& m = *slots[size_t(s)].model;
    const ClusterState::Path& path = slots[size_t(s)].state.clusters.path();
    const int base = static_cast<int>(layout.tasks.size());
    for (int t = 0; t < static_cast<int>(m.tasks.size()); ++t) layout.tasks.push_back({s, t});
    std::vector<char> inBatch(size_t(m.clusterCount()), 0);
    if (path.batched)
      for (int k = 0; k < static_cast<int>(m.batches.size()); ++k) {
        layout.batches.push_back({s, k});
        for (int l = 0; l < m.batches[size_t(k)].count; ++l)
          inBatch[size_t(m.batches[size_t(k)].cluster[l])] = 1;
      }
    for (int c = 0; c < m.clusterCount(); ++c) {
      if (!inBatch[size_t(c)])
        layout.clusters.push_back({s, c, base + m.taskStart[size_t(c)], path.grouped});
      if (!path.grouped && m.taskStart[size_t(c) + 1] - m.taskStart[size_t(c)] > 1)
        for (int t = m.taskStart[size_t(c)]; t < m.taskStart[size_t(c) + 1]; ++t)
          layout.splitTasks.push_back(base + t);
    }
    const int n = m.particleCount();
    // Clustered bodies in smaller blocks: a particle there costs a sum over its clusters, and
    // blocks that follow the clusters' split over threads read goals their own thread wrote.
    const int block = m.wholeBodyCluster ? kParticlesPerBlock : kClusteredParticlesPerBlock;
    appendBlocks(layout.blocks, s, n, block);
    const int groups = m.groups.count();
    appendBlocks(layout.groupBlocks, s, groups, kClusteredParticlesPerBlock);
    if (path.grouped)
      appendBlocks(layout.momentGroupBlocks, s, groups, kClusteredParticlesPerBlock);
    layout.members += static_cast<long long>(m.clusterMembers.items.size());
    layout.particles += n;
  }
  return layout;
}

}  // namespace sb
