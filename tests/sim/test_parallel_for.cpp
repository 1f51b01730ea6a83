// parallelForClaimed (sim/base/parallel_for.h): every item runs exactly once, whatever the
// thread count, the item count, or a loop nested inside another.
#include <gtest/gtest.h>

#include <atomic>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/base/parallel_for.h"

namespace sb {
namespace {

TEST(ParallelForClaimed, RunsEveryItemOnceOnAnyThreadCount) {
  for (int threads : {1, 2, 3}) {
    setThreadCount(threads);
    for (int count : {0, 1, 2, 5, 1000}) {
      std::vector<std::atomic<int>> runs(static_cast<size_t>(count));
      parallelForClaimed(count, 2, [&](int i) { runs[size_t(i)].fetch_add(1); });
      for (int i = 0; i < count; ++i) EXPECT_EQ(runs[size_t(i)].load(), 1) << count << " " << i;
    }
    setThreadCount(0);
  }
}

// Inside a parallel loop the pool is busy: the inner loop runs on its caller's thread alone.
TEST(ParallelForClaimed, NestedLoopsRunEveryItemOnce) {
  setThreadCount(2);
  std::vector<std::atomic<int>> runs(64);
  parallelForClaimed(8, 2, [&](int i) {
    parallelForClaimed(8, 2, [&](int j) { runs[size_t(8 * i + j)].fetch_add(1); });
  });
  setThreadCount(0);
  for (const std::atomic<int>& r : runs) EXPECT_EQ(r.load(), 1);
}

}  // namespace
}  // namespace sb
