// A Gauss–Seidel sweep over an island's contacts on several threads, with the results of the
// one-thread sweep bit for bit (docs/design.md §5.5).
//
// A contact visit reads and writes only its two bodies (and itself). So two visits that share no
// body give the same results in either order, and the sweep's result only depends on the order
// of the visits of each body. The schedule cuts the sweep into tasks (runs of consecutive
// contacts between the same bodies) and gives each task a level one above the last earlier task
// that shares a body with it. The tasks of one level then share no body, so they may run at once
// in any split between threads, and running the levels in order keeps every body's visits in
// sweep order. (A colouring of the contacts would also run in parallel, but in another order:
// other results, and a stack's behaviour retuned. This keeps every result, hash and test.)
//
// The seed-scale pile is one island (~16,000 contacts, ~1,900 tasks, ~60 levels per sweep):
// without this its contact solve could not use the second thread at all.
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "sim/base/parallel_for.h"

namespace sb {

class SweepSchedule {
 public:
  // Items [0, count) in sweep order; bodiesOf(k) gives the two bodies item k writes, as
  // std::array<int, 2> of indices in [0, bodyCount) or −1 (none: a static collider, or a body
  // that only reads). Parts each level into `threads` pieces of about equal item counts.
  template <typename BodiesOf>
  void build(int count, int bodyCount, int threads, const BodiesOf& bodiesOf);

  // Calls visit(k) for every item: level by level, the tasks of a level split between the
  // threads, each task's items in order.
  template <typename Visit>
  void run(const Visit& visit) const;

  int levels() const { return int(levelStart_.size()) - 1; }
  int tasks() const { return int(taskStart_.size()) - 1; }

 private:
  int threads_ = 1;
  std::vector<int> taskStart_;   // task t is items [taskStart_[t], taskStart_[t + 1])
  std::vector<int> byLevel_;     // task indices grouped by level, in sweep order within a level
  std::vector<int> levelStart_;  // level l is byLevel_[levelStart_[l], levelStart_[l + 1])
  // Level l's piece c is byLevel_[pieces_[l·(threads + 1) + c], pieces_[l·(threads + 1) + c + 1]).
  std::vector<int> pieces_;
  std::vector<int> scratch_;  // per body: the lowest level a new task of it may take
};

template <typename BodiesOf>
void SweepSchedule::build(int count, int bodyCount, int threads, const BodiesOf& bodiesOf) {
  threads_ = std::max(1, threads);
  taskStart_.clear();
  std::vector<int> taskLevel;
  std::vector<int>& after = scratch_;  // per body: the lowest level a new task of it may take
  after.assign(size_t(bodyCount), 0);
  int levels = 0;
  std::array<int, 2> last{-2, -2};
  for (int k = 0; k < count; ++k) {
    const std::array<int, 2> b = bodiesOf(k);
    if (k > 0 && b == last) continue;  // same bodies: the same task
    last = b;
    int level = 0;
    for (int s : b)
      if (s >= 0) level = std::max(level, after[size_t(s)]);
    for (int s : b)
      if (s >= 0) after[size_t(s)] = level + 1;
    taskStart_.push_back(k);
    taskLevel.push_back(level);
    levels = std::max(levels, level + 1);
  }
  taskStart_.push_back(count);
  // Group by level (a counting sort keeps sweep order within a level).
  levelStart_.assign(size_t(levels) + 1, 0);
  for (int l : taskLevel) ++levelStart_[size_t(l) + 1];
  for (int l = 0; l < levels; ++l) levelStart_[size_t(l) + 1] += levelStart_[size_t(l)];
  byLevel_.resize(taskLevel.size());
  std::vector<int> fill(levelStart_.begin(), levelStart_.end() - 1);
  for (int t = 0; t < int(taskLevel.size()); ++t)
    byLevel_[size_t(fill[size_t(taskLevel[size_t(t)])]++)] = t;
  // Pieces of about equal item counts.
  pieces_.resize(size_t(levels) * size_t(threads_ + 1));
  for (int l = 0; l < levels; ++l) {
    const int begin = levelStart_[size_t(l)], end = levelStart_[size_t(l) + 1];
    long long items = 0;
    for (int i = begin; i < end; ++i)
      items +=
          taskStart_[size_t(byLevel_[size_t(i)]) + 1] - taskStart_[size_t(byLevel_[size_t(i)])];
    int* piece = &pieces_[size_t(l) * size_t(threads_ + 1)];
    piece[0] = begin;
    long long done = 0;
    int i = begin;
    for (int c = 1; c < threads_; ++c) {
      while (i < end && done * threads_ < items * c) {
        done +=
            taskStart_[size_t(byLevel_[size_t(i)]) + 1] - taskStart_[size_t(byLevel_[size_t(i)])];
        ++i;
      }
      piece[c] = i;
    }
    piece[threads_] = end;
  }
}

template <typename Visit>
void SweepSchedule::run(const Visit& visit) const {
  auto runTasks = [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const int t = byLevel_[size_t(i)];
      for (int k = taskStart_[size_t(t)]; k < taskStart_[size_t(t) + 1]; ++k) visit(k);
    }
  };
  for (int l = 0; l < levels(); ++l) {
    const int* piece = &pieces_[size_t(l) * size_t(threads_ + 1)];
    if (threads_ == 1 || levelStart_[size_t(l) + 1] - levelStart_[size_t(l)] < 2) {
      runTasks(piece[0], piece[threads_]);
      continue;
    }
    parallelRanges(threads_, 2, threads_, [&](int c0, int c1) {
      for (int c = c0; c < c1; ++c) runTasks(piece[c], piece[c + 1]);
    });
  }
}

}  // namespace sb
