// The phases of one World sub-step, in the order they run, and the time spent in each.
//
// Every consumer (the run command, the viewer's panel and stats, the benchmarks) loops over
// kPhases and prints phaseName(): adding a phase here is the only change they need.
// What each phase reads and writes: docs/design.md §3.
#pragma once

#include <array>
#include <cstddef>

namespace sb {

enum class Phase : int {
  External,    // drags and queued forces change velocities
  Predict,     // x̂ = x + h·v + h²·gravity (the body's turn as a rotation)
  Goals,       // per cluster: centre of mass, moments, rotation, goal transform (fitted to x̂)
  Plasticity,  // per cluster: plastic flow of the rest shape (measured inside Goals)
  Project,     // per particle: α of the way to the blend of its clusters' goals
  WholeBody,   // bodies with several clusters: the whole-body level's fit and projection
  Velocities,  // v from the positions' change; the body's spin kept
  Contacts,    // contact detection: bounds, broad phase, grids, narrow phase, static colliders
  Solve,       // the contact solve: body–body and static contacts together, per island
  Damping,     // velocities relative to each body's rigid motion damped
  Check,       // NaN/Inf detection and reset
  Sleep,       // bodies at rest fall asleep, island by island
};

inline constexpr int kPhaseCount = 12;
inline constexpr std::array<Phase, kPhaseCount> kPhases = {
    Phase::External, Phase::Predict,   Phase::Goals,      Phase::Plasticity,
    Phase::Project,  Phase::WholeBody, Phase::Velocities, Phase::Contacts,
    Phase::Solve,    Phase::Damping,   Phase::Check,      Phase::Sleep,
};

// Lower-case name ("goals"), used as label and as key in files.
const char* phaseName(Phase phase);

// Wall-clock seconds spent in each phase, accumulated over the sub-steps of World::step.
struct StepProfile {
  std::array<double, kPhaseCount> seconds{};

  double& operator[](Phase p) { return seconds[std::size_t(p)]; }
  double operator[](Phase p) const { return seconds[std::size_t(p)]; }
  double total() const {
    double sum = 0;
    for (double s : seconds) sum += s;
    return sum;
  }
  StepProfile& operator+=(const StepProfile& o) {
    for (int i = 0; i < kPhaseCount; ++i) seconds[std::size_t(i)] += o.seconds[std::size_t(i)];
    return *this;
  }
};

}  // namespace sb
