// SlabSchedule (sim/world/contact/slab_schedule.h): a large island's sweep in slab order gives
// the same bits on any number of threads, and its order is the one the header describes,
// recomputed here from the slabs alone.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/world/contact/slab_schedule.h"

namespace sb {
namespace {

struct Island {
  std::vector<std::array<int, 2>> bodies;  // per item: the bodies it writes (−1: none)
  std::vector<Eigen::Vector3f> centres;    // per body
};

// Bodies scattered over a pen (wider in z than in x), contacts in runs between bodies near in
// z, one pair in 29 between any two, one in 7 static: like a pile's island.
Island randomIsland(unsigned seed, int bodyCount, int pairs) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> x(-2, 2), y(0, 1), z(-5, 5);
  std::uniform_int_distribution<int> body(0, bodyCount - 1), near(-4, 4), run(1, 12);
  Island s;
  for (int b = 0; b < bodyCount; ++b) s.centres.emplace_back(x(rng), y(rng), z(rng));
  std::vector<int> byZ(static_cast<size_t>(bodyCount));
  for (int b = 0; b < bodyCount; ++b) byZ[size_t(b)] = b;
  std::sort(byZ.begin(), byZ.end(),
            [&](int a, int b) { return s.centres[size_t(a)].z() < s.centres[size_t(b)].z(); });
  for (int p = 0; p < pairs; ++p) {
    const int r = body(rng);
    const int a = byZ[size_t(r)];
    int b = -1;
    if (p % 29 == 0)
      b = body(rng);
    else if (p % 7 != 0)
      b = byZ[size_t(std::clamp(r + near(rng), 0, bodyCount - 1))];
    if (b == a) b = -1;
    const int n = run(rng);
    for (int k = 0; k < n; ++k)
      s.bodies.push_back(p % 2 ? std::array<int, 2>{a, b} : std::array<int, 2>{b, a});
  }
  return s;
}

// Each visit mixes the item into both of its bodies' states: an order-dependent result.
void visitItem(const Island& s, int k, std::vector<std::uint64_t>& state) {
  for (int b : s.bodies[size_t(k)])
    if (b >= 0) state[size_t(b)] = (state[size_t(b)] ^ std::uint64_t(k + 1)) * 0x100000001b3ULL;
}

SlabSchedule build(const Island& s) {
  SlabSchedule schedule;
  schedule.build(
      int(s.bodies.size()), int(s.centres.size()), [&](int k) { return s.bodies[size_t(k)]; },
      [&](int b) { return s.centres[size_t(b)]; });
  return schedule;
}

TEST(SlabSchedule, SweepsOnAnyThreadCountEqualTheOneThreadSweepBitForBit) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Island s = randomIsland(seed, 80 + 60 * int(seed), 600);
    const SlabSchedule schedule = build(s);
    const std::vector<std::uint64_t> start(s.centres.size(), 0x9e3779b97f4a7c15ULL);
    // The sweep in the schedule's order, one item after another.
    std::vector<std::uint64_t> sequential = start;
    for (int sweep = 0; sweep < 3; ++sweep)
      for (int k : schedule.order()) visitItem(s, k, sequential);
    for (int threads : {1, 2, 3}) {
      setThreadCount(threads);
      std::vector<std::uint64_t> scheduled = start;
      std::vector<int> visits(s.bodies.size(), 0);
      for (int sweep = 0; sweep < 3; ++sweep)
        schedule.run([&](int k) {
          visitItem(s, k, scheduled);
          ++visits[size_t(k)];  // bins run at once write distinct items
        });
      setThreadCount(0);
      EXPECT_EQ(scheduled, sequential) << "seed " << seed << ", threads " << threads;
      EXPECT_EQ(std::count(visits.begin(), visits.end(), 3), int(visits.size()));
    }
  }
}

