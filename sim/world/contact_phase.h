// The Contacts and Solve phases (docs/design.md §3, §5.5): particles kept out of the other
// bodies' closed surfaces (body–body contact) and out of the static colliders, with Coulomb
// friction and restitution.
//
// Contacts — detection, per sub-step: bounds and speeds of every body; sweep-and-prune over
//   grown boxes; per obstacle a surface grid over where its probes are (kept while the surface
//   drifts less than a quarter spacing); narrow phase per pair in parallel, with a whole-surface
//   search for deep particles every few sub-steps (every sub-step for pairs that found some);
//   every particle near a static collider. Sleeping bodies are obstacles only: pairs of two
//   sleeping bodies are skipped, and a sleeping body an awake one touches is asked to wake.
//   Reads: x, v, models, settings, colliders, sleep state. Writes: the scratch only.
// Solve — every contact of the sub-step, body–body and static, in one solve (contact_solver.h),
//   per island of touching bodies (islands share no body, so they run in parallel, each in a
//   fixed order: the result does not depend on the thread count); the impulses warm start the
//   next sub-step. Sleeping bodies do not move. Then the impacts of pairs with a soft body
//   (soft_impact.h), which are kept from sub-step to sub-step like the impulses.
//   Reads: x, v, models, params (α, restitution), settings, colliders. Writes: x, v.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "sim/world/body.h"
#include "sim/world/collider.h"
#include "sim/world/contact/body_contact.h"
#include "sim/world/contact/contact_solver.h"
#include "sim/world/contact/soft_impact.h"
#include "sim/world/contact/surface_grid.h"
#include "sim/world/mass_properties.h"
#include "sim/world/work_layout.h"

namespace sb {

struct ContactSettings {
  bool bodyContact = true;
  float friction = 0.5f;              // μ between bodies
  float restitutionThreshold = 1.0f;  // m/s: slower approaches do not bounce
  float rollingResistance = 0.0f;     // dimensionless, WorldSettings::rollingResistance
  Vec3 gravity = Vec3::Zero();        // m/s² (the order of shock propagation)
};

// Per-body data of the contact phases, derived from the positions every sub-step (indexed by
// slot), and the scratch of the phases, kept between sub-steps so they do not allocate; the
// impulses of the last sub-step are kept to warm start the next (cleared when bodies change).
struct ContactScratch {
  // A particle near a static collider.
  struct StaticHit {
    int particle, collider;
    float distance;  // signed, metres
    Vec3f normal;    // out of the collider
  };
  struct Body {
    Eigen::AlignedBox3f box;             // particles' bounding box
    float maxSpeed = 0;                  // m/s
    Vec3f meanVelocity = Vec3f::Zero();  // m/s, of the centre of mass
    float maxRelativeSpeed = 0;          // m/s, fastest particle relative to the centre of mass
    // The box and speeds were taken while the body slept: they hold until it wakes (a sleeping
    // body does not move), so a resting scene does not sweep its particles every sub-step.
    bool boundsWhileAsleep = false;
    bool obstacle = false;       // has a surface and meets some other body this sub-step
    Eigen::AlignedBox3f region;  // obstacles: bounding box of the probes that meet it
    bool involved = false;       // meets some other body this sub-step
    SurfaceGrid grid;
    ContactGeometry geometry;  // set up for involved bodies
    // The grid's surface positions and region when it was built, and whose it is (a slot can
    // be reused by another body).
    MatX3f gridPositions;
    Eigen::AlignedBox3f gridRegion;
    const BodyModel* gridModel = nullptr;
    long long gridBuiltAt = 0;  // the sub-step (ContactScratch::substeps) it was built at
    std::vector<StaticHit> staticHits;
    std::vector<int> nearColliders;  // the colliders its particles are tested against, ascending
    // Where the body-body detection sees a sleeping body: moved by what gravity moves an awake
    // body in the sub-step's prediction (h²·g), with the velocity h·g that reaches it. An awake
    // body's particles are detected at their predicted positions; a sleeping body does not
    // move. Compared as they are, a body resting on a sleeping one was seen h²·g below its rest
    // (9.8 m at 1-s sub-steps), beside or under its neighbour, and held there by the contacts
    // made from it: piles sank step by step whenever one group fell asleep. In this frame the
    // two stand as they rest. Contact distances are carried back to the actual positions, which
    // the solver starts from: the same plane, so the constraint is unchanged but well chosen.
    Vec3f frameShift = Vec3f::Zero();  // metres; zero for awake bodies
    MatX3f detectX, detectV;           // #P × 3, metres and m/s: sleeping involved bodies only
  };
  // A probe body whose particles are tested against an obstacle body's surface (slots).
  struct Pair {
    int probe, obstacle;
  };
  // The impulses of one contact, by (probe slot, obstacle slot or −1 − collider, particle).
  struct Warm {
    std::array<int, 3> key;
    float lambda[2];
    Vec3f tangent[2];
    bool resting;        // ContactPoint::resting when these impulses were found
    float distance0;     // ContactPoint::distance0 then (m)
    int steadySubsteps;  // ContactPoint::steadySubsteps then
  };
  std::vector<Body> bodies;  // per slot
  std::vector<Pair> pairs;
  std::vector<std::vector<Contact>> pairContacts;  // per pair
  std::vector<int> pairVisitOrder;  // pair indices, the narrow phase's order (by obstacle)
  std::vector<int> obstacleVisits;  // where each obstacle's run in pairVisitOrder starts, + end
  std::vector<char> pairDeep;       // per pair: found deep particles
  std::vector<long> pairTests;      // per pair: point–triangle tests made
  // What each pair's look-ups learned (ProbeClearance), kept while the obstacle's grid is: per
  // pair during a sub-step, then sorted by (probe, obstacle) slots for the next one.
  struct PairClearance {
    std::pair<int, int> key;    // (probe, obstacle) slots
    long long gridBuiltAt = 0;  // the obstacle's grid it holds for (Body::gridBuiltAt)
    ProbeClearance probe;
  };
  std::vector<PairClearance> clearances, clearancesNext;
  // This sub-step's body–body narrow phase: point–triangle tests made, and the tests a pass of
  // every probe particle over every obstacle triangle would make (Σ over the pairs looked at).
  long triangleTests = 0, triangleTestsOfAllPairs = 0;
  // Visits of the velocity sweeps in the last solve, and those skipped as idle
  // (ContactPoint::idleSlack).
  long sweepVisits = 0, skippedVisits = 0;
  // Bodies in sweep order, grown boxes and creation rank per slot, obstacle slots.
  std::vector<int> sweep, rank;
  std::vector<Eigen::AlignedBox3f> boxes;
  // Deep search: sub-steps counted, and the (probe, obstacle) slot pairs that found deep
  // particles at the last sub-step (sorted).
  long long substeps = 0;
  std::vector<std::pair<int, int>> deepPairs;
  // Sleeping slots an awake body touched (the World wakes their islands).
  std::vector<int> wake;

