// The contact solve of a sub-step (docs/design.md §5.5): every contact, body–body and static,
// in one velocity-level solve whose positions follow its velocities.
//
// Why this form (each point fixes a measured cause of energy gain or drift, issue 11):
// - Every velocity change Δv moves the positions by h·Δv, as the integration would have
//   (x_{n+1} = x_n + h·v_{n+1}); a position push without the matching velocity was free work.
//   The velocity target lets a particle approach until it touches at the end of the sub-step
//   (speculative contact); one already inside is stopped, not thrown out, and no target asks
//   for separation (restitution aside), so a normal visit only takes energy away, and so does a
//   friction visit (maximal dissipation in the contact's own metric: friction_cone.h), except
//   where a friction impulse must shrink with a normal impulse that dropped; the warm start can
//   add some too. What is still inside afterwards, deeper than the slop (kContactSlop), is
//   pushed out without velocity, at a bounded rate (at most kMaxPush spacings per sweep), so
//   recovery cannot launch a body, and by moving the bodies as a whole, so it stores no
//   deformation that shape matching would turn into speed.
// - Each contact is two constraints that can only remove energy, because each measures the
//   velocity its own impulse distribution acts on (the impulse is M⁻¹Cᵀλ of the row C it
//   measures): A, split between the particle (1 − s) and the body's rigid motion (s, as a rigid
//   body with the body's mass and inertia), measures (1 − s)·v_p + s·(V + ω × r) with V, ω the
//   momentum-fitted rigid velocity; B measures the particle alone and acts on it alone. Rigid
//   bodies (s = 1) answer B as a whole too, so they stay rigid, and so does every body in a
//   resting contact (ContactPoint::resting: B on the lone particle there rocked soft stacks).
// - Impulses are accumulated over the sweeps and clamped as totals (λ ≥ 0, friction within
//   μ·λ): clamping each visit apart let the first-visited contacts take all the load, the body
//   rocked in particle order and friction turned the rocking into a walk. Warm started from the
//   previous sub-step, so a resting body's contact forces are there from the first sweep.
// - The rigid share is applied as a true rotation about the centre of mass after the particle
//   shares moved it: linear momentum exact to round-off, rigid bodies rigid at any step.
// - Shock propagation: after the sweeps, islands that rest on a static collider are solved once
//   more bottom-up, each body with everything below it immovable, so a stack's load reaches the
//   floor in one pass.
#pragma once

#include <limits>
#include <vector>

#include "sim/base/types.h"
#include "sim/mesh/closed_surface.h"
#include "sim/world/collider.h"

namespace sb {

// Penetration left alone by the position recovery, in spacings of the probe body (0.2 mm for a
// 0.1 m spacing): resting contacts may stay this deep. Why, and why this value: docs/design.md
// §5.5 (the slop).
inline constexpr float kContactSlop = 0.002f;
// Metres: the spacing used for a body without a surface (particles only, e.g. against colliders).
inline constexpr float kSpacingWithoutSurface = 0.05f;

// One body in the solve: views into the World's arrays and its response as a whole.
struct SolverBody {
  float* x[3] = {nullptr, nullptr, nullptr};  // position columns (#P each), metres
  float* v[3] = {nullptr, nullptr, nullptr};  // velocity columns (#P each), m/s
  const float* mass = nullptr;                // kg per particle
  const float* invMass = nullptr;  // 1/kg per particle; 0 for pinned particles (immovable)
  int count = 0;                   // #P
  const std::vector<mesh::Triangle>* triangles = nullptr;  // surface (when an obstacle)
  float gap = 0;      // metres: separation its surface keeps (when an obstacle)
  float spacing = 0;  // metres: the surface spacing, scale of the position recovery
  // Share of constraint A taken by the rigid motion, in [0, 1] (the World uses α; 0 for bodies
  // with pinned particles); share 1 also answers B as a whole.
  float rigidShare = 0;
  // Share of the position-only pushes (what is still inside after the velocity sweeps) taken
  // by the body as a whole: 1, or 0 for pinned bodies.
  float recoveryShare = 1;
  bool immovable = false;  // a sleeping body: an obstacle that does not move this sub-step
  bool frozen = false;     // shock propagation: immovable while set

