// The Contacts and Collide phases (docs/design.md §3): particles kept out of the other bodies'
// closed surfaces (body–body contact) and out of the static colliders, with Coulomb friction.
// A contact acts partly on a body's rigid motion (see contact/body_contact.h).
//
// Contacts — per sub-step: bounds and speeds of every body; sweep-and-prune over grown boxes;
//   per obstacle a surface grid over where its probes are (kept while the surface drifts less
//   than a quarter spacing); narrow phase per pair in parallel; resolution in pair order
//   (Gauss–Seidel), so the result does not depend on the thread count.
//   Reads: x, v, models, params (α), settings (bodyContact, contactFriction). Writes: x, v.
// Collide — per body, its particles inside a static collider are pushed out and their
//   approaching velocity removed, with friction; bodies are independent.
//   Reads: x, v, models, params, colliders. Writes: x, v.
#pragma once

#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "sim/world/body.h"
#include "sim/world/collider.h"
#include "sim/world/contact/body_contact.h"
#include "sim/world/contact/surface_grid.h"
#include "sim/world/work_layout.h"

namespace sb {

// Per-body data of the contact phases, derived from the positions every sub-step (indexed by
// slot), and the scratch lists of the phase, kept between sub-steps so they do not allocate.
struct ContactScratch {
  struct Body {
    Eigen::AlignedBox3f box;             // particles' bounding box
    float maxSpeed = 0;                  // m/s
    Vec3f meanVelocity = Vec3f::Zero();  // m/s, of the centre of mass
    float maxRelativeSpeed = 0;          // m/s, fastest particle relative to the centre of mass
    bool obstacle = false;               // has a surface and meets some other body this sub-step
    Eigen::AlignedBox3f region;          // obstacles: bounding box of the probes that meet it
    bool involved = false;               // meets some other body this sub-step
    SurfaceGrid grid;
    ContactBody view;  // set up by prepareContactBody for involved bodies
    // The grid's surface positions and region when it was built, and whose it is (a slot can
    // be reused by another body).
    MatX3f gridPositions;
    Eigen::AlignedBox3f gridRegion;
    const BodyModel* gridModel = nullptr;
    std::vector<std::pair<int, int>> staticContacts;  // (particle, collider) inside a collider
  };
  // A probe body whose particles are tested against an obstacle body's surface (slots).
  struct Pair {
    int probe, obstacle;
  };
  std::vector<Body> bodies;  // per slot
  std::vector<Pair> pairs;
  std::vector<std::vector<Contact>> pairContacts;  // per pair
  // Bodies in sweep order, grown boxes and creation rank per slot, obstacle and involved slots.
  std::vector<int> sweep, rank, obstacles, involved;
  std::vector<Eigen::AlignedBox3f> boxes;
};

struct ContactSettings {
  bool bodyContact = true;
  float friction = 0.5f;  // μ between bodies
};

// Returns the number of body–body contacts resolved.
int runContactsPhase(const WorkLayout& layout, const ContactSettings& settings, double h,
                     std::vector<BodySlot>& slots, const std::vector<int>& order,
                     ContactScratch& scratch);

void runCollidePhase(const WorkLayout& layout, const std::vector<Collider>& colliders,
                     std::vector<BodySlot>& slots, const std::vector<int>& order,
                     ContactScratch& scratch);

}  // namespace sb