// The order recomputed from the slabs: contacts within slab 0 … 7, even seams, odd seams, the
// rest; the island's order within each bin. The slabs follow the widest axis (z here) and hold
// about equal numbers of contact ends.
TEST(SlabSchedule, OrderIsBySlabThenSeamWithTheIslandOrderKept) {
  const Island s = randomIsland(7, 300, 900);
  const SlabSchedule schedule = build(s);
  constexpr int kSlabs = SlabSchedule::kSlabs;
  auto expectedBin = [&](int k) {
    const std::array<int, 2> b = s.bodies[size_t(k)];
    const int s0 = b[0] >= 0 ? schedule.slabOf(b[0]) : -1;
    const int s1 = b[1] >= 0 ? schedule.slabOf(b[1]) : -1;
    if (s0 < 0 || s1 < 0 || s0 == s1) return std::max(s0, s1);               // within a slab
    if (std::abs(s0 - s1) == 1 && std::min(s0, s1) % 2 == 0) return kSlabs;  // even seam
    if (std::abs(s0 - s1) == 1) return kSlabs + 1;                           // odd seam
    return kSlabs + 2;                                                       // the rest
  };
  auto seam = [&](int k) {
    return std::min(schedule.slabOf(s.bodies[size_t(k)][0]),
                    schedule.slabOf(s.bodies[size_t(k)][1]));
  };
  const std::vector<int>& order = schedule.order();
  ASSERT_EQ(order.size(), s.bodies.size());
  std::vector<int> sorted(order);
  std::sort(sorted.begin(), sorted.end());
  for (size_t k = 0; k < sorted.size(); ++k) ASSERT_EQ(sorted[k], int(k)) << "not a permutation";
  int serial = 0;
  for (size_t q = 0; q < order.size(); ++q) {
    const int k = order[q];
    serial += expectedBin(k) == kSlabs + 2;
    if (q == 0) continue;
    const int j = order[q - 1];
    const int bj = expectedBin(j), bk = expectedBin(k);
    ASSERT_LE(bj, bk) << "position " << q;
    if (bj != bk) continue;
    if (bk == kSlabs || bk == kSlabs + 1) {  // seams in order, the island's order within one
      ASSERT_LE(seam(j), seam(k));
      if (seam(j) == seam(k)) {
        ASSERT_LT(j, k);
      }
    } else {
      ASSERT_LT(j, k) << "the island's order within a bin";
    }
  }
  EXPECT_EQ(serial, schedule.serialItems());
  EXPECT_LT(serial, int(order.size()) / 20) << "far contacts are rare here";
  // Slabs along z (the widest spread), in order, of about equal numbers of contact ends.
  std::vector<int> ends(s.centres.size(), 0);
  for (const auto& b : s.bodies)
    for (int x : b)
      if (x >= 0) ++ends[size_t(x)];
  std::array<int, kSlabs> slabEnds{};
  int total = 0, most = 0;
  for (size_t b = 0; b < s.centres.size(); ++b) {
    if (ends[b] == 0) {
      EXPECT_EQ(schedule.slabOf(int(b)), -1);
      continue;
    }
    slabEnds[size_t(schedule.slabOf(int(b)))] += ends[b];
    total += ends[b];
    most = std::max(most, ends[b]);
    for (size_t c = 0; c < s.centres.size(); ++c) {
      if (ends[c] > 0 && s.centres[c].z() > s.centres[b].z()) {
        ASSERT_GE(schedule.slabOf(int(c)), schedule.slabOf(int(b)));
      }
    }
  }
  for (int e : slabEnds) EXPECT_NEAR(e, total / kSlabs, most + 1);
}

TEST(SlabSchedule, EmptyAndTinyIslands) {
  SlabSchedule schedule;
  schedule.build(
      0, 4,
      [](int) {
        return std::array<int, 2>{0, 1};
      },
      [](int) { return Eigen::Vector3f::Zero().eval(); });
  int visits = 0;
  schedule.run([&](int) { ++visits; });
  EXPECT_EQ(visits, 0);
  // One body, all its contacts static: one slab, the island's order.
  const std::vector<std::array<int, 2>> one{{0, -1}, {0, -1}, {-1, 0}};
  schedule.build(
      3, 1, [&](int k) { return one[size_t(k)]; }, [](int) { return Eigen::Vector3f(1, 2, 3); });
  std::vector<int> order;
  schedule.run([&](int k) { order.push_back(k); });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2}));
}

}  // namespace
}  // namespace sb