  // Set by prepareSolverBody: centre of mass (m), mass (kg), 1/mass, inverse inertia about the
  // centre (world axes, pseudo-inverse), and the momentum-fitted rigid velocity (m/s, rad/s),
  // kept current by every impulse of the solve.
  Vec3f centre = Vec3f::Zero();
  float totalMass = 0, invTotalMass = 0;
  Eigen::Matrix3f invInertia = Eigen::Matrix3f::Zero();
  Vec3f fitV = Vec3f::Zero(), fitW = Vec3f::Zero();
  // Rigid corrections gathered by the solve, applied by finishSolverBody: velocity change (m/s,
  // rad/s) and position change (translation m, rotation vector rad, its rotation matrix).
  Vec3f deltaV = Vec3f::Zero(), deltaW = Vec3f::Zero();
  Vec3f shift = Vec3f::Zero(), turn = Vec3f::Zero();
  Eigen::Matrix3f turnRotation = Eigen::Matrix3f::Identity();
  // Sum of the normal impulses the body took in this sub-step (N·s): it carried load.
  float load = 0;
  // An upper bound on how far any velocity a contact of this body measures has moved since the
  // velocity solve began (m/s), grown by every impulse, so that a contact that carries nothing
  // can tell it would still do nothing (ContactPoint::idleSlack). It grows per unit impulse
  // (m/s per N·s) by particleResponse (the largest 1/m of a particle) times the particle share
  // and bodyResponse (1/M + |I⁻¹|·R², R the farthest particle from the centre), which also
  // bounds what the impulse does to the fitted rigid velocity.
  double measuredChange = 0;
  float particleResponse = 0, bodyResponse = 0;
  // m/s: the fastest the rigid motion moves any particle, |V| + |ω|·R (set by prepareSolverBody).
  float rigidSpeed = 0;

  Vec3f position(int i) const { return Vec3f(x[0][i], x[1][i], x[2][i]); }
  Vec3f velocity(int i) const { return Vec3f(v[0][i], v[1][i], v[2][i]); }
  bool fixed() const { return immovable || frozen; }
};

// Centre, mass, inertia and fitted rigid velocity from the body's current state; clears the
// gathered corrections.
void prepareSolverBody(SolverBody& body);

// Applies the gathered rigid corrections about the centre of mass c as it is now (after the
// particle shares moved it): x = c + shift + R(turn)(x − c), and the velocities turn with the
// body, v ← v + (R − I)(v − vc) + deltaV + deltaW × R(x − c) (vc the centre's velocity).
void finishSolverBody(SolverBody& body);

// The particle's position including the gathered rigid corrections (metres).
inline Vec3f correctedPosition(const SolverBody& body, int particle) {
  return body.centre + body.shift + body.turnRotation * (body.position(particle) - body.centre);
}

// One contact: particle `particle` of body `probe` against a triangle of body `obstacle`, or
// against collider `collider` (obstacle = −1). Bodies are indices into the solve's body list.
struct ContactPoint {
  int probe = 0, obstacle = -1;
  int particle = 0;
  int triangle = -1;              // the obstacle's triangle (body contacts)
  int collider = -1;              // static contacts
  Vec3f weights = Vec3f::Zero();  // on the triangle
  Vec3f normal = Vec3f::Zero();   // unit, out of the obstacle
  float distance0 = 0;            // signed distance minus the gap, at detection (m; < 0: inside)
  float friction = 0;             // μ
  float restitution = 0;          // e in [0, 1]
  // Accumulated impulses (N·s) of constraints A [0] and B [1]: normal (≥ 0) and friction (a
  // vector in the tangent plane, within μ times the normal one). Set before the solve to warm
  // start it; read afterwards to warm start the next sub-step.
  float lambda[2] = {0, 0};
  Vec3f tangent[2] = {Vec3f::Zero(), Vec3f::Zero()};

