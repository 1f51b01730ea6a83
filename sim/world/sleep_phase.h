// The Sleep phase (docs/design.md §3, §5.5): bodies at rest fall asleep, island by island, and
// whatever wakes one wakes its island.
//
// Each awake body counts how long every one of its particles has stayed within the distance its
// sleep speed (BodyModel::sleepSpeed, scaled to its size) carries it in kTimeToSleep of where it
// was when the count started (Jolt's test, on every particle rather than three points): where the
// particles go, not the velocities they carry, so a body ringing or rocking in place by less
// rests, and one crept along by position corrections does not. Bodies joined by a body–body
// contact this sub-step form an island; when every body of an island has been still for
// kTimeToSleep,
// the island falls asleep together: velocities zeroed, the island remembered, and from the next
// sub-step on its bodies skip every phase (they stay obstacles for awake bodies). Bodies held by
// a drag never sleep.
//
// Reads: x, models, the sub-step's touching pairs, which bodies are held. Writes: the sleep
// state (with each body's anchor positions, #P×3); v of the bodies that fall asleep.
#pragma once

#include <utility>
#include <vector>

#include "sim/world/body.h"

namespace sb {

// Seconds a body (and its whole island) must stay still: Box2D's and Jolt's 0.5 s.
inline constexpr double kTimeToSleep = 0.5;

struct SleepScratch {
  std::vector<int> parent;  // union-find over slots
  int nextIsland = 0;       // island ids handed out
};

// `awake`: the awake slots; `touching`: slot pairs that had a body–body contact this sub-step;
// `held`: per slot, 1 when a drag holds the body. With `enabled` false nothing runs (the clocks
// restart when it is turned on: World::setSettings wakes every body). Returns whether some body
// fell asleep.
bool runSleepPhase(double h, bool enabled, std::vector<BodySlot>& slots,
                   const std::vector<int>& awake, const std::vector<std::pair<int, int>>& touching,
                   const std::vector<char>& held, SleepScratch& scratch);

// Wakes the body in slot s and every body that fell asleep in the same island (`order`: every
// alive slot). Returns whether any body woke.
bool wakeIsland(std::vector<BodySlot>& slots, const std::vector<int>& order, int s);

}  // namespace sb
