// sim/base/parallel_for.h: parallelForClaimed runs every item exactly once, whatever the thread
// count, the item count, or a loop nested inside another; pieceHoldingMiddle cuts weighted items
// into pieces in order, each item whole, the pieces' weights close to equal.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
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

// Items in order go to pieces in order; each piece's weight is within one item's weight of its
// share (an item goes to the share that holds its middle, so a piece gains or loses at most half
// an item at each end); equal items split evenly.
TEST(PieceHoldingMiddle, CutsWeightedItemsIntoPiecesOfAboutEqualWeight) {
  const std::vector<long long> weights = {5, 1, 1, 9, 3, 0, 2, 7, 7, 1, 4, 6, 2, 8, 1, 3};
  long long total = 0, heaviest = 0;
  for (long long w : weights) {
    total += w;
    heaviest = std::max(heaviest, w);
  }
  for (int pieces : {1, 2, 3, 8}) {
    std::vector<long long> load(size_t(pieces), 0);
    long long before = 0;
    int last = 0;
    for (long long w : weights) {
      const int piece = pieceHoldingMiddle(before, w, total, pieces);
      ASSERT_GE(piece, last);
      ASSERT_LT(piece, pieces);
      load[size_t(piece)] += w;
      last = piece;
      before += w;
    }
    for (int p = 0; p < pieces; ++p)
      EXPECT_LE(std::abs(double(load[size_t(p)]) - double(total) / pieces), double(heaviest))
          << pieces << " pieces, piece " << p;
  }
  for (int i = 0; i < 12; ++i) EXPECT_EQ(pieceHoldingMiddle(i, 1, 12, 4), i / 3);
}

}  // namespace
}  // namespace sb
