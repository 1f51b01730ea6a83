// Thread count of the simulation library and the cage binder, and the worker pool under
// parallelFor (sim/base/parallel_for.h).
//
// Threading policy: one pool of threadCount() − 1 workers plus the calling thread. A parallel
// loop is cut into one fixed piece per thread; workers that find no work spin only briefly
// (kSpinMicroseconds) and then sleep on a condition variable, and the caller does the same while
// it waits for the others. So with more busy processes than cores a descheduled worker costs a
// short wait, not a whole time slice of spinning threads (OpenMP's active waiting made a loaded
// two-core machine 17× slower at two threads than at one); unloaded, a worker woken within the
// spin window starts at once. Plain std::thread, mutex, condition variable and atomics: what
// ThreadSanitizer understands.
#pragma once

namespace sb {

// Threads used by the simulation and the cage binder (≥ 1); 0 restores the default (all cores).
// Call it while no parallel loop runs (between steps).
void setThreadCount(int threads);
int threadCount();

namespace detail {
// Runs fn(ctx, c) for every c in [0, chunks), chunk c on participant c (the caller is 0), and
// returns when all are done. chunks ≤ threadCount(). Runs them one after another on the caller
// when called from inside a parallel loop or while another thread uses the pool.
void runChunks(int chunks, void (*fn)(void*, int), void* ctx);
}  // namespace detail

}  // namespace sb
