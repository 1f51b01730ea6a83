// SweepSchedule (sim/world/contact/sweep_schedule.h): a sweep on several threads gives the
// one-thread sweep's results bit for bit, because every body sees its visits in sweep order.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/world/contact/sweep_schedule.h"

namespace sb {
namespace {

struct Sweep {
  std::vector<std::array<int, 2>> bodies;  // per item: the bodies it writes (−1: none)
  int bodyCount = 0;
};

// Runs of items between random pairs of bodies, some against nothing (a static collider), like
// the contacts of a pile: pairs in order, then each body's static contacts.
Sweep randomSweep(unsigned seed, int bodyCount, int pairs) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> body(0, bodyCount - 1), run(1, 12);
  Sweep s;
  s.bodyCount = bodyCount;
  for (int p = 0; p < pairs; ++p) {
    const int a = body(rng);
    int b = body(rng);
    if (b == a) b = -1;
    const int n = run(rng);
    for (int k = 0; k < n; ++k) s.bodies.push_back({a, b});
  }
  for (int a = 0; a < bodyCount; a += 3)
    for (int k = 0; k < 4; ++k) s.bodies.push_back({a, -1});
  return s;
}

// Each visit mixes the item into both of its bodies' states: an order-dependent result, so a
// body that saw two of its visits swapped ends with another value.
void visitItem(const Sweep& s, int k, std::vector<std::uint64_t>& state) {
  for (int b : s.bodies[size_t(k)])
    if (b >= 0) state[size_t(b)] = (state[size_t(b)] ^ std::uint64_t(k + 1)) * 0x100000001b3ULL;
}

constexpr int kSweeps = 3;  // a schedule is reused sweep after sweep

TEST(SweepSchedule, ParallelSweepsEqualTheSequentialOneBitForBit) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Sweep s = randomSweep(seed, 60 + 40 * int(seed), 400);
    const std::vector<std::uint64_t> start(size_t(s.bodyCount), 0x9e3779b97f4a7c15ULL);
    std::vector<std::uint64_t> sequential = start;
    for (int sweep = 0; sweep < kSweeps; ++sweep)
      for (int k = 0; k < int(s.bodies.size()); ++k) visitItem(s, k, sequential);
    for (int threads : {1, 2, 3}) {
      setThreadCount(threads);
      SweepSchedule schedule;
      schedule.build(int(s.bodies.size()), s.bodyCount, threads,
                     [&](int k) { return s.bodies[size_t(k)]; });
      std::vector<std::uint64_t> scheduled = start;
      for (int sweep = 0; sweep < kSweeps; ++sweep)
        schedule.run([&](int k) { visitItem(s, k, scheduled); });
      setThreadCount(0);
      EXPECT_EQ(scheduled, sequential) << "seed " << seed << ", threads " << threads;
      // Parallel at all: far fewer levels than tasks (400 pairs and the static runs).
      EXPECT_LT(schedule.levels(), schedule.tasks() / 3) << "seed " << seed;
    }
  }
}

// The trivial sweeps: none, one item, and every item on one body (one level per task).
TEST(SweepSchedule, EmptyAndSerialSweeps) {
  SweepSchedule schedule;
  schedule.build(0, 5, 2, [](int) { return std::array<int, 2>{0, 1}; });
  int visits = 0;
  schedule.run([&](int) { ++visits; });
  EXPECT_EQ(visits, 0);
  EXPECT_EQ(schedule.levels(), 0);
  std::vector<int> order;
  const std::vector<std::array<int, 2>> chain{{0, 1}, {1, 2}, {2, 0}, {0, -1}};
  schedule.build(int(chain.size()), 3, 2, [&](int k) { return chain[size_t(k)]; });
  schedule.run([&](int k) { order.push_back(k); });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(schedule.levels(), 4);
}

}  // namespace
}  // namespace sb
