// Parallel loops for the simulation. Work is always split into the same fixed pieces whatever
// the thread count, and every sum is formed in a fixed order, so results are bit-identical for
// any number of threads.
#pragma once

namespace sb {

// Threads used by the simulation and the cage binder (≥ 1); 0 restores the default (all cores).
void setThreadCount(int threads);
int threadCount();

// Calls body(i) for i in [0, count). Runs serially when count is below minParallel.
template <typename Body>
void parallelFor(int count, int minParallel, const Body& body) {
#pragma omp parallel for schedule(static) if (count >= minParallel)
  for (int i = 0; i < count; ++i) body(i);
}

}  // namespace sb
