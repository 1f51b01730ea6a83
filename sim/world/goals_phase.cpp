#include "sim/world/goals_phase.h"

#include <algorithm>
#include <chrono>

#include "sim/base/parallel_for.h"

namespace sb {

namespace {
// Below this many cluster members the moment sums run on one thread: fork/join would cost more
// than it saves.
constexpr long long kMinParallelMembers = 16384;
// Clusters (general path) and batches per sub-step from which their loops fork.
constexpr int kMinParallelClusters = 512;
constexpr int kMinParallelBatches = 64;
}  // namespace

GoalsTimes runGoalsPhase(const WorkLayout& layout, double h, std::vector<BodySlot>& slots,
                         GoalsScratch& scratch, std::vector<char>& bad) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const std::vector<GlobalTask>& tasks = layout.tasks;
  const std::vector<GlobalCluster>& clusters = layout.clusters;
  scratch.partial.resize(tasks.size());
  auto taskMoments = [&](int i) {
    const BodySlot& b = slots[size_t(tasks[size_t(i)].slot)];
    return b.state.clusters.taskMoments(*b.model, b.stepParams.mode == Mode::Quadratic, b.state.x,
                                        tasks[size_t(i)].task);
  };
  // Large clusters are split into tasks summed first, in parallel; a cluster with one task is
  // summed inside the per-cluster loop below (no second pass over its partial result).
  const std::vector<int>& split = layout.splitTasks;
  const int minParallelTasks = layout.members >= kMinParallelMembers ? 2 : INT32_MAX;
  parallelFor(static_cast<int>(split.size()), minParallelTasks, [&](int k) {
    scratch.partial[size_t(split[size_t(k)])] = taskMoments(split[size_t(k)]);
  });
  // Moments of particle groups (bodies with grouped moments), about each group's first particle.
  const std::vector<ParticleBlock>& groupBlocks = layout.momentGroupBlocks;
  parallelFor(static_cast<int>(groupBlocks.size()), minParallelTasks, [&](int i) {
    const ParticleBlock& blk = groupBlocks[size_t(i)];
    BodySlot& b = slots[size_t(blk.slot)];
    b.state.clusters.computeGroupMoments(*b.model, b.state.x, blk.begin, blk.end);
  });
  // Per cluster: sum its tasks in order (or its groups' moments), fit, plastic flow, goal.
  scratch.plasticSeconds.assign(clusters.size(), 0.0);
  scratch.clusterBad.assign(clusters.size(), 0);
  parallelFor(static_cast<int>(clusters.size()),
              clusters.size() >= size_t(kMinParallelClusters) ? 2 : INT32_MAX, [&](int i) {
                const GlobalCluster& gc = clusters[size_t(i)];
                BodySlot& b = slots[size_t(gc.slot)];
                const BodyModel& m = *b.model;
                ClusterMoments& sum = scratch.partial[size_t(gc.firstTask)];
                if (gc.grouped) {
                  sum = b.state.clusters.momentsFromGroups(m, gc.cluster);
                } else {
                  const int taskCount =
                      m.taskStart[size_t(gc.cluster) + 1] - m.taskStart[size_t(gc.cluster)];
                  if (taskCount == 1) sum = taskMoments(gc.firstTask);
                  for (int t = 1; t < taskCount; ++t)
                    sum += scratch.partial[size_t(gc.firstTask + t)];
                }
                scratch.clusterBad[size_t(i)] = b.state.clusters.updateCluster(
                    m, b.stepParams, gc.cluster, sum, h, &scratch.plasticSeconds[size_t(i)]);
              });
  // Batches of small clusters. Static split: a thread handles the same batches every sub-step,
  // so the clusters' state and goals stay in its cache (with a dynamic split they moved between
  // cores every sub-step, which cost more than the load balance gained).
  const std::vector<GlobalBatch>& batches = layout.batches;
  scratch.batchBad.assign(batches.size(), 0);
  parallelFor(static_cast<int>(batches.size()), kMinParallelBatches, [&](int i) {
    const GlobalBatch& gb = batches[size_t(i)];
    BodySlot& b = slots[size_t(gb.slot)];
    scratch.batchBad[size_t(i)] =
        b.state.clusters.updateBatch(*b.model, b.stepParams, gb.batch, b.state.x, h);
  });
  for (size_t i = 0; i < batches.size(); ++i)
    if (scratch.batchBad[i]) bad[size_t(batches[i].slot)] = 1;
  double plasticTotal = 0;
  for (size_t i = 0; i < clusters.size(); ++i) {
    plasticTotal += scratch.plasticSeconds[i];
    if (scratch.clusterBad[i]) bad[size_t(clusters[i].slot)] = 1;
  }
  // Plastic time is measured inside the cluster loop (summed over threads); report it apart.
  const double total = std::chrono::duration<double>(Clock::now() - t0).count();
  GoalsTimes times;
  times.plasticity = std::min(plasticTotal, total);
  times.goals = total - times.plasticity;
  return times;
}

}  // namespace sb
