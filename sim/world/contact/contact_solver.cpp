#include "sim/world/contact/contact_solver.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <limits>

#include "sim/base/parallel_for.h"
#include "sim/world/contact/friction_cone.h"
#include "sim/world/contact/slab_schedule.h"
#include "sim/world/mass_properties.h"

namespace sb {

namespace {

// Position sweeps for what is still inside after the velocity sweeps.
constexpr int kPositionSweeps = 2;
// Position-only recovery per contact and sweep, in spacings of the probe body: pushes without
// velocity are free work, so they are rate-bounded (a pile whose residue was projected out at
// once kept buzzing at 0.1 m/s).
constexpr float kMaxPush = 0.02f;
// A contact still deeper than this (spacings of the probe body) after the whole-body pushes,
// which moved it out by less than kBlockedProgress of what they were asked for, is blocked:
// pushed out locally instead (pushOutLocally).
constexpr float kBlockedDepth = 0.02f;
constexpr float kBlockedProgress = 0.25f;
// Rigid corrections whose every component is at most this (shift m, turn rad, velocity m/s, spin
// rad/s) are not applied (finishSolverBody). At rest the solve's rigid share is a jitter of that
// size, and applied, its turns lean a soft body over its support edge (docs/design.md §5.5, the
// known defect): a linear α 0.6 bunny (0.7 m) on its side, sleep off, moved 4.5 mm in 30 s with
// them and 0.10 mm without. The momentum this drops is at most 1e-5 m/s of the body's per
// sub-step. (It was Eigen's isZero() default precision; stated here, as a choice.)
constexpr float kNegligibleRigidCorrection = 1e-5f;

bool negligible(const Vec3f& v) {
  return v.cwiseAbs().maxCoeff() <= kNegligibleRigidCorrection;
}

// Two contacts of a pair that push its bodies apart along directions more than 120° apart hook
// the bodies into each other (hookedContacts).
constexpr float kHookedCosine = -0.5f;
// The deepest a particle may be, in spacings of its body, for its contact to count as resting
// (ContactPoint::resting): deeper, it is stopped on its own again, so a soft body's particles
// cannot sink into what they rest on while their body as a whole stands still. (Without it the
// pile at 1/120-s sub-steps came to rest with particles 0.22 spacings deep; at 0.002, the slop,
// contacts flipped between the two answers and a soft stack still walked 2–15 % of its edge.)
constexpr float kRestingDepth = 0.01f;
// And the deepest the sub-step's integration may have taken it, in spacings: a soft body's
// supports are pulled in by the goals that carry its weight every sub-step (ContactPoint::resting;
// 3–8 % of a spacing for a bunny on four supports at 1/240 s). Deeper than this it came in on
// its own and is stopped on its own (without this bound a rigid-mode α 0.5 body on a plane ended
// steps 0.5 % of a spacing deep and the seed-scale pile 0.33 spacings inside the floor; at 0.1
// the large scene's bodies crept as before).
constexpr float kRestingPull = 0.25f;
// A pull deeper than kRestingDepth counts as resting only if it is steady: within this many
// spacings of the same contact's pull at the sub-step before, for kSteadySubsteps sub-steps in a
// row, each of them loaded. The weight a resting body carries pulls its supports in by the same
// amount every sub-step (to 10⁻⁴ of a spacing for a bunny on the floor); a body that is landing
// is still being compressed, and its pull grows by 0.5–15 % of a spacing per sub-step. Counted
// as resting, such a particle was answered through the body's rigid motion, which the landing was
// already lifting, and sank (the seed-scale pile's first second: particles 5.5 mm, 8 % of a
// spacing, inside the floor).
constexpr float kSteadyPull = 0.002f;
// At the turn of a landing's compression the pull holds still for a sub-step or two while the
// rebound lifts the body: with one steady sub-step a quadratic bunny dropped 2 m still ended a
// step 1.2 % of a spacing inside the floor, and a particle of the large scene stayed lodged 0.03
// spacings deep in another body from 1 s on; with four neither.
constexpr int kSteadySubsteps = 4;

Eigen::Matrix3f rotationOf(const Vec3f& turn) {
  const float angle = turn.norm();
  if (!(angle > 0.0f)) return Eigen::Matrix3f::Identity();
  return Eigen::AngleAxisf(angle, turn / angle).toRotationMatrix();
}

// One side of a contact: a particle (count 1), a point of a triangle (count 3), or a static
// collider (no body).
struct Side {
  SolverBody* body = nullptr;
  int idx[3] = {0, 0, 0};
  float w[3] = {1, 0, 0};
  int count = 0;
  bool resting = false;  // ContactPoint::resting of the contact it is a side of
};

Side probeSide(std::vector<SolverBody>& bodies, const ContactPoint& c) {
  Side s;
  s.body = &bodies[size_t(c.probe)];
  s.idx[0] = c.particle;
  s.count = 1;
  s.resting = c.resting;
  return s;
}

Side obstacleSide(std::vector<SolverBody>& bodies, const ContactPoint& c) {
  Side s;
  if (c.obstacle < 0) return s;
  s.body = &bodies[size_t(c.obstacle)];
  const mesh::Triangle& t = (*s.body->triangles)[size_t(c.triangle)];
  for (int k = 0; k < 3; ++k) {
    s.idx[k] = t[size_t(k)];
    s.w[k] = c.weights[k];
  }
  s.count = 3;
  s.resting = c.resting;
  return s;
}

Vec3f leverArm(const Side& s) {
  if (!s.body) return Vec3f::Zero();
  Vec3f r = Vec3f::Zero();
  for (int k = 0; k < s.count; ++k) r += s.w[k] * (s.body->position(s.idx[k]) - s.body->centre);
  return r;
}

// Velocity of the side's point itself, gathered rigid corrections included.
Vec3f pointVelocity(const Side& s, const Vec3f& r) {
  if (!s.body) return Vec3f::Zero();
  Vec3f v = Vec3f::Zero();
  for (int k = 0; k < s.count; ++k) v += s.w[k] * s.body->velocity(s.idx[k]);
  return v + s.body->deltaV + s.body->deltaW.cross(r);
}

// The share of a side's response taken by its rigid motion: A (blended) the body's rigid share;
// B the particles alone, except on bodies with share 1, which answer as a whole (a local
// impulse would bend a rigid body for a sub-step), and in resting contacts, where every body
// answers B as a whole (ContactPoint::resting says why).
float shareOf(const Side& s, bool blended) {
  const float sh = s.body->rigidShare;
  if (blended) return sh;
  return sh >= 1.0f || s.resting ? 1.0f : 0.0f;
}

// What constraint A (blended) or B measures at the side's point, given the point's own velocity
// v = pointVelocity(s, r).
Vec3f measuredVelocity(const Side& s, const Vec3f& v, const Vec3f& r, bool blended) {
  if (!s.body) return Vec3f::Zero();
  const float sh = shareOf(s, blended);
  if (sh == 0.0f) return v;
  return (1.0f - sh) * v + sh * (s.body->fitV + s.body->fitW.cross(r));
}

// The two sides' point velocities (pointVelocity) during one visit of a contact. Only the
// visit's own impulses change them (a sweep visits the contacts of a body one after the other),
// so they are read again only after an impulse: a contact that carries nothing reads each side's
// particles once per visit instead of once per constraint.
struct VisitVelocities {
  Vec3f probe, obstacle;
  void read(const Side& p, const Side& o, const ContactPoint& c) {
    probe = pointVelocity(p, c.leverProbe);
    obstacle = pointVelocity(o, c.leverObstacle);
  }
};

float localInverseMass(const Side& s) {
  float k = 0;
  for (int c = 0; c < s.count; ++c) k += s.w[c] * s.w[c] * s.body->invMass[s.idx[c]];
  return k;
}

float rigidInverseMass(const SolverBody& b, const Vec3f& r, const Vec3f& d) {
  const Vec3f rd = r.cross(d);
  return b.invTotalMass + rd.dot(b.invInertia * rd);
}

// A side's response to impulses at its point, for the directions of computeInverseMasses: what
// does not depend on the direction (its particles' own inverse mass and the share of an impulse
// they carry) once, the rigid inverse mass per direction.
struct SideResponse {
  static constexpr int kDirections = 5;  // n, t1, t2 and the tangent diagonals u, w
  bool moves = false;                    // a body that is not fixed
  float local = 0;                       // localInverseMass
  float carried = 0;  // the share of an impulse the particles carry: 0 for pinned, else w
  float kappa[kDirections] = {};  // rigidInverseMass along each direction
};

SideResponse responseOf(const Side& s, const Vec3f& r,
                        const Vec3f (&dirs)[SideResponse::kDirections]) {
  SideResponse q;
  if (!s.body || s.body->fixed()) return q;
  const SolverBody& b = *s.body;
  q.moves = true;
  q.local = localInverseMass(s);
  for (int c = 0; c < s.count; ++c) q.carried += s.w[c] * b.invMass[s.idx[c]] * b.mass[s.idx[c]];
  for (int d = 0; d < SideResponse::kDirections; ++d) q.kappa[d] = rigidInverseMass(b, r, dirs[d]);
  return q;
}

// How much the measured velocity along direction d changes per unit impulse along it (C M⁻¹ Cᵀ),
// for constraint A (blended) or B.
float measuredInverseMass(const Side& s, const SideResponse& q, int d, bool blended) {
  if (!q.moves) return 0.0f;
  const float sh = shareOf(s, blended);
  if (sh == 0.0f) return q.local;
  const float kappa = q.kappa[d];
  const float point = (1.0f - sh) * q.local + sh * kappa;
  // The fitted rigid velocity at r changes by the whole impulse (both shares): the particle
  // share carries its momentum into the fit too, at the lever arm r (applyImpulse).
  const float fit = (1.0f - sh) * q.carried * kappa + sh * kappa;
  return (1.0f - sh) * point + sh * fit;
}

// How far the particle (point) itself moves per unit impulse of A along direction d.
float pointInverseMass(const Side& s, const SideResponse& q, int d) {
  if (!q.moves) return 0.0f;
  const float sh = s.body->rigidShare;
  return (1.0f - sh) * q.local + sh * q.kappa[d];
}

// Applies impulse J (N·s) to the side with the given rigid share. Velocities change by Δv and
// positions by h·Δv; with positionsOnly, J is a position correction (kg·m) and only positions
// move.
void applyImpulse(const Side& s, const Vec3f& r, const Vec3f& J, float share, float h,
                  bool positionsOnly) {
  if (!s.body || s.body->fixed()) return;
  SolverBody& b = *s.body;
  Vec3f carriedLinear = Vec3f::Zero();
  if (share < 1.0f)
    for (int c = 0; c < s.count; ++c) {
      const int i = s.idx[c];
      const Vec3f dv = (1.0f - share) * s.w[c] * b.invMass[i] * J;
      if (positionsOnly) {
        for (int a = 0; a < 3; ++a) b.x[a][i] += dv[a];
      } else {
        for (int a = 0; a < 3; ++a) {
          b.v[a][i] += dv[a];
          b.x[a][i] += h * dv[a];
        }
        carriedLinear += b.mass[i] * dv;
      }
    }
  if (share > 0.0f) {
    const Vec3f linear = share * b.invTotalMass * J;
    const Vec3f angular = share * (b.invInertia * r.cross(J));
    if (positionsOnly) {
      b.shift += linear;
      b.turn += angular;
      b.turnRotation = rotationOf(b.turn);
    } else {
      b.deltaV += linear;
      b.deltaW += angular;
      b.shift += h * linear;
      b.turn += h * angular;
    }
  }
  // The momentum the particle shares carry enters the fitted rigid motion at the contact's lever
  // arm r, fixed when the solve began, as in measuredInverseMass: the solve is linear about the
  // configuration it started from. (Taken at the particles' current positions, which the
  // particle shares move by h·Δv, the fit's response no longer matched the effective masses and
  // a visit was no longer a projection: at one-second sub-steps a soft body's particles move
  // metres within the solve, the fitted spin swung to 10 rad/s, the friction turned the body by
  // 2 rad per sub-step, and the default scene's soft bodies at dt 1 s with one sub-step gained
  // ×10⁴ kinetic energy in five steps.)
  if (!positionsOnly) {
    // A particle share moves its particles by at most (1 − share)·max(1/m)·|J|; the rest, and the
    // fitted rigid velocity (which takes the whole impulse), by at most bodyResponse·|J| at any
    // lever arm. (The 1.001 covers the rounding of this product.)
    b.measuredChange +=
        1.001 * double(J.norm()) * double((1.0f - share) * b.particleResponse + b.bodyResponse);
    b.fitV += b.invTotalMass * (carriedLinear + share * J);
    b.fitW += b.invInertia * r.cross(carriedLinear + share * J);
  }
}

// Effective inverse masses of A and B along n, t1, t2 and the point's own along n, with the
// sides' current fixed/immovable state.
void computeInverseMasses(const Side& p, const Side& o, ContactPoint& c) {
  // The tangent coupling by polarisation: q(d) = dᵀKd along the diagonals u, w of the tangent
  // basis gives K₁₂ = (q(u) − q(w)) / 2.
  const Vec3f u = (c.tangent1 + c.tangent2) * std::sqrt(0.5f);
  const Vec3f w = (c.tangent1 - c.tangent2) * std::sqrt(0.5f);
  const Vec3f dirs[SideResponse::kDirections] = {c.normal, c.tangent1, c.tangent2, u, w};
  const SideResponse qp = responseOf(p, c.leverProbe, dirs);
  const SideResponse qo = responseOf(o, c.leverObstacle, dirs);
  for (int j = 0; j < 2; ++j) {
    auto q = [&](int d) {
      return measuredInverseMass(p, qp, d, j == 0) + measuredInverseMass(o, qo, d, j == 0);
    };
    for (int d = 0; d < 3; ++d) c.inverseMass[j][d] = q(d);
    c.tangentCoupling[j] = 0.5f * (q(3) - q(4));
  }
  c.pointInverseMass = pointInverseMass(p, qp, 0) + pointInverseMass(o, qo, 0);
}

// How fast the two bodies' rigid motions (their momentum fits) bring the contact's sides together
// along n (m/s; < 0: parting): the bodies' approach as a whole, blind to one particle's jitter.
float rigidApproach(const Side& p, const Side& o, const Vec3f& n) {
  auto rigidVelocity = [](const Side& s) -> Vec3f {
    if (!s.body) return Vec3f::Zero();
    return s.body->fitV + s.body->fitW.cross(leverArm(s));
  };
  return -(rigidVelocity(p) - rigidVelocity(o)).dot(n);
}

void prepareContact(std::vector<SolverBody>& bodies, ContactPoint& c,
                    const ContactSolverSettings& settings) {
  const float h = settings.h;
  Side p = probeSide(bodies, c), o = obstacleSide(bodies, c);
  c.leverProbe = leverArm(p);
  c.leverObstacle = leverArm(o);
  const Vec3f& n = c.normal;
  // The approach now (after the integration) and where the particle was at the start of the
  // sub-step (positions follow velocities: x = x₀ + h·v): it may come as close as touching at
  // the end of the sub-step; one already inside is stopped, not thrown out. Never a separating
  // target: a contact only stops. (Aiming at the speed of a particle already leaving, constraint
  // A pushed the whole soft body until its blended velocity matched the particle's; in a pile on
  // a very soft body that made energy every sub-step until it blew up.)
  const float u0 = (pointVelocity(p, c.leverProbe) - pointVelocity(o, c.leverObstacle)).dot(n);
  const float start = c.distance0 - h * u0;
  // Resting: judged by how deep the particle is at the start of the sub-step, not after the
  // integration. A soft body carries its weight to its supports through shape matching's goals,
  // which lie below them: every sub-step the integration pulls each support millimetres into
  // what it rests on (3–8 mm at 1/240 s for a bunny on four supports), however still the body
  // is. Judged after that pull, supports were never resting; B stopped them one by one, fought
  // A's friction at the same contact (their friction impulses nearly opposite, each at its
  // cone's limit) and the body walked (docs/design.md §5.5). A pull deeper than kRestingDepth
  // must also be steady (kSteadyPull, kSteadySubsteps): a landing body's particles are pulled as
  // deep, but deeper every sub-step.
  const float spacing = p.body->spacing;
  c.steadySubsteps = std::abs(c.distance0 - c.warmDistance0) <= kSteadyPull * spacing
                         ? c.warmSteadySubsteps + 1
                         : 0;
  const bool steady =
      c.distance0 >= -kRestingDepth * spacing ||
      (c.distance0 >= -kRestingPull * spacing && c.steadySubsteps >= kSteadySubsteps);
  c.resting = rigidApproach(p, o, n) <= settings.restingSpeed &&
              start >= -kRestingDepth * spacing && steady;
  p.resting = o.resting = c.resting;
  c.tangent1 = (std::abs(n.x()) < 0.6f ? Vec3f::UnitX() : Vec3f::UnitY()).cross(n).normalized();
  c.tangent2 = n.cross(c.tangent1);
  computeInverseMasses(p, o, c);
  c.target = std::min(-start / h, 0.0f);
  // Bounce only where the surfaces meet within this sub-step, faster than the threshold.
  if (c.restitution > 0.0f && -u0 > settings.restitutionThreshold && c.distance0 < 0.0f)
    c.target = std::max(c.target, -c.restitution * u0);
}

void warmStart(std::vector<SolverBody>& bodies, ContactPoint& c, float h) {
  const Side p = probeSide(bodies, c), o = obstacleSide(bodies, c);
  const Vec3f& n = c.normal;
  const bool answerChanged = c.resting != c.warmResting &&
                             (p.body->rigidShare < 1.0f || (o.body && o.body->rigidShare < 1.0f));
  for (int j = 0; j < 2; ++j) {
    const bool blended = j == 0;
    if (!(c.inverseMass[j][0] > 0.0f) || !(c.lambda[j] > 0.0f) || (!blended && answerChanged)) {
      c.lambda[j] = 0;
      c.tangent[j].setZero();
      continue;
    }
    // The friction impulse re-projected onto the current tangent plane, within the cone.
    Vec3f t = c.tangent[j] - c.tangent[j].dot(n) * n;
    const float limit = c.friction * c.lambda[j];
    const float len = t.norm();
    if (len > limit) t *= len > 0.0f ? limit / len : 0.0f;
    c.tangent[j] = t;
    const Vec3f J = c.lambda[j] * n + t;
    applyImpulse(p, c.leverProbe, J, shareOf(p, blended), h, false);
    applyImpulse(o, c.leverObstacle, -J, o.body ? shareOf(o, blended) : 0.0f, h, false);
  }
}

// One visit of constraint A (blended) or B: normal impulse toward the target, then friction in
// the tangent plane clamped to the cone of the accumulated normal impulse.
// `v` holds the sides' point velocities on entry and is kept current. `slack`, where given,
// takes the minimum with this constraint's idle slack (ContactPoint::idleSlack) as measured on
// entry.
void solveConstraint(const Side& p, const Side& o, ContactPoint& c, bool blended, float h,
                     VisitVelocities& v, float* slack) {
  const Vec3f& rp = c.leverProbe;
  const Vec3f& ro = c.leverObstacle;
  const Vec3f& n = c.normal;
  const int j = blended ? 0 : 1;
  const float k = c.inverseMass[j][0];
  if (!(k > 0.0f)) return;
  const float sp = shareOf(p, blended), so = o.body ? shareOf(o, blended) : 0.0f;
  float& lambda = c.lambda[j];
  auto measured = [&] {
    return Vec3f(measuredVelocity(p, v.probe, rp, blended) -
                 measuredVelocity(o, v.obstacle, ro, blended));
  };
  const float u = measured().dot(n);
  if (slack) {
    // The margin: u is a few roundings of velocities as large as the two sides' measured ones,
    // and every impulse since rounded them again; 1e-3 of their size leaves room for a thousand
    // roundings.
    const float size = measuredVelocity(p, v.probe, rp, blended).cwiseAbs().sum() +
                       measuredVelocity(o, v.obstacle, ro, blended).cwiseAbs().sum() +
                       std::abs(c.target);
    *slack = std::min(*slack, u - c.target - 1e-3f * size - 1e-6f);
  }
  // The projection onto the target (λ ≥ 0). A never pushes harder than it takes to bring the
  // particle itself to the target: where the body's rigid motion approaches but the particle
  // does not (it is already being compressed), the blended measure would fling the light
  // particle away. That cap only limits an increase: taking back impulse while the measured
  // velocity approaches (a step against the projection's) would make energy.
  float nextLambda = std::max(lambda + (c.target - u) / k, 0.0f);
  if (blended && nextLambda > lambda && c.pointInverseMass > 0.0f) {
    const float up = (v.probe - v.obstacle).dot(n);
    nextLambda =
        std::min(nextLambda, std::max(lambda + (c.target - up) / c.pointInverseMass, lambda));
  }
  const float dl = nextLambda - lambda;
  lambda = nextLambda;
  if (dl != 0.0f) {
    applyImpulse(p, rp, dl * n, sp, h, false);
    applyImpulse(o, ro, -dl * n, so, h, false);
    v.read(p, o, c);
  }
  // A contact that carries no load and no friction impulse keeps none: the cone's radius μλ is
  // zero, so the visit below would end where it starts. Most visits are of such contacts (about
  // 80 % in the large scene and in a settled layer of bunnies: the margin's speculative
  // contacts), and this skips their slip and cone arithmetic.
  if (lambda == 0.0f && c.tangent[j] == Vec3f::Zero()) return;
  if (!(c.friction > 0.0f)) return;
  const Vec3f rel = measured();
  const Vec3f& t1 = c.tangent1;
  const Vec3f& t2 = c.tangent2;
  const Eigen::Matrix2f K{{c.inverseMass[j][1], c.tangentCoupling[j]},
                          {c.tangentCoupling[j], c.inverseMass[j][2]}};
  // K is positive definite whenever a side can move (a particle's own share and a body's 1/M
  // respond alike in every direction); otherwise (both sides fixed) there is nothing to rub.
  const float det = K.determinant();
  if (!(K(0, 0) > 0.0f && K(1, 1) > 0.0f && det > 1e-6f * K(0, 0) * K(1, 1))) return;
  Vec3f& tangent = c.tangent[j];
  const Eigen::Vector2f before(tangent.dot(t1), tangent.dot(t2));
  // Coulomb friction as maximal dissipation in the metric of K (friction_cone.h): the radial
  // clamp used before could end at a higher energy than the visit started from when K is
  // anisotropic.
  const Eigen::Vector2f next =
      frictionImpulse(K, Eigen::Vector2f(rel.dot(t1), rel.dot(t2)), before, c.friction * lambda);
  const Eigen::Vector2f change = next - before;
  tangent = next.x() * t1 + next.y() * t2;
  // Exactly zero: what is recorded must be applied. (Eigen's isZero(), an absolute 1e-5 N·s,
  // skipped the small changes of light bodies but kept them in the accumulated impulse: a 1 g
  // bunny lost most of its friction and walked; docs/design.md §5.5.)
  if (change == Eigen::Vector2f::Zero()) return;
  const Vec3f dJ = change.x() * t1 + change.y() * t2;
  applyImpulse(p, rp, dJ, sp, h, false);
  applyImpulse(o, ro, -dJ, so, h, false);
  v.read(p, o, c);
}

bool carriesNothing(const ContactPoint& c) {
  return c.lambda[0] == 0.0f && c.lambda[1] == 0.0f && c.tangent[0] == Vec3f::Zero() &&
         c.tangent[1] == Vec3f::Zero();
}

// One visit of both constraints. In the velocity sweeps (mayIdle), a contact that carries
// nothing and provably would still do nothing (ContactPoint::idleSlack) is skipped: the same
// results, without reading its particles.
void solveContact(std::vector<SolverBody>& bodies, ContactPoint& c, float h, bool mayIdle) {
  const Side p = probeSide(bodies, c), o = obstacleSide(bodies, c);
  const bool idle = carriesNothing(c);
  auto changeSinceVisit = [&] {
    return (p.body->measuredChange - c.measuredChangeAtVisit[0]) +
           (o.body ? o.body->measuredChange - c.measuredChangeAtVisit[1] : 0.0);
  };
  if (mayIdle && idle && c.idleSlack > 0.0f && changeSinceVisit() < double(c.idleSlack)) {
    ++c.skippedVisits;
    return;
  }
  VisitVelocities v;
  v.read(p, o, c);
  // The slack is measured on entry, so it holds only where the visit applied nothing: idle
  // before and after. (Contacts that carry something do not measure it.)
  float slack = std::numeric_limits<float>::infinity();
  float* measureSlack = mayIdle && idle ? &slack : nullptr;
  solveConstraint(p, o, c, true, h, v, measureSlack);
  solveConstraint(p, o, c, false, h, v, measureSlack);
  c.idleSlack = -1;
  if (mayIdle && idle && carriesNothing(c)) {
    c.idleSlack = slack;
    c.measuredChangeAtVisit[0] = p.body->measuredChange;
    c.measuredChangeAtVisit[1] = o.body ? o.body->measuredChange : 0.0;
  }
}

// Signed distance minus the gap at the current positions, rigid corrections included.
float currentDistance(std::vector<SolverBody>& bodies, const ContactPoint& c,
                      const std::vector<Collider>& colliders) {
  const SolverBody& probe = bodies[size_t(c.probe)];
  const Vec3f xp = correctedPosition(probe, c.particle);
  if (c.obstacle < 0) {
    Vec3 n;
    double d;
    // A point whose nearest surface of this collider is buried is held by the other collider.
    if (!exposedColliderDistance(colliders, c.collider, xp.cast<double>(), &d, &n))
      return std::numeric_limits<float>::infinity();
    return float(d);
  }
  const SolverBody& ob = bodies[size_t(c.obstacle)];
  const mesh::Triangle& tri = (*ob.triangles)[size_t(c.triangle)];
  Vec3f xo = Vec3f::Zero();
  for (int k = 0; k < 3; ++k) xo += c.weights[k] * correctedPosition(ob, tri[size_t(k)]);
  return (xp - xo).dot(c.normal) - ob.gap;
}

// Position-only push of what is still inside, at most kMaxPush spacings, moving the bodies as a
// whole (their recovery share; pinned bodies locally). Pushing a soft body's particle on its
// own deforms the body without velocity: that is elastic energy from nowhere, which shape
// matching turns into speed at the next sub-step. Under a pile held together by friction these
// pushes fed energy in every sub-step until the pile blew up (issue 18's soak, seeds 1234 and 7;
// without local pushes both run 1,500 steps clean; the 20,000-step soak then failed where a
// very soft body was crushed through itself, until the reach, docs/design.md §5.3 and §5.5).
// A whole-body push stores no deformation; it is free work only against gravity, and
// rate-bounded.
//
// Only what is deeper than the slop (kContactSlop spacings) is pushed, and only the excess:
// resting contacts end each velocity solve a little inside (round-off), and each push turns the
// body about its centre of mass, sliding its other contacts sideways with nothing to hold them;
// pushed every sub-step, that made stacks walk and tall ones fall (docs/design.md §5.5). Within
// the slop a contact stays as it is: its velocity target keeps it from going deeper.
void pushOut(std::vector<SolverBody>& bodies, const ContactPoint& c, float distance) {
  const Side p = probeSide(bodies, c), o = obstacleSide(bodies, c);
  const float spacing = p.body->spacing > 0.0f ? p.body->spacing : kSpacingWithoutSurface;
  const float depth = -distance - kContactSlop * spacing;
  if (!(depth > 0.0f)) return;
  const Vec3f rp = leverArm(p), ro = leverArm(o);
  auto kPos = [&](const Side& s, const Vec3f& r) {
    if (!s.body || s.body->fixed()) return 0.0f;
    const float sh = s.body->recoveryShare;
    return (1.0f - sh) * localInverseMass(s) + sh * rigidInverseMass(*s.body, r, c.normal);
  };
  const float k = kPos(p, rp) + kPos(o, ro);
  if (!(k > 0.0f)) return;
  const float amount = std::min(depth, kMaxPush * spacing);
  applyImpulse(p, rp, (amount / k) * c.normal, p.body->recoveryShare, 0.0f, true);
  if (o.body) applyImpulse(o, ro, (-amount / k) * c.normal, o.body->recoveryShare, 0.0f, true);
}

// The push of a blocked contact (kBlockedDepth) between bodies hooked into each other
// (hookedContacts), both at rest (their rigid motion no faster than the resting speed). The
// whole-body pushes cannot free it: other contacts of the same two bodies push them the other
// way. That is where a thin part of one body went through a thin part of another during a
// landing (contacts are particles against faces, so edges can pass through edges): in the pile at
// 1-s steps a bunny's particle stayed 0.2 spacings inside another bunny for good, pushed down by
// its contact while three others pushed its body up. Deforming the bodies can free it: the soft
// sides are pushed locally (by their particles' own inverse masses), at the same bounded rate as
// the whole-body pushes; never a rigid side (α 1), whose shape matching would throw the push
// back as speed. Local pushes store deformation, which shape matching turns into speed: pushing
// every blocked contact (not only hooked ones, and not only at rest) spread a very soft bunny
// (α 0.005) through the soak's pile to 3 m within 100 steps, and bodies then hit each other at
// 10–25 m/s. Gated by rest, the energy they can add is self-limiting: a body they set moving
// faster than the resting speed is no longer pushed.
void pushOutLocally(std::vector<SolverBody>& bodies, const ContactPoint& c, float distance) {
  const Side p = probeSide(bodies, c), o = obstacleSide(bodies, c);
  const float spacing = p.body->spacing > 0.0f ? p.body->spacing : kSpacingWithoutSurface;
  const float depth = -distance - kContactSlop * spacing;
  if (!(depth > 0.0f)) return;
  auto kLocal = [](const Side& s) {
    if (!s.body || s.body->fixed() || s.body->rigidShare >= 1.0f) return 0.0f;
    return localInverseMass(s);
  };
  const float kp = kLocal(p), ko = kLocal(o);
  if (!(kp + ko > 0.0f)) return;
  const float amount = std::min(depth, kMaxPush * spacing) / (kp + ko);
  if (kp > 0.0f) applyImpulse(p, Vec3f::Zero(), amount * c.normal, 0.0f, 0.0f, true);
  if (ko > 0.0f) applyImpulse(o, Vec3f::Zero(), -amount * c.normal, 0.0f, 0.0f, true);
}

// For each contact of pointList (by position q): whether its two bodies are hooked into each
// other there, i.e. it is inside beyond the slop (distance[q], metres) and another contact
// between the same two bodies, also inside, pushes them apart along a direction more than 120°
// from its own (kHookedCosine). Static contacts are never hooked.
std::vector<char> hookedContacts(const std::vector<SolverBody>& bodies,
                                 const std::vector<ContactPoint>& points,
                                 const std::vector<int>& pointList,
                                 const std::vector<float>& distance) {
  struct Inside {
    int a, b;    // the pair's bodies, a < b
    Vec3f push;  // the direction the contact pushes body a
    int q;
  };
  std::vector<Inside> inside;
  for (int q = 0; q < int(pointList.size()); ++q) {
    const ContactPoint& c = points[size_t(pointList[size_t(q)])];
    if (c.obstacle < 0) continue;
    const float spacing = bodies[size_t(c.probe)].spacing;
    if (!(-distance[size_t(q)] > kContactSlop * spacing)) continue;
    const bool probeFirst = c.probe < c.obstacle;
    inside.push_back({std::min(c.probe, c.obstacle), std::max(c.probe, c.obstacle),
                      probeFirst ? c.normal : Vec3f(-c.normal), q});
  }
  std::sort(inside.begin(), inside.end(), [](const Inside& x, const Inside& y) {
    return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.q < y.q;
  });
  std::vector<char> hooked(pointList.size(), 0);
  for (size_t begin = 0; begin < inside.size();) {
    size_t end = begin + 1;
    while (end < inside.size() && inside[end].a == inside[begin].a &&
           inside[end].b == inside[begin].b)
      ++end;
    for (size_t i = begin; i < end; ++i)
      for (size_t j = begin; j < end && !hooked[size_t(inside[i].q)]; ++j)
        if (inside[i].push.dot(inside[j].push) < kHookedCosine) hooked[size_t(inside[i].q)] = 1;
    begin = end;
  }
  return hooked;
}

// A contact's accumulated impulses (constraints A and B), to put them back.
struct ContactImpulses {
  float lambda[2];
  Vec3f tangent[2];
};

ContactImpulses impulsesOf(const ContactPoint& c) {
  return {{c.lambda[0], c.lambda[1]}, {c.tangent[0], c.tangent[1]}};
}

void setImpulses(ContactPoint& c, const ContactImpulses& saved) {
  for (int j = 0; j < 2; ++j) {
    c.lambda[j] = saved.lambda[j];
    c.tangent[j] = saved.tangent[j];
  }
}

}  // namespace

void prepareSolverBody(SolverBody& b) {
  const RigidMotion rm = rigidMotion(PointColumns{{b.x[0], b.x[1], b.x[2]}},
                                     PointColumns{{b.v[0], b.v[1], b.v[2]}}, b.mass, b.count);
  b.centre = rm.centre.cast<float>();
  b.invTotalMass = 1.0f / b.totalMass;
  b.invInertia = rm.inverseInertia.cast<float>();
  b.fitV = rm.velocity.cast<float>();
  b.fitW = rm.omega.cast<float>();
  b.deltaV = b.deltaW = b.shift = b.turn = Vec3f::Zero();
  b.turnRotation.setIdentity();
  b.frozen = false;
  b.load = 0;
  b.measuredChange = 0;
  float particleResponse = 0, reach = 0;  // largest 1/m; largest |x − c|²
  for (int i = 0; i < b.count; ++i) {
    particleResponse = std::max(particleResponse, b.invMass[i]);
    reach = std::max(reach, (b.position(i) - b.centre).squaredNorm());
  }
  b.particleResponse = particleResponse;
  // |I⁻¹| by its Frobenius norm, which bounds the spectral one.
  b.bodyResponse = b.invTotalMass + b.invInertia.norm() * reach;
  b.rigidSpeed = b.fitV.norm() + b.fitW.norm() * std::sqrt(reach);
}

void finishSolverBody(SolverBody& b) {
  if (negligible(b.shift) && negligible(b.turn) && negligible(b.deltaV) && negligible(b.deltaW))
    return;
  // About the centre of mass as it is now, after the particle shares moved it: then deltaW × r
  // carries no linear momentum and the centre moves by exactly `shift`.
  const Vec3f centre =
      centreOfMass(PointColumns{{b.x[0], b.x[1], b.x[2]}}, b.mass, b.count).cast<float>();
  // The velocities turn with the positions, v + (R − I)(v − vc) as in the prediction, and the
  // rigid share's velocity is the rigid field about the turned positions. (Left unturned, the
  // velocity field no longer matched the turned body: a rigid field of the old orientation is a
  // shear of the new one. Negligible at small turns; at dt 10 s the turn reached radians and a
  // stiff linear body (α 1, β 0.2) resting on the floor grew by 20–30 % at every other step.)
  const Eigen::Matrix3f R = rotationOf(b.turn);
  const Eigen::Matrix3f turnVelocity = R - Eigen::Matrix3f::Identity();
  // The centre's velocity: the mass-weighted mean of the velocities.
  const Vec3f vc = b.turn == Vec3f::Zero()
                       ? Vec3f(Vec3f::Zero())
                       : Vec3f(centreOfMass(PointColumns{{b.v[0], b.v[1], b.v[2]}}, b.mass, b.count)
                                   .cast<float>());
  for (int i = 0; i < b.count; ++i) {
    if (b.invMass[i] == 0.0f) continue;  // pinned (a pinned body has no rigid share anyway)
    const Vec3f r = R * (b.position(i) - centre);
    const Vec3f x = centre + b.shift + r;
    const Vec3f v =
        b.velocity(i) + turnVelocity * (b.velocity(i) - vc) + b.deltaV + b.deltaW.cross(r);
    for (int a = 0; a < 3; ++a) {
      b.x[a][i] = x[a];
      b.v[a][i] = v[a];
    }
  }
  b.deltaV = b.deltaW = b.shift = b.turn = Vec3f::Zero();
  b.turnRotation.setIdentity();
}

void solveIsland(std::vector<SolverBody>& bodies, std::vector<ContactPoint>& points,
                 const std::vector<int>& bodyList, const std::vector<int>& pointList,
                 const std::vector<Collider>& colliders, const ContactSolverSettings& settings) {
  const float h = settings.h;
  // Sweeps in pointList order; a large island's by slabs, on all threads (slab_schedule.h: an
  // order that depends only on the island, so the same results for any thread count).
  const int count = static_cast<int>(pointList.size());
  const bool large = count >= kMinParallelSweep;
  const bool parallel = large && threadCount() > 1;
  SlabSchedule slabs;
  if (large)
    slabs.build(
        count, static_cast<int>(bodies.size()),
        [&](int q) {
          const ContactPoint& c = points[size_t(pointList[size_t(q)])];
          auto writes = [&](int b) { return b >= 0 && !bodies[size_t(b)].immovable ? b : -1; };
          return std::array<int, 2>{writes(c.probe), writes(c.obstacle)};
        },
        [&](int b) { return bodies[size_t(b)].centre; });
  auto sweep = [&](const auto& visit) {
    if (large)
      slabs.run([&](int q) { visit(points[size_t(pointList[size_t(q)])]); });
    else
      for (int k : pointList) visit(points[size_t(k)]);
  };
  // Preparing only reads the bodies.
  parallelFor(count, parallel ? 2 : INT32_MAX, [&](int q) {
    prepareContact(bodies, points[size_t(pointList[size_t(q)])], settings);
  });
  sweep([&](ContactPoint& c) { warmStart(bodies, c, h); });
  for (int s = 0; s < kVelocitySweeps; ++s)
    sweep([&](ContactPoint& c) { solveContact(bodies, c, h, settings.skipIdle); });

  // Shock propagation, for islands resting on a static collider under gravity: bodies bottom-up
  // along `up`; each body's contacts with what is below it (static colliders, bodies already
  // done) are solved with that below immovable, then the body is frozen. A stack's load then
  // reaches the floor in one pass instead of creeping down through the sweeps. (Mid-air
  // collisions are left alone: the one-sided pass does not conserve momentum.)
  //
  // The impulses this pass adds are applied but not remembered as the next sub-step's warm
  // start: they were found against bodies held immovable, and the sweeps, where those bodies
  // move, would re-apply them to bodies that cannot carry them — a very soft body (α 0.005) under
  // a rigid one took the rigid body's whole weight on single particles and the pile reached
  // 10⁴ m/s within a second (the soak's random parameters found it).
  bool grounded = false;
  for (int k : pointList) grounded = grounded || points[size_t(k)].obstacle < 0;
  if (grounded && settings.up != Vec3f::Zero() && bodyList.size() > 1) {
    std::vector<ContactImpulses> swept;
    swept.reserve(pointList.size());
    for (int k : pointList) swept.push_back(impulsesOf(points[size_t(k)]));
    std::vector<int> levels(bodyList);
    std::sort(levels.begin(), levels.end(), [&](int a, int b) {
      const float ha = bodies[size_t(a)].centre.dot(settings.up);
      const float hb = bodies[size_t(b)].centre.dot(settings.up);
      return ha != hb ? ha < hb : a < b;
    });
    // Each contact goes with the higher of its two bodies (static contacts with their body).
    std::vector<int> rank(bodies.size(), -1);
    for (size_t r = 0; r < levels.size(); ++r) rank[size_t(levels[r])] = int(r);
    const int levelCount = static_cast<int>(levels.size());
    std::vector<std::vector<int>> atLevel(levels.size());
    for (int k : pointList) {
      const ContactPoint& c = points[size_t(k)];
      const int rp = rank[size_t(c.probe)];
      const int ro = c.obstacle >= 0 ? rank[size_t(c.obstacle)] : -1;
      atLevel[size_t(std::max(rp, ro))].push_back(k);
    }
    auto solveLevel = [&](int level) {
      // Effective masses with what is below frozen.
      for (int k : atLevel[size_t(level)]) {
        ContactPoint& c = points[size_t(k)];
        computeInverseMasses(probeSide(bodies, c), obstacleSide(bodies, c), c);
      }
      for (int k : atLevel[size_t(level)]) solveContact(bodies, points[size_t(k)], h, false);
      bodies[size_t(levels[size_t(level)])].frozen = true;
    };
    // A level's contacts write only its body and read, besides it, only the bodies below that
    // they touch, which are final (frozen) once their own levels are done. So a level may run as
    // soon as the levels it touches have: in waves, each level one wave after the latest level it
    // touches, the levels of a wave (which touch none of each other) at once. Every body then
    // sees the values it sees in bottom-up order: the same bits for any thread count. Islands
    // too small for the sweeps' threads go bottom-up without the waves' bookkeeping.
    if (!parallel) {
      for (int level = 0; level < levelCount; ++level) solveLevel(level);
    } else {
      std::vector<int> wave(levels.size(), 0);
      int waves = 0;
      for (int level = 0; level < levelCount; ++level) {
        for (int k : atLevel[size_t(level)]) {
          const ContactPoint& c = points[size_t(k)];
          const int below =
              std::min(rank[size_t(c.probe)], c.obstacle >= 0 ? rank[size_t(c.obstacle)] : -1);
          if (below >= 0)
            wave[size_t(level)] = std::max(wave[size_t(level)], wave[size_t(below)] + 1);
        }
        waves = std::max(waves, wave[size_t(level)] + 1);
      }
      // The levels by wave, bottom-up within a wave (a counting sort).
      std::vector<int> waveStart(size_t(waves) + 1, 0), byWave(levels.size());
      for (int w : wave) ++waveStart[size_t(w) + 1];
      for (int w = 0; w < waves; ++w) waveStart[size_t(w) + 1] += waveStart[size_t(w)];
      std::vector<int> fill(waveStart.begin(), waveStart.end() - 1);
      for (int level = 0; level < levelCount; ++level)
        byWave[size_t(fill[size_t(wave[size_t(level)])]++)] = level;
      for (int w = 0; w < waves; ++w) {
        const int begin = waveStart[size_t(w)], end = waveStart[size_t(w) + 1];
        long long visits = 0;
        for (int i = begin; i < end; ++i)
          visits += static_cast<long long>(atLevel[size_t(byWave[size_t(i)])].size());
        if (end - begin < 2 || visits < kMinParallelShockWave) {
          for (int i = begin; i < end; ++i) solveLevel(byWave[size_t(i)]);
          continue;
        }
        // Pieces of about equal contact counts, one per thread.
        const int threads = threadCount();
        parallelRanges(threads, 2, threads, [&](int c0, int c1) {
          long long before = 0;
          for (int i = begin; i < end; ++i) {
            const int level = byWave[size_t(i)];
            const auto size = static_cast<long long>(atLevel[size_t(level)].size());
            const int piece = pieceHoldingMiddle(before, size, visits, threads);
            before += size;
            if (piece >= c0 && piece < c1) solveLevel(level);
          }
        });
      }
    }
    for (int b : bodyList) bodies[size_t(b)].frozen = false;
    for (size_t q = 0; q < pointList.size(); ++q)
      setImpulses(points[size_t(pointList[q])], swept[q]);
  }

  // What is still inside is pushed out without velocity, at a bounded rate.
  for (int b : bodyList) bodies[size_t(b)].turnRotation = rotationOf(bodies[size_t(b)].turn);
  // Local pushes (below) only between two bodies at rest: where no body contact has both, the
  // depths before the pushes are not needed.
  auto atRest = [&](int b) { return bodies[size_t(b)].rigidSpeed <= settings.restingSpeed; };
  bool mayPushLocally = false;
  for (int k : pointList) {
    const ContactPoint& c = points[size_t(k)];
    if (c.obstacle >= 0 && atRest(c.probe) && atRest(c.obstacle)) {
      mayPushLocally = true;
      break;
    }
  }
  std::vector<float> beforePush;
  if (mayPushLocally) {
    beforePush.assign(static_cast<size_t>(count), 0.0f);
    parallelFor(count, parallel ? 2 : INT32_MAX, [&](int q) {
      beforePush[size_t(q)] =
          currentDistance(bodies, points[size_t(pointList[size_t(q)])], colliders);
    });
  }
  for (int s = 0; s < kPositionSweeps; ++s)
    sweep(
        [&](const ContactPoint& c) { pushOut(bodies, c, currentDistance(bodies, c, colliders)); });
  // Blocked contacts of hooked pairs (pushOutLocally), in pointList order.
  if (mayPushLocally) {
    const std::vector<char> hooked = hookedContacts(bodies, points, pointList, beforePush);
    for (int q = 0; q < count; ++q) {
      if (!hooked[size_t(q)]) continue;
      const ContactPoint& c = points[size_t(pointList[size_t(q)])];
      if (!(atRest(c.probe) && atRest(c.obstacle))) continue;
      const SolverBody& probe = bodies[size_t(c.probe)];
      const float spacing = probe.spacing > 0.0f ? probe.spacing : kSpacingWithoutSurface;
      const float before = beforePush[size_t(q)];
      if (!(-before > kBlockedDepth * spacing)) continue;
      const float distance = currentDistance(bodies, c, colliders);
      const float asked =
          std::min(-before - kContactSlop * spacing, kPositionSweeps * kMaxPush * spacing);
      if (-distance > kBlockedDepth * spacing && distance - before < kBlockedProgress * asked)
        pushOutLocally(bodies, c, distance);
    }
  }
  for (int k : pointList) {
    const ContactPoint& c = points[size_t(k)];
    const float load = c.lambda[0] + c.lambda[1];
    // (Immovable bodies are shared between islands: not written.)
    if (!bodies[size_t(c.probe)].immovable) bodies[size_t(c.probe)].load += load;
    if (c.obstacle >= 0 && !bodies[size_t(c.obstacle)].immovable)
      bodies[size_t(c.obstacle)].load += load;
  }
}

}  // namespace sb
