// Thread count of the simulation library (OpenMP underneath).
#pragma once

namespace sb {

// Threads used by the simulation and the cage binder (≥ 1); 0 restores the default (all cores).
void setThreadCount(int threads);
int threadCount();

}  // namespace sb
