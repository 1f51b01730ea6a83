// Parallel loops for the library's own .cpp files (not a public header), on the pool of
// sim/base/parallel.h. Work is always split into the same fixed pieces whatever the thread
// count, and every sum is formed in a fixed order by the callers, so results are bit-identical
// for any thread count.
#pragma once

#include <algorithm>

#include "sim/base/parallel.h"

namespace sb {

// Loops that stream a few floats per particle fork from this many particles of one body: below,
// the fork/join costs more than the second thread saves (one place for the passes inside a body:
// predict, velocities, damping, its rigid motion, its fastest speed).
inline constexpr int kMinParallelParticles = 32768;

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

}  // namespace sb
