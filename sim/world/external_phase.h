// The External phase (docs/design.md §3): forces queued for this step and drag constraints
// change velocities.
//
// Reads: the queued forces, the drags, x, v, masses. Writes: v.
#pragma once

#include <map>
#include <vector>

#include "sim/world/body.h"
#include "sim/world/world.h"

namespace sb {

// A force on one particle for the next step only (World::addForce).
struct QueuedForce {
  BodyHandle body;
  int particle;
  Vec3 force;  // N
};

// Every force and drag refers to a live body (the World drops them with their body).
void runExternalPhase(const std::vector<QueuedForce>& forces, const std::map<int, DragDef>& drags,
                      double h, std::vector<BodySlot>& slots);

}  // namespace sb
