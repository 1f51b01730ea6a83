// The order and the threads of a large island's Gauss–Seidel sweeps (docs/design.md §5.5).
//
// A contact visit reads and writes only its two bodies (and itself), so visits that share no
// movable body give the same results in either order, or at once. The island's bodies are cut
// into kSlabs slabs along the axis their centres spread most on, each slab holding about the
// same number of contact ends, and the contacts are swept in bins:
//   1. the contacts within slab 0, within slab 1, …, within the last slab;
//   2. the contacts between slabs 0 and 1, 2 and 3, … (even seams);
//   3. the contacts between slabs 1 and 2, 3 and 4, … (odd seams);
//   4. the rest (contacts of bodies two or more slabs apart), one after another.
// Within a bin, contacts keep the island's order. The bins of each of the first three groups
// share no movable body, so they run at once on however many threads there are, and every body
// sees its visits in the same order: the same bits for any thread count. The cut depends only
// on the island, never on the thread count.
//
// This order differs from the island's plain contact order, so it is used only for islands of
// at least kMinParallelSweep contacts (piles such as seed-scale.json); smaller islands keep the
// plain order and one thread. It replaced a schedule that kept the plain order and ran its
// levels of independent contacts in parallel: ~60 levels per sweep in the seed-scale pile, a
// fork each, and its velocity sweeps took 1.14× less time on two threads than on one; here
// four forks per sweep, 1.5× (docs/design.md §5.5).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <limits>
#include <vector>

#include "sim/base/parallel_for.h"

namespace sb {

class SlabSchedule {
 public:
  static constexpr int kSlabs = 8;

  // Items [0, count) in the island's order; bodiesOf(k) gives the two bodies item k writes, as
  // std::array<int, 2> of indices in [0, bodyCount) or −1 (none: a static collider, or a body
  // that only reads); centreOf(b) a body's centre (m, Eigen::Vector3f), asked only for bodies
  // some item writes.
  template <typename BodiesOf, typename CentreOf>
  void build(int count, int bodyCount, const BodiesOf& bodiesOf, const CentreOf& centreOf);

  // Calls visit(k) for every item k, bin by bin as above, the bins of a group at once. Each
  // group is cut into one run of neighbouring bins per thread, of about equal item counts, the
  // same every sweep, so a slab's bodies stay in one core's cache.
  template <typename Visit>
  void run(const Visit& visit) const;

  // The items in sweep order; the slab of body b (−1: written by no item); the items of the
  // last, one-thread group.
  const std::vector<int>& order() const { return order_; }
  int slabOf(int body) const { return slab_[size_t(body)]; }
  int serialItems() const { return binStart_[kBins] - binStart_[kBins - 1]; }

 private:
  static constexpr int kEvenSeams = kSlabs / 2, kOddSeams = (kSlabs - 1) / 2;
  static constexpr int kBins = kSlabs + kEvenSeams + kOddSeams + 1;
  std::vector<int> order_;
  std::array<int, kBins + 1> binStart_{};  // bin b is order_[binStart_[b], binStart_[b + 1])
  std::vector<int> slab_;                  // per body
};

template <typename BodiesOf, typename CentreOf>
void SlabSchedule::build(int count, int bodyCount, const BodiesOf& bodiesOf,
                         const CentreOf& centreOf) {
  // The bodies written, with their numbers of contact ends, and the axis their centres spread
  // most on.
  std::vector<int> ends(static_cast<size_t>(bodyCount), 0);
  std::vector<int> written;
  for (int k = 0; k < count; ++k)
    for (int b : bodiesOf(k))
      if (b >= 0 && ends[size_t(b)]++ == 0) written.push_back(b);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f hi = -lo;
  for (int b : written) {
    lo = lo.cwiseMin(centreOf(b));
    hi = hi.cwiseMax(centreOf(b));
  }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  // Slabs of about equal numbers of contact ends (a pile's bottom bodies have more contacts
  // than its top ones; cut by body count, one thread's slabs took 20 % longer than the other's),
  // by centre along the axis, ties by index.
  std::sort(written.begin(), written.end(), [&](int a, int b) {
    const float ca = centreOf(a)[axis], cb = centreOf(b)[axis];
    return ca != cb ? ca < cb : a < b;
  });
  slab_.assign(size_t(bodyCount), -1);
  long long total = 0, before = 0;
  for (int b : written) total += ends[size_t(b)];
  for (int b : written) {
    slab_[size_t(b)] = pieceHoldingMiddle(before, ends[size_t(b)], total, kSlabs);
    before += ends[size_t(b)];
  }

  auto binOf = [&](int k) {
    const std::array<int, 2> b = bodiesOf(k);
    const int s0 = b[0] >= 0 ? slab_[size_t(b[0])] : -1;
    const int s1 = b[1] >= 0 ? slab_[size_t(b[1])] : -1;
    if (s0 < 0 && s1 < 0) return kBins - 1;
    if (s0 < 0 || s1 < 0 || s0 == s1) return std::max(s0, s1);
    const int seam = std::min(s0, s1);
    if (std::max(s0, s1) != seam + 1) return kBins - 1;
    return seam % 2 == 0 ? kSlabs + seam / 2 : kSlabs + kEvenSeams + seam / 2;
  };
  // A counting sort by bin keeps the island's order within a bin.
  std::vector<int> bins(static_cast<size_t>(count));
  binStart_.fill(0);
  for (int k = 0; k < count; ++k) {
    bins[size_t(k)] = binOf(k);
    ++binStart_[size_t(bins[size_t(k)]) + 1];
  }
  for (int b = 0; b < kBins; ++b) binStart_[size_t(b) + 1] += binStart_[size_t(b)];
  std::array<int, kBins> fill;
  std::copy(binStart_.begin(), binStart_.end() - 1, fill.begin());
  order_.resize(size_t(count));
  for (int k = 0; k < count; ++k) order_[size_t(fill[size_t(bins[size_t(k)])]++)] = k;
}

template <typename Visit>
void SlabSchedule::run(const Visit& visit) const {
  auto runBins = [&](int first, int last) {
    for (int q = binStart_[size_t(first)]; q < binStart_[size_t(last)]; ++q)
      visit(order_[size_t(q)]);
  };
  const int threads = threadCount();
  auto runGroup = [&](int first, int last) {
    const long long items = binStart_[size_t(last)] - binStart_[size_t(first)];
    if (threads < 2 || last - first < 2 || items == 0) {
      runBins(first, last);
      return;
    }
    parallelRanges(threads, 2, threads, [&](int c0, int c1) {
      for (int b = first; b < last; ++b) {
        // Bin b goes to the thread whose share of the group's items holds its middle.
        const int piece =
            pieceHoldingMiddle(binStart_[size_t(b)] - binStart_[size_t(first)],
                               binStart_[size_t(b) + 1] - binStart_[size_t(b)], items, threads);
        if (piece >= c0 && piece < c1) runBins(b, b + 1);
      }
    });
  };
  runGroup(0, kSlabs);
  runGroup(kSlabs, kSlabs + kEvenSeams);
  runGroup(kSlabs + kEvenSeams, kBins - 1);
  runBins(kBins - 1, kBins);
}

}  // namespace sb
