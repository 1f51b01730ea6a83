// Parallel loops for the library's own .cpp files (not a public header), on the pool of
// sim/base/parallel.h. Work is always split into the same fixed pieces whatever the thread
// count, and every sum is formed in a fixed order by the callers, so results are bit-identical
// for any thread count.
#pragma once

#include <algorithm>
#include <atomic>

#include "sim/base/parallel.h"

namespace sb {

// Loops that stream a few floats per particle fork from this many particles of one body: below,
// the fork/join costs more than the second thread saves (one place for the passes inside a body:
// predict, velocities, damping, its rigid motion, its fastest speed).
inline constexpr int kMinParallelParticles = 32768;

// Of `pieces` consecutive shares of equal weight cutting a run of items of total weight `total`,
// the one that holds the middle of the item whose weight is `weight` and whose predecessors weigh
// `before` (all ≥ 0, before + weight ≤ total, total > 0): how items of unequal cost are cut into
// pieces of about equal cost without splitting one, in [0, pieces).
inline int pieceHoldingMiddle(long long before, long long weight, long long total, int pieces) {
  const long long twiceMiddle = 2 * before + weight;
  return int(std::min<long long>(pieces - 1, twiceMiddle * pieces / (2 * total)));
}

// Calls body(begin, end) on disjoint ranges covering [0, count), at most maxThreads of them
// (≤ threadCount()) at a time, one contiguous range per thread. Serial (one call) when count is
// below minParallel.
template <typename Body>
void parallelRanges(int count, int minParallel, int maxThreads, const Body& body) {
  if (count <= 0) return;
  const int chunks = std::min({count, threadCount(), std::max(1, maxThreads)});
  if (count < minParallel || chunks <= 1) {
    body(0, count);
    return;
  }
  struct Job {
    const Body* body;
    int count, chunks;
  } job{&body, count, chunks};
  detail::runChunks(
      chunks,
      [](void* ctx, int c) {
        const Job& j = *static_cast<const Job*>(ctx);
        const long long begin = 1LL * j.count * c / j.chunks,
                        end = 1LL * j.count * (c + 1) / j.chunks;
        if (begin < end) (*j.body)(int(begin), int(end));
      },
      &job);
}

// Calls body(i) for i in [0, count). Runs serially when count is below minParallel.
template <typename Body>
void parallelFor(int count, int minParallel, const Body& body) {
  parallelRanges(count, minParallel, 1 << 30, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) body(i);
  });
}

// Calls body(i) for i in [0, count) with the items handed out one at a time to whichever thread
// is free (an atomic counter), for loops whose items differ widely in cost (a contact pair of two
// large bodies next to one of two pebbles): a fixed cut gave one thread most of the work. Each
// body(i) must write only what belongs to item i, so the results do not depend on which thread
// ran it. Runs serially when count is below minParallel.
template <typename Body>
void parallelForClaimed(int count, int minParallel, const Body& body) {
  if (count <= 0) return;
  const int chunks = std::min(count, threadCount());
  if (count < minParallel || chunks <= 1) {
    for (int i = 0; i < count; ++i) body(i);
    return;
  }
  struct Job {
    const Body* body;
    int count;
    std::atomic<int> next{0};
  } job{&body, count};
  detail::runChunks(
      chunks,
      [](void* ctx, int) {
        Job& j = *static_cast<Job*>(ctx);
        for (int i = j.next.fetch_add(1, std::memory_order_relaxed); i < j.count;
             i = j.next.fetch_add(1, std::memory_order_relaxed))
          (*j.body)(i);
      },
      &job);
}

}  // namespace sb