  // Fixed for the sub-step by the solve: the relative normal velocity aimed at (m/s), lever
  // arms from the bodies' centres, a tangent basis, and the effective inverse masses of A and
  // B along n, t1, t2 and their coupling between t1 and t2 (the off-diagonal of the tangent
  // block); pointInverseMass: how far the particle itself moves per unit impulse of A.
  float target = 0;
  Vec3f leverProbe = Vec3f::Zero(), leverObstacle = Vec3f::Zero();
  Vec3f tangent1 = Vec3f::Zero(), tangent2 = Vec3f::Zero();
  float inverseMass[2][3] = {{0, 0, 0}, {0, 0, 0}};
  float tangentCoupling[2] = {0, 0};
  float pointInverseMass = 0;
  // Whether the bodies' rigid motions approach here no faster than the settings' restingSpeed and
  // the particle was at most kRestingDepth deep at the start of the sub-step (and at most
  // kRestingPull after its integration, which pulls a soft body's supports in by the weight they
  // carry; a pull deeper than kRestingDepth must have been as deep, within kSteadyPull, for
  // kSteadySubsteps sub-steps, as a resting body's is and a landing body's is not): a resting
  // contact, where B acts on the bodies' rigid motion (as for rigid bodies) instead of the particle
  // alone, so a particle's jitter is not answered by that particle alone. Answered alone, a resting
  // particle pushed out of its body's goal was pulled back in by shape matching in the next
  // sub-step, over and over, and those pushes rocked and walked soft stacks (five boxes at α 0.9,
  // sleep off: top drift 0.8–33 % of the edge in 20 s, now 0.03–0.2 %; docs/design.md §5.5).
  // Impacts keep B on the particle: it is what dents a soft body.
  bool resting = false;
  // `resting` of the sub-step the warm start's impulses come from: where it changed on a soft
  // body, B's impulse was found for the whole body and would land on one particle (or the other
  // way round), so B starts cold.
  bool warmResting = false;
  // distance0 of the sub-step the warm start comes from (m): how deep the contact's particle
  // was pulled then; NaN where there is no warm start (the contact carried nothing). And for how
  // many sub-steps in a row, up to this one, the pull has stayed that steady (prepareContact sets
  // steadySubsteps from warmSteadySubsteps).
  float warmDistance0 = std::numeric_limits<float>::quiet_NaN();
  int warmSteadySubsteps = 0, steadySubsteps = 0;
  // A contact that carried nothing before and after its last visit of the velocity sweeps:
  // by how much its sides' measured separation then exceeded the target, less a margin for
  // round-off (m/s; ≤ 0: none), and the two bodies' measuredChange then. Until that has grown
  // by more than the slack, a visit would again do nothing, so the sweeps skip it (most contacts
  // are the margin's speculative ones: 57–67 % of the visits are skipped in the pile, default,
  // large and seed-scale scenes).
  float idleSlack = -1;
  double measuredChangeAtVisit[2] = {0, 0};
  int skippedVisits = 0;  // velocity-sweep visits skipped so in this sub-step
};

struct ContactSolverSettings {
  float h = 0;                        // sub-step (s)
  float restitutionThreshold = 1.0f;  // m/s: slower approaches do not bounce
  // m/s: contacts whose rigid approach is at most this are resting (ContactPoint::resting);
  // −∞: none.
  float restingSpeed = -std::numeric_limits<float>::infinity();
  Vec3f up = Vec3f::UnitY();  // against gravity (shock propagation order); zero: none
  // Skip the visits that provably do nothing (ContactPoint::idleSlack); false visits every
  // contact in every sweep, with the same results (the tests compare the two).
  bool skipIdle = true;
};

// Velocity sweeps over an island's contacts (Gauss–Seidel with accumulated impulses).
inline constexpr int kVelocitySweeps = 8;

// Islands with at least this many contacts sweep in slab order on all threads (slab_schedule.h),
// with the same results for any thread count; below, in plain order on one thread. Such an
// island must be solved outside any parallel loop (inside one, the sweeps run on its thread
// alone).
inline constexpr int kMinParallelSweep = 2048;
// In such an island, a wave of the shock-propagation pass (bodies that touch none of each other)
// runs on all threads from this many contact visits (a visit is ~0.1–0.2 µs, a fork a few µs).
inline constexpr int kMinParallelShockWave = 256;

// Solves one island: the bodies `bodyList` (indices into bodies, prepared) and the contacts
// `pointList` (indices into points, in the order they are swept) that join them. Islands share
// no body, so they may be solved in parallel. Changes the bodies' velocities and positions
// (the rigid corrections stay gathered until finishSolverBody) and the points' impulses.
void solveIsland(std::vector<SolverBody>& bodies, std::vector<ContactPoint>& points,
                 const std::vector<int>& bodyList, const std::vector<int>& pointList,
                 const std::vector<Collider>& colliders, const ContactSolverSettings& settings);

}  // namespace sb
