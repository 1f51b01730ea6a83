// Parallel loop for the simulation's own .cpp files (needs OpenMP; not a public header).
// Work is always split into the same fixed pieces whatever the thread count, and every sum is
// formed in a fixed order by the callers, so results are bit-identical for any thread count.
#pragma once

namespace sb {

// Calls body(i) for i in [0, count). Runs serially when count is below minParallel.
template <typename Body>
void parallelFor(int count, int minParallel, const Body& body) {
#pragma omp parallel for schedule(static) if (count >= minParallel)
  for (int i = 0; i < count; ++i) body(i);
}

}  // namespace sb
