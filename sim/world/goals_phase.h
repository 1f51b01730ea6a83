// The Goals phase (docs/design.md §3): per cluster, the centre of mass and moments of its
// particles, the best rotation and the goal transform; plastic flow of the rest shape for
// plastic bodies. Small clusters of rigid and linear bodies go eight at a time through the
// batched kernel (sim/world/matching/cluster_batch.h).
//
// Reads:  every body's positions x, model and parameters; the work lists.
// Writes: every body's ClusterState (reference points, rotations, plastic state, goals).
//         bad[slot] = 1 for bodies that produced NaN/Inf.
#pragma once

#include <vector>

#include "sim/world/body.h"
#include "sim/world/work_layout.h"

namespace sb {

// Scratch of the phase, kept between sub-steps so it does not allocate.
struct GoalsScratch {
  std::vector<ClusterMoments> partial;  // per task of the work layout
  std::vector<double> plasticSeconds;   // per cluster of the work layout
  std::vector<char> clusterBad, batchBad;
};

struct GoalsTimes {
  double goals = 0;       // seconds, without plastic flow
  double plasticity = 0;  // seconds of plastic flow (measured inside the cluster loop)
};

GoalsTimes runGoalsPhase(const WorkLayout& layout, double h, std::vector<BodySlot>& slots,
                         GoalsScratch& scratch, std::vector<char>& bad);

}  // namespace sb
