// The work lists of a step: which pieces the phases split their work into, over every body of
// the World, in a fixed order. Rebuilt only when bodies, their clusters or their cluster paths
// change; building them reads the bodies and changes nothing.
//
// Every parallel loop runs over one of these lists with a static split, and every sum over the
// pieces is formed in list order, so results do not depend on the thread count.
#pragma once

#include <vector>

#include "sim/world/body.h"

namespace sb {

// One unit of per-particle (or per-group) work: items [begin, end) of the body in `slot`.
struct ParticleBlock {
  int slot;
  int begin, end;
};

// A moment task of some body, in the world's fixed order.
struct GlobalTask {
  int slot;
  int task;
};

// A cluster of some body (one that is not in a batch) and where its tasks start in the world's
// task list.
struct GlobalCluster {
  int slot;
  int cluster;
  int firstTask;
  bool grouped;  // moments from the body's particle groups (ClusterState::Path::grouped)
};

// A batch of small clusters of some body.
struct GlobalBatch {
  int slot;
  int batch;
};

struct WorkLayout {
  std::vector<GlobalTask> tasks;
  std::vector<int> splitTasks;  // tasks of clusters with several tasks (summed in a first pass)
  std::vector<GlobalCluster> clusters;  // clusters not in a batch
  std::vector<GlobalBatch> batches;
  std::vector<ParticleBlock> blocks;       // particles, for integration
  std::vector<ParticleBlock> groupBlocks;  // the same over particle groups (begin, end: groups)
  std::vector<ParticleBlock> momentGroupBlocks;  // group blocks of bodies with grouped moments
  long long members = 0, particles = 0;          // totals over all bodies
};

// The work lists of the bodies `order` (slots in creation order), each on its current path.
WorkLayout buildWorkLayout(const std::vector<BodySlot>& slots, const std::vector<int>& order);

}  // namespace sb
