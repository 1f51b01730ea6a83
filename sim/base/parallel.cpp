#include "sim/base/parallel.h"

#include <omp.h>

namespace sb {

namespace {
int defaultThreads() {
  return omp_get_num_procs();
}
}  // namespace

void setThreadCount(int threads) {
  omp_set_num_threads(threads > 0 ? threads : defaultThreads());
}

int threadCount() {
  return omp_get_max_threads();
}

}  // namespace sb
