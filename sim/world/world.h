// The World owns every particle, body, cluster and collider and advances them in time.
//
// One step runs the phases of step_phases.h in a fixed order, each in its own file with what it
// reads and writes (docs/design.md §3):
//   External    drag constraints and queued forces change velocities      (external_phase.h)
//   Predict     x̂ = x + h·v + h²·gravity, the body's turn as a rotation   (integrate_phase.h)
//   Goals       per cluster, fitted to x̂: centre of mass, moments, rotation, goal (goals_phase.h)
//   Plasticity  plastic flow of the rest shape (plastic bodies only)
//   Project     per particle: x ← x̂ + α(ḡ − x̂), ḡ the blend of its clusters' goals
//   WholeBody   bodies with several clusters: one cluster over the whole body, projected the
//               same way, so the material does not depend on the number of clusters
//   Velocities  v = v̂ + (x − x̂)/h + h·gravity, the body's spin kept
//   Contacts    contact detection: particles near other bodies' surfaces and near the static
//               colliders                                                  (contact_phase.h)
//   Solve       every contact in one solve: no penetration, Coulomb friction, restitution
//   Damping     damp velocity relative to each body's rigid motion
//   Check       bodies with NaN/Inf are reset to their start and reported as events
//   Sleep       bodies at rest fall asleep, island by island                (sleep_phase.h)
// The step is position-based and stable at any time step (for α ≤ 1 it maps a deformation to
// at most √(1 − α) of itself per sub-step); rigid mode with α = 1 keeps the shape exactly. A
// body's α, β and damping are stated for a 1/240 s sub-step and converted to the one the step
// runs (substep_material.h): the material does not change with the time step.
// Results depend only on the input and never on the thread count: every sum is formed in a
// fixed order over fixed-size blocks. Accepted parameter ranges: param_ranges.h.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/base/types.h"
#include "sim/world/body_def.h"
#include "sim/world/collider.h"
#include "sim/world/step_phases.h"

namespace sb {

struct WorldSettings {
  Vec3 gravity = Vec3(0.0, -9.81, 0.0);  // m/s²
  double timeStep = 1.0 / 60.0;          // seconds advanced by step(), [1e-7, 10]
  int substeps = 1;                      // sub-steps per step(), 1 … 1000
  // Longest sub-step, seconds, [1e-4, 1]: a step whose dt / substeps exceeds it runs
  // ceil(dt / maxSubstep) equal sub-steps instead (World::substepsFor). Contacts are found
  // after each sub-step's prediction and solved linearised, which needs bodies to move less
  // than about a particle spacing per sub-step. The material is the same at any sub-step
  // (substep_material.h), and at 1-s sub-steps every shipped scene keeps its energy and its
  // bodies' shapes (within 26 % of their diagonal; resting particles up to 3 spacings inside a
  // collider). Longer sub-steps are refused: at 2 s the large scene's bodies grow ×8, at 10 s
  // (g·h² = 981 m) the pile's bodies pass through each other in the first sub-step and blow
  // up (docs/design.md §3). The default, 1/120 s, is half
  // Jolt's rule of thumb (one collision step per 1/60 s): at 1/60 s the shipped pile rests with
  // particles 1.15 spacings inside other bodies and restitution.json's e = 0.9 box never stops
  // bouncing; at 1/120 s neither happens.
  double maxSubstep = 1.0 / 120.0;
  bool bodyContact = true;       // bodies with a surface keep other bodies out
  double contactFriction = 0.5;  // μ in [0, 1000] between bodies (as Collider::friction)
  // Approach speed (m/s, [0, 1e4]) below which contacts do not bounce whatever their
  // restitution: a resting body's small impacts (gravity's h·g every sub-step) stay inelastic.
  double restitutionThreshold = 1.0;
  // Rolling resistance, dimensionless, [0, 1]: a pair in contact resists its relative spin with
  // a couple up to c·ρ·N (N the normal force, ρ the smaller rest radius of gyration of the
  // two; docs/design.md §5.5), so bodies rolling or rocking on a rounded part come to rest; a
  // ball stays put on slopes below about atan(c). 0: contacts exert no couple.
  double rollingResistance = 0.05;
  // Bodies at rest sleep: a body none of whose particles has strayed farther than its sleep
  // speed (5 % of its size per second, at most 5 cm/s) carries it in 0.5 s, for 0.5 s, together
  // with every body it touches, skips the whole step until something wakes it (an awake body
  // touching it, a drag, a force, setParams/setClusters/setState, a collider or settings change).
  bool sleep = true;
};

// Refers to a body; stays valid until the body is removed (then contains() is false).
struct BodyHandle {
  std::uint32_t index = UINT32_MAX;
  std::uint32_t generation = 0;
  bool operator==(const BodyHandle& o) const {
    return index == o.index && generation == o.generation;
  }
  bool operator!=(const BodyHandle& o) const { return !(*this == o); }
};

// A soft constraint that pulls a point of a body toward a target (mouse dragging). The point is
// Σ wⱼ xⱼ over the listed particles; each step every listed particle j is pulled by
// stiffness · wⱼ·Δ / Σₖwₖ² with Δ = target − point (the minimum-norm move of the particles that
// brings the point onto the target, docs/design.md §5.4), so shape matching keeps acting.
struct DragDef {
  BodyHandle body;
  std::vector<int> particles;   // indices within the body
  std::vector<double> weights;  // same length; e.g. a surface point's cage weights
  Vec3 target = Vec3::Zero();   // metres
  double stiffness = 0.2;       // fraction of the gap closed per step, in (0, 1]
};

// Something the user should be told about (a body that went NaN and was reset, ...).
struct WorldEvent {
  BodyHandle body;
  std::string message;
};

class World {
 public:
  explicit World(const WorldSettings& settings = {});
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  World(const World&);
  World& operator=(const World&);

