// The Integrate and Damping phases (docs/design.md §3).
//
// Integrate — per particle: blend the goals of its clusters (summed once per particle group),
//   then Müller's update v += α(g − x)/h + h·gravity, x += h·v (stable for every h when α ≤ 1);
//   pinned particles are put back at their start positions.
//   Reads:  every body's ClusterState goals, model, α; gravity. Writes: x, v; bad[slot] = 1 for
//   bodies whose particles became NaN/Inf.
// Damping — per body with damping > 0: v ← v + kd·(v_rigid − v), v_rigid the rigid motion with
//   the body's linear and angular momentum.
//   Reads: x, v, masses. Writes: v.
#pragma once

#include <vector>

#include "sim/base/types.h"
#include "sim/world/body.h"
#include "sim/world/work_layout.h"

namespace sb {

void runIntegratePhase(const WorkLayout& layout, const Vec3& gravity, double h,
                       std::vector<BodySlot>& slots, const std::vector<int>& order,
                       std::vector<char>& blockBad, std::vector<char>& bad);

void runDampingPhase(const WorkLayout& layout, std::vector<BodySlot>& slots,
                     const std::vector<int>& order);

}  // namespace sb