  // The solve: bodies by solver index and their slots, every contact point, islands.
  std::vector<SolverBody> solverBodies;
  std::vector<int> solverIndex, solverSlot;  // per slot (−1: not in the solve), per solver body
  std::vector<ContactPoint> points;
  std::vector<int> islandParent;                             // union-find over solver bodies
  std::vector<std::vector<int>> islandBodies, islandPoints;  // per island
  std::vector<Warm> warm, warmNext;                          // sorted by key
  // After the solve: slot pairs joined by a body–body contact this sub-step (for the sleep
  // islands), the number of body–body contacts that carried load, and the deepest of all
  // load-carrying contacts (body and collider) when they were detected, before the solve pushed
  // them out (m, ≥ 0).
  std::vector<std::pair<int, int>> touching;
  int activeContacts = 0;
  float deepestContact = 0;

  // Restitution of pairs that involve a soft body (soft_impact.h): the pairs touching this
  // sub-step, keyed as SoftImpact::key, and the impacts in progress (both sorted by key).
  struct SoftPair {
    std::array<int, 2> key;
    Vec3f normal;       // sum of the contacts' normals, from b toward a
    float restitution;  // e, the largest of the two sides'
    bool meets;         // some particle is inside after the integration: the surfaces meet
    float before;       // relative normal velocity of the centres before the solve, m/s
    Vec3f impulse;      // N·s: what the pair's contacts gave a in the solve (b: the opposite)
  };
  std::vector<SoftPair> softPairs;
  std::vector<SoftImpact> impacts, impactsNext;
  // Per solver body while the impacts run: centre velocity, velocity change, shift, and
  // whether the centre velocity is known.
  std::vector<Vec3f> impactVelocity, impactChange, impactShift;
  std::vector<char> impactKnown;
  std::vector<int> impactPairCount;  // per slot: touching soft pairs this sub-step

  // Rolling resistance (rolling_resistance.h): the pairs that touched, as (solver body, solver
  // body or −1 − collider) with their normal impulse (N·s), sorted; per solver body its rigid
  // motion from the velocities after the solve, and whether it takes couples.
  struct RollingPair {
    std::pair<int, int> key;
    float load;
  };
  std::vector<RollingPair> rollingPairs;
  std::vector<RigidMotion> rollingMotion;
  std::vector<Vec3> rollingSpinChange;  // rad/s, per solver body
  std::vector<char> rollingTurns;

  // What is kept between sub-steps and keyed by slot (warm starts, impacts): forgotten when
  // bodies are added, removed or reset, since a reused slot is another body.
  void forgetBodies() {
    warm.clear();
    impacts.clear();
    for (Body& b : bodies) b.boundsWhileAsleep = false;
  }
};

// Detection. `order`: every alive slot in creation order; sleeping bodies have
// slot.sleep.asleep set.
void runContactsPhase(const WorkLayout& layout, const ContactSettings& settings, double h,
                      std::vector<BodySlot>& slots, const std::vector<int>& order,
                      const std::vector<Collider>& colliders, ContactScratch& scratch);

// The solve of what runContactsPhase found; returns the number of body–body contacts that
// carried load.
int runSolvePhase(const WorkLayout& layout, const ContactSettings& settings, double h,
                  std::vector<BodySlot>& slots, const std::vector<int>& order,
                  const std::vector<Collider>& colliders, ContactScratch& scratch);

}  // namespace sb