  // ---- world ----
  const WorldSettings& settings() const;
  // Throws std::invalid_argument naming the field when a value is out of range.
  void setSettings(const WorldSettings& settings);
  void addCollider(const Collider& collider);  // throws std::invalid_argument on bad shapes
  void clearColliders();
  const std::vector<Collider>& colliders() const;

  // ---- bodies ----
  // Validates the definition (throws std::invalid_argument naming the field and reason; the
  // world is unchanged then) and creates the body at its start state.
  BodyHandle addBody(const BodyDef& def);
  void removeBody(BodyHandle body);
  bool contains(BodyHandle body) const;
  std::vector<BodyHandle> bodies() const;  // in creation order
  const std::string& name(BodyHandle body) const;
  const BodyParams& params(BodyHandle body) const;
  void setParams(BodyHandle body, const BodyParams& params);  // throws on bad values
  const ClusterDef& clusterDef(BodyHandle body) const;
  // Rebuilds the body's clusters from its rest shape (throws on bad values; body unchanged then).
  // Plastic deformation is cleared; positions and velocities are kept.
  void setClusters(BodyHandle body, const ClusterDef& clusters);
  int clusterCount(BodyHandle body) const;
  // Particle indices (within the body) of each cluster.
  std::vector<std::vector<int>> clusterMembers(BodyHandle body) const;

  // ---- per-body particle data (#P×3, metres or m/s; rows in the order of BodyDef::positions) --
  // The views returned stay valid (same memory, current values) across steps, resets and the
  // addition of other bodies; removing the body or rebuilding its clusters ends them.
  int particleCount(BodyHandle body) const;
  ConstPointsRef positions(BodyHandle body) const;
  ConstPointsRef velocities(BodyHandle body) const;
  ConstPointsRef restPositions(BodyHandle body) const;
  Eigen::VectorXf masses(BodyHandle body) const;  // kg per particle (#P)
  double mass(BodyHandle body) const;             // kg
  Vec3 centreOfMass(BodyHandle body) const;
  Vec3 linearMomentum(BodyHandle body) const;
  Vec3 angularMomentum(BodyHandle body, const Vec3& about = Vec3::Zero()) const;
  // Overwrites positions and velocities (#P×3 each); for tests, tools and scripted starts.
  void setState(BodyHandle body, const Eigen::MatrixX3d& positions,
                const Eigen::MatrixX3d& velocities);
  // Goal positions of the last step, blended per particle (#P×3); the rest shape before the
  // first step.
  Eigen::MatrixX3d goals(BodyHandle body) const;
  // Permanent deformation Sᵖ of one cluster (identity without plasticity).
  Mat3 plasticDeformation(BodyHandle body, int cluster) const;

  // ---- interaction ----
  // Adds a force (newtons) on one particle for the next step only.
  void addForce(BodyHandle body, int particle, const Vec3& force);
  int addDrag(const DragDef& drag);  // returns an id; throws on bad indices/weights
  void setDragTarget(int id, const Vec3& target);
  void setDragStiffness(int id, double stiffness);
  void removeDrag(int id);

  // ---- time ----
  void step();           // advance by settings().timeStep in settings().substeps sub-steps
  void step(double dt);  // advance by dt seconds ([1e-7, 10]) in substepsFor(dt) sub-steps
  // Sub-steps that step(dt) runs: settings().substeps, or more when dt / substeps is longer
  // than settings().maxSubstep (to 1e-6 relative, so a dt written as 0.016666667 is one
  // sub-step of 1/60 s).
  int substepsFor(double dt) const;
  void reset();         // every body back to its start state; plasticity and drags cleared
  double time() const;  // seconds simulated since creation or reset
  const StepProfile& lastProfile() const;  // phases of the last step() call
  int lastContactCount() const;  // body–body contacts that carried load in the last sub-step
  // Work of the contacts over the last step() (all its sub-steps): the body–body narrow phase's
  // point–triangle tests, and those a pass of every probe particle over every triangle of each
  // obstacle it was paired with would make; the contact solve's velocity-sweep visits, and those
  // it skipped because they provably do nothing. The same at any thread count: for tests of how
  // contacts scale (no timings).
  struct ContactWork {
    long triangleTests = 0, triangleTestsOfAllPairs = 0;
    long sweepVisits = 0, skippedVisits = 0;
  };
  ContactWork lastContactWork() const;
  // Deepest penetration (m, ≥ 0) of a load-carrying contact (body or collider) of the last
  // sub-step, as detected: before the solve pushed it out, so it shows how hard contacts work,
  // not what is left inside.
  double lastDeepestContact() const;
  std::vector<WorldEvent> takeEvents();  // returns and clears pending events

  // ---- sleep (WorldSettings::sleep) ----
  bool isSleeping(BodyHandle body) const;
  int sleepingCount() const;
  // Wakes the body and every body that fell asleep with it (nothing for an awake body).
  void wake(BodyHandle body);

  // Hash of the physical state (positions, velocities, plastic deformation), bit-exact. The
  // solver's caches — warm-start rotations and reference points of the cluster fits — are left
  // out: they are held in float lanes or in double per cluster depending on the solver path
  // (cluster_state.h), so hashing them would make equal physical states hash differently.
  // They do steer later steps, so replays compare hashes after the same number of steps.
  std::uint64_t stateHash() const;

 private:
  struct Data;
  std::unique_ptr<Data> d_;
};

}  // namespace sb
