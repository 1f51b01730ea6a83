#include "sim/world/sleep_phase.h"

#include <algorithm>
#include <climits>

#include "sim/base/parallel_for.h"
#include "sim/base/union_find.h"

namespace sb {

namespace {

// max |xᵢ − aᵢ|² (m²) over the rows of x and a (a maximum: the same bits for any split).
float farthestSquared(const MatX3f& x, const MatX3f& a) {
  const int n = static_cast<int>(x.rows());
  const int pieces = std::max(1, std::min(threadCount(), 64));
  float piece[64] = {};
  parallelRanges(pieces, n >= kMinParallelParticles ? 2 : INT32_MAX, 1 << 30, [&](int c0, int c1) {
    for (int c = c0; c < c1; ++c) {
      const int begin = int(1LL * n * c / pieces), end = int(1LL * n * (c + 1) / pieces);
      piece[c] = end > begin ? (x.middleRows(begin, end - begin) - a.middleRows(begin, end - begin))
                                   .rowwise()
                                   .squaredNorm()
                                   .maxCoeff()
                             : 0.0f;
    }
  });
  return *std::max_element(piece, piece + pieces);
}

}  // namespace

bool runSleepPhase(double h, bool enabled, std::vector<BodySlot>& slots,
                   const std::vector<int>& awake, const std::vector<std::pair<int, int>>& touching,
                   const std::vector<char>& held, SleepScratch& scratch) {
  // With sleep off nothing reads the clocks (turning it on wakes every body, which restarts
  // them): no pass over the velocities (issue 17).
  if (!enabled) return false;
  bool candidate = false;
  for (int s : awake) {
    BodySlot& b = slots[size_t(s)];
    SleepState& sleep = b.sleep;
    // Still while every particle stays within the distance its sleep speed carries it in
    // kTimeToSleep of where the count started (Jolt's test, on every particle): a body that
    // rocks or rings in place by less than that rests, whatever its particles' speeds.
    const float radius = b.model->sleepSpeed * float(kTimeToSleep);
    if (held[size_t(s)] || sleep.anchor.rows() != b.state.x.rows() ||
        farthestSquared(b.state.x, sleep.anchor) > radius * radius) {
      sleep.anchor = b.state.x;
      sleep.still = 0;
    } else {
      sleep.still += h;
    }
    candidate = candidate || sleep.still >= kTimeToSleep;
  }
  if (!candidate) return false;
  // Islands of awake bodies: an island sleeps only as a whole.
  std::vector<int>& parent = scratch.parent;
  parent.resize(slots.size());
  for (int s : awake) parent[size_t(s)] = s;
  for (const auto& [a, b] : touching) {
    if (slots[size_t(a)].sleep.asleep || slots[size_t(b)].sleep.asleep) continue;
    const int ra = findRoot(parent, a), rb = findRoot(parent, b);
    if (ra != rb) parent[size_t(std::max(ra, rb))] = std::min(ra, rb);
  }
  // An island is ready when its least still body is: mark the roots of islands that are not.
  std::vector<char> notReady(slots.size(), 0);
  for (int s : awake)
    if (slots[size_t(s)].sleep.still < kTimeToSleep) notReady[size_t(findRoot(parent, s))] = 1;
  bool fell = false;
  std::vector<int> islandId(slots.size(), -1);
  for (int s : awake) {
    const int root = findRoot(parent, s);
    if (notReady[size_t(root)]) continue;
    if (islandId[size_t(root)] < 0) islandId[size_t(root)] = scratch.nextIsland++;
    BodySlot& b = slots[size_t(s)];
    b.sleep.asleep = true;
    b.sleep.island = islandId[size_t(root)];
    b.state.v.setZero();
    b.sleep.anchor.resize(0, 3);  // read again only after it wakes, which restarts the count
    fell = true;
  }
  return fell;
}

bool wakeIsland(std::vector<BodySlot>& slots, const std::vector<int>& order, int s) {
  BodySlot& b = slots[size_t(s)];
  if (!b.sleep.asleep) {
    b.sleep.still = 0;
    b.sleep.anchor.resize(0, 3);
    return false;
  }
  const int island = b.sleep.island;
  for (int o : order) {
    SleepState& other = slots[size_t(o)].sleep;
    if (other.asleep && other.island == island) other = SleepState{};
  }
  return true;
}

}  // namespace sb
