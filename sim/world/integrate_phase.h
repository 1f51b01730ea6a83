// The motion phases of a sub-step (docs/design.md §3, §5.3): a position-based step.
//
// Predict     x̂ = x + h·v + h²·gravity, the body's rigid turn advanced as a rotation (not along
//             its tangent, which would stretch a turning body by √(1 + (hω)²)); v̂ = v turned with
//             the body. Reads x, v, masses. Writes x (= x̂), spin; xPred and vPred for bodies
//             with several clusters, the turn that forms v̂ for the others (no copies there).
// Project     per particle x ← x̂ + α(ḡ − x̂), ḡ the blend of its clusters' goals (fitted to x̂ by
//             the Goals phase; summed once per particle group). Reads goals. Writes x; bad. For a
//             body with one cluster (nothing moves it between here and Velocities) also v as
//             Velocities forms it, in the same sweep (v̂ formed from v): reads v, the turn,
//             gravity too, writes v and (no pins) the sums of the body's new rigid motion.
// WholeBody   bodies with several clusters: one cluster over the whole body, fitted to x and
//             projected with the body's α, β and mode (cluster_state.h). Writes x; bad.
// Velocities  v = v̂ + (x − x̂)/h + h·gravity (bodies with one cluster: formed by Project), then
//             the body's spin as it was before the sub-step (bodies with one cluster and no pins:
//             from the rigid motion Project summed). Reads x, xPred, vPred, spin. Writes v.
// Damping     per body with damping > 0: v ← v + kd·(v_rigid − v), v_rigid the rigid motion
//             with the body's momenta (pinned particles immovable). Reads x, v. Writes v.
// Pinned particles are put back at their start after every phase that moves positions.
//
// For one particle and a fixed goal the step maps (y = x − g, v) by [[1−α, (1−α)h], [−α/h, 1−α]]:
// |eigenvalues|² = 1 − α for every h, so it is stable at any time step and dissipates the
// deformation it corrects (α = 1: onto the goal in one sub-step).
#pragma once

#include <vector>

#include "sim/base/types.h"
#include "sim/world/body.h"
#include "sim/world/work_layout.h"

namespace sb {

void runPredictPhase(const WorkLayout& layout, const Vec3& gravity, double h,
                     std::vector<BodySlot>& slots, const std::vector<int>& order);

void runProjectPhase(const WorkLayout& layout, const Vec3& gravity, double h,
                     std::vector<BodySlot>& slots, const std::vector<int>& order,
                     std::vector<char>& blockBad, std::vector<char>& bad);

void runWholeBodyPhase(const WorkLayout& layout, std::vector<BodySlot>& slots,
                       const std::vector<int>& order, std::vector<char>& bad);

void runVelocitiesPhase(const WorkLayout& layout, const Vec3& gravity, double h,
                        std::vector<BodySlot>& slots, const std::vector<int>& order);

void runDampingPhase(const WorkLayout& layout, std::vector<BodySlot>& slots,
                     const std::vector<int>& order);

}  // namespace sb
