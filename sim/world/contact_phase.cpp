#include "sim/world/contact_phase.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/base/parallel_for.h"
#include "sim/base/union_find.h"
#include "sim/world/contact/rolling_resistance.h"
#include "sim/world/mass_properties.h"

namespace sb {

namespace {

// Per-body work (bounds, grids, pairs, static contacts, islands) forks only in worlds with at
// least this many particles.
constexpr long long kMinParallelBodyWork = 2048;
// Separation body–body contacts restore, as a fraction of the obstacle's surface spacing: a
// small positive gap keeps resting particles outside despite float round-off.
constexpr float kContactGap = 0.01f;
// Contacts are made this far beyond the gap (spacings of the obstacle; for colliders, of the
// body) plus the sub-step's travel: the solve lets them approach until they touch, so resting
// contacts persist from sub-step to sub-step (and warm start) and nothing tunnels.
constexpr float kContactMargin = 0.25f;
// An obstacle's contact grid is rebuilt once its surface has moved this many spacings.
constexpr float kGridSlack = 0.25f;
// Spacings beyond the reach that each grid cell also holds triangles for (SurfaceGrid::build's
// lookAhead), so that a particle whose look-up widens by its travel and the grid's drift by no
// more reads one cell instead of up to eight (in the seed-scale pile most widen by 0.1–0.75
// spacings; 0.25 and 0.5 cut its contact phase by ~10 %, 0.75 no further).
constexpr float kGridLookAhead = 0.25f;
// Sub-steps between whole-surface searches for deep particles (overlapping starts, drags into
// another body); pairs that found some are searched every sub-step until they find none.
constexpr int kDeepSearchEvery = 8;
// m/s: the largest 2|g|h (twice what gravity adds in a sub-step) at which contacts may count as
// resting (ContactSolverSettings::restingSpeed); 1 m/s: sub-steps up to 51 ms at |g| = 9.81.
constexpr float kRestingSpeedLimit = 1.0f;

// m/s: 2|g|h, twice what gravity adds to a velocity in a sub-step of h seconds. A body resting
// on another meets it at about |g|·h every sub-step, so approaches below this are resting
// contact, not impacts (restitution threshold, ContactSolverSettings::restingSpeed).
double restingApproach(const ContactSettings& settings, double h) {
  return 2.0 * settings.gravity.norm() * h;
}

// Whether contacts may rest at sub-steps of h seconds: 2|g|h ≤ kRestingSpeedLimit.
bool contactsCanRest(const ContactSettings& settings, double h) {
  return restingApproach(settings, h) <= kRestingSpeedLimit;
}

bool lessKey(const ContactScratch::Warm& a, const ContactScratch::Warm& b) {
  return a.key < b.key;
}

// The bounding box the body-body detection sees the body in slot s in
// (ContactScratch::Body::frameShift).
Eigen::AlignedBox3f detectionBox(const ContactScratch::Body& cs) {
  return Eigen::AlignedBox3f(cs.box.min() + cs.frameShift, cs.box.max() + cs.frameShift);
}

// Sets up the detection view of the body in slot s; a sleeping body is seen moved by its frame
// shift (ContactScratch::Body::frameShift) at the sub-step of h seconds.
void prepareGeometry(const BodySlot& b, float h, ContactScratch::Body& cs) {
  const BodyModel& m = *b.model;
  ContactGeometry& g = cs.geometry;
  const bool shifted = b.sleep.asleep;
  if (shifted) {
    cs.detectX = b.state.x.rowwise() + cs.frameShift.transpose();
    cs.detectV.resize(b.state.v.rows(), 3);
    cs.detectV.rowwise() = cs.frameShift.transpose() / h;
  }
  for (int a = 0; a < 3; ++a) {
    g.x[a] = (shifted ? cs.detectX : b.state.x).col(a).data();
    g.v[a] = (shifted ? cs.detectV : b.state.v).col(a).data();
  }
  g.count = m.particleCount();
  g.triangles = &m.surface;
  g.topology = &m.surfaceTopology;
  g.grid = &cs.grid;
  g.box = detectionBox(cs);
  g.gap = kContactGap * m.spacing;
  g.margin = kContactMargin * m.spacing;
  g.slop = kContactSlop * m.spacing;
  g.meanVelocity = cs.meanVelocity + cs.frameShift / h;
  g.maxRelativeSpeed = cs.maxRelativeSpeed;
}

// Sets up the solve's view of the body in slot s.
void prepareBody(BodySlot& b, SolverBody& sb) {
  const BodyModel& m = *b.model;
  for (int a = 0; a < 3; ++a) {
    sb.x[a] = b.state.x.col(a).data();
    sb.v[a] = b.state.v.col(a).data();
  }
  sb.mass = m.mass.data();
  sb.invMass = m.contactInvMass.data();
  sb.count = m.particleCount();
  sb.triangles = &m.surface;
  sb.gap = kContactGap * m.spacing;
  sb.spacing = m.spacing;
  sb.totalMass = float(m.totalMass);
  // A stiff body answers a contact mostly as a whole (contact_solver.h): shape matching couples
  // a particle to its body by α per sub-step. One held by pinned particles cannot move as a
  // whole.
  sb.rigidShare = m.pinned.empty() ? float(b.stepParams.alpha) : 0.0f;
  sb.recoveryShare = m.pinned.empty() ? 1.0f : 0.0f;
  sb.immovable = b.sleep.asleep;
  prepareSolverBody(sb);
}

// A body whose impacts are events of the pair as a whole (soft_impact.h): soft (α < 1) and free
// to move as a whole (no pinned particles).
bool impactsAsAWhole(const BodySlot& b) {
  return b.stepParams.alpha < 1.0 && b.model->pinned.empty();
}

bool lessImpactKey(const ContactScratch::SoftPair& a, const ContactScratch::SoftPair& b) {
  return a.key < b.key;
}

// Adds one contact of a pair that involves a soft body: n out of the obstacle, which is the
// pair's b when `flip` is false.
void addSoftContact(std::vector<ContactScratch::SoftPair>& pairs, const std::array<int, 2>& key,
                    const Vec3f& n, bool flip, float restitution, bool inside) {
  if (pairs.empty() || pairs.back().key != key)
    pairs.push_back({key, Vec3f::Zero(), restitution, false, 0.0f, Vec3f::Zero()});
  pairs.back().normal += flip ? Vec3f(-n) : n;
  pairs.back().meets = pairs.back().meets || inside;
}

// Sorts the touching soft pairs, merges the two directions of a body pair, makes the normals
// unit and takes the centres' relative normal velocity before the solve.
void prepareSoftPairs(std::vector<ContactScratch::SoftPair>& pairs,
                      const std::vector<SolverBody>& bodies, const std::vector<int>& solverIndex) {
  std::stable_sort(pairs.begin(), pairs.end(), lessImpactKey);
  size_t kept = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (kept > 0 && pairs[kept - 1].key == pairs[k].key) {
      pairs[kept - 1].normal += pairs[k].normal;
      pairs[kept - 1].meets = pairs[kept - 1].meets || pairs[k].meets;
      continue;
    }
    pairs[kept++] = pairs[k];
  }
  pairs.resize(kept);
  auto velocityOf = [&](int slot) {
    if (slot < 0) return Vec3f(Vec3f::Zero());  // colliders are static
    const SolverBody& b = bodies[size_t(solverIndex[size_t(slot)])];
    return b.immovable ? Vec3f(Vec3f::Zero()) : b.fitV;
  };
  for (ContactScratch::SoftPair& p : pairs) {
    const float length = p.normal.norm();
    p.normal = length > 0.0f ? Vec3f(p.normal / length) : Vec3f::Zero();
    p.before = (velocityOf(p.key[0]) - velocityOf(p.key[1])).dot(p.normal);
  }
}

// After the solve: the impulse each touching soft pair's contacts gave its body a (the total of
// constraints A and B; either changes the body's momentum by all of it).
void gatherSoftImpulses(std::vector<ContactScratch::SoftPair>& pairs,
                        const std::vector<ContactPoint>& points,
                        const std::vector<int>& solverSlot) {
  if (pairs.empty()) return;
  for (const ContactPoint& cp : points) {
    const int probe = solverSlot[size_t(cp.probe)];
    const int other = cp.obstacle >= 0 ? solverSlot[size_t(cp.obstacle)] : -1 - cp.collider;
    ContactScratch::SoftPair key;
    key.key = cp.obstacle >= 0 ? std::array<int, 2>{std::min(probe, other), std::max(probe, other)}
                               : std::array<int, 2>{probe, other};
    const auto it = std::lower_bound(pairs.begin(), pairs.end(), key, lessImpactKey);
    if (it == pairs.end() || it->key != key.key) continue;      // not a soft pair
    const Vec3f J = (cp.lambda[0] + cp.lambda[1]) * cp.normal;  // on the probe
    it->impulse += probe == key.key[0] ? J : Vec3f(-J);
  }
}

// After the solve: starts, advances and ends the impacts of the touching soft pairs (an impact
// whose pair stopped touching is over) and gives each body the velocity change. A change that
// separates the pair moves the positions with it (x += h·Δv, as in the solve); one that holds
// the pair together (the cap of the release) changes only the velocities and acts from the
// next sub-step on, whose contacts still stop the particles it moves towards the obstacle
// (moving the positions at once pushed the touching particles of a body held after landing up
// to 3 mm into the floor).
void runSoftImpacts(ContactScratch& scratch, std::vector<SolverBody>& bodies,
                    const std::vector<BodySlot>& slots, float h, float threshold) {
  std::vector<SoftImpact>& next = scratch.impactsNext;
  next.clear();
  if (scratch.softPairs.empty()) {
    std::swap(scratch.impacts, next);
    return;
  }
  // Per solver body: the centre's velocity (computed when first needed, for bodies in an
  // impact), and the velocity change and shift the impacts give it.
  const int nb = static_cast<int>(bodies.size());
  std::vector<Vec3f>& centreVelocity = scratch.impactVelocity;
  std::vector<Vec3f>& change = scratch.impactChange;
  std::vector<Vec3f>& shift = scratch.impactShift;
  std::vector<char>& known = scratch.impactKnown;
  centreVelocity.assign(size_t(nb), Vec3f::Zero());
  change.assign(size_t(nb), Vec3f::Zero());
  shift.assign(size_t(nb), Vec3f::Zero());
  known.assign(size_t(nb), 0);
  auto side = [&](int slot, Vec3f& velocity, float& invMass) -> int {
    velocity.setZero();
    invMass = 0;
    if (slot < 0) return -1;
    const int b = scratch.solverIndex[size_t(slot)];
    const SolverBody& body = bodies[size_t(b)];
    if (body.immovable) return -1;
    if (!known[size_t(b)]) {
      known[size_t(b)] = 1;
      centreVelocity[size_t(b)] =
          centreOfMass(PointColumns{{body.v[0], body.v[1], body.v[2]}}, body.mass, body.count)
              .cast<float>();
    }
    velocity = centreVelocity[size_t(b)] + change[size_t(b)];
    // A body held by pinned particles answers as immovable.
    invMass = slots[size_t(slot)].model->pinned.empty() ? body.invTotalMass : 0.0f;
    return b;
  };
  // Bodies touching more than one other body or collider this sub-step (a soft body's every
  // pair is a soft pair): their impacts are not held back. In a pile the holds of many pairs
  // fought each other and the contacts, and bodies were pressed into each other (the soak:
  // ~500 → 7,000 contacts per sub-step within 1,250 steps, steps 10× slower).
  std::vector<int>& pairsOf = scratch.impactPairCount;
  pairsOf.assign(slots.size(), 0);
  for (const ContactScratch::SoftPair& p : scratch.softPairs)
    for (int slot : p.key)
      if (slot >= 0) ++pairsOf[size_t(slot)];
  size_t old = 0;
  for (const ContactScratch::SoftPair& p : scratch.softPairs) {
    while (old < scratch.impacts.size() && scratch.impacts[old].key < p.key) ++old;
    SoftImpact impact;
    if (old < scratch.impacts.size() && scratch.impacts[old].key == p.key) {
      impact = scratch.impacts[old];
      // Until the surfaces meet, u₀ is the fastest approach seen (gravity may still speed the
      // pair up; the speculative contacts only slow it within the solve).
      if (!impact.met) impact.approach = std::max(impact.approach, -p.before);
    } else {
      // An impact starts where the pair comes within reach while the centres approach fast
      // enough.
      if (!(-p.before > threshold) || p.normal == Vec3f::Zero()) continue;
      impact.key = p.key;
      impact.normal = p.normal;
      impact.approach = -p.before;
      impact.restitution = p.restitution;
      double alpha = 1.0;
      for (int slot : p.key)
        if (slot >= 0) alpha = std::min(alpha, slots[size_t(slot)].stepParams.alpha);
      impact.relaxing = relaxSubsteps(alpha);
    }
    Vec3f va, vb;
    float wa, wb;
    const int a = side(impact.key[0], va, wa), b = side(impact.key[1], vb, wb);
    bool alive = false;
    const bool alone = (impact.key[0] < 0 || pairsOf[size_t(impact.key[0])] == 1) &&
                       (impact.key[1] < 0 || pairsOf[size_t(impact.key[1])] == 1);
    const float pushed = alone ? p.impulse.dot(impact.normal) * (wa + wb) : 0.0f;
    const float dv =
        advanceSoftImpact(impact, (va - vb).dot(impact.normal), p.meets, pushed, alive);
    if (!alive) continue;
    next.push_back(impact);
    if (dv == 0.0f || !(wa + wb > 0.0f)) continue;
    const float impulse = dv / (wa + wb);         // N·s along n, on a (−impulse on b)
    const float moved = dv > 0.0f ? 1.0f : 0.0f;  // separating: the positions follow
    if (a >= 0) {
      change[size_t(a)] += (impulse * wa) * impact.normal;
      shift[size_t(a)] += (moved * impulse * wa) * impact.normal;
    }
    if (b >= 0) {
      change[size_t(b)] -= (impulse * wb) * impact.normal;
      shift[size_t(b)] -= (moved * impulse * wb) * impact.normal;
    }
  }
  std::swap(scratch.impacts, next);
  for (int b = 0; b < nb; ++b) {
    if (change[size_t(b)] == Vec3f::Zero()) continue;
    SolverBody& body = bodies[size_t(b)];
    const Vec3f dv = change[size_t(b)], dx = h * shift[size_t(b)];
    for (int i = 0; i < body.count; ++i) {
      if (body.invMass[i] == 0.0f) continue;  // pinned
      for (int k = 0; k < 3; ++k) {
        body.v[k][i] += dv[k];
        body.x[k][i] += dx[k];
      }
    }
  }
}

}  // namespace

void runContactsPhase(const WorkLayout& layout, const ContactSettings& settings, double h,
                      std::vector<BodySlot>& slots, const std::vector<int>& order,
                      const std::vector<Collider>& colliders, ContactScratch& scratch) {
  std::vector<ContactScratch::Body>& contactScratch = scratch.bodies;
  contactScratch.resize(slots.size());
  scratch.pairs.clear();
  scratch.wake.clear();
  scratch.triangleTests = scratch.triangleTestsOfAllPairs = 0;
  ++scratch.substeps;
  const int minParallel = layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX;
  for (int s : order) {
    ContactScratch::Body& cs = contactScratch[size_t(s)];
    cs.obstacle = false;
    cs.involved = false;
    cs.staticHits.clear();
    cs.frameShift = slots[size_t(s)].sleep.asleep ? Vec3f((h * h * settings.gravity).cast<float>())
                                                  : Vec3f::Zero();
  }
  const bool bodyPairs = settings.bodyContact && order.size() >= 2;
  // Bounds and speeds of every body: what the body–body broad and narrow phases need.
  if (bodyPairs)
    parallelFor(static_cast<int>(order.size()), minParallel, [&](int k) {
      const int s = order[size_t(k)];
      const BodyState& st = slots[size_t(s)].state;
      ContactScratch::Body& cs = contactScratch[size_t(s)];
      const bool asleep = slots[size_t(s)].sleep.asleep;
      if (asleep && cs.boundsWhileAsleep) return;
      cs.boundsWhileAsleep = asleep;
      const BodyModel& m = *slots[size_t(s)].model;
      cs.box.setEmpty();
      Eigen::Vector3f momentum = Eigen::Vector3f::Zero();
      for (int i = 0; i < st.x.rows(); ++i) {
        cs.box.extend(st.x.row(i).transpose());
        momentum += m.mass[i] * st.v.row(i).transpose();
      }
      cs.meanVelocity = momentum / float(m.totalMass);
      float speed2 = 0, relative2 = 0;
      for (int i = 0; i < st.x.rows(); ++i) {
        speed2 = std::max(speed2, st.v.row(i).squaredNorm());
        relative2 = std::max(relative2, (st.v.row(i).transpose() - cs.meanVelocity).squaredNorm());
      }
      cs.maxSpeed = std::sqrt(speed2);
      cs.maxRelativeSpeed = std::sqrt(relative2);
    });

  // Static colliders: every particle of an awake body within the margin plus its sub-step's
  // travel of one (per body, in parallel).
  if (!colliders.empty()) {
    parallelForClaimed(static_cast<int>(order.size()), minParallel, [&](int k) {
      const int s = order[size_t(k)];
      if (slots[size_t(s)].sleep.asleep) return;
      ContactScratch::Body& cs = contactScratch[size_t(s)];
      const BodyState& st = slots[size_t(s)].state;
      const double margin = kContactMargin * slots[size_t(s)].model->spacing;
      // Only the colliders the body's box comes within its fastest particle's reach of (in a
      // walled pen most bodies are far from most walls: seed-scale.json).
      if (st.x.rows() == 0) return;
      const Eigen::AlignedBox3d box(st.x.colwise().minCoeff().transpose().cast<double>(),
                                    st.x.colwise().maxCoeff().transpose().cast<double>());
      const double farthest = margin + h * double(st.v.rowwise().norm().maxCoeff());
      std::vector<int>& near = cs.nearColliders;
      near.clear();
      for (size_t c = 0; c < colliders.size(); ++c)
        if (!box.sizes().allFinite() ||
            !(colliderDistanceLowerBound(colliders[c], box) >= farthest))
          near.push_back(int(c));
      for (int p = 0; p < st.x.rows() && !near.empty(); ++p) {
        const Vec3 x = st.x.row(p).transpose().cast<double>();
        const double reach = margin + h * double(st.v.row(p).norm());
        for (int c : near) {
          Vec3 n;
          double d = colliderDistance(colliders[size_t(c)], x, &n);
          // Only within reach (the look-up reads the other colliders): is the point it meets
          // buried in another collider?
          if (d < reach && moveOntoExposedSurface(colliders, c, x, &d, &n) && d < reach)
            cs.staticHits.push_back({p, c, float(d), n.cast<float>()});
        }
      }
    });
  }
  if (!bodyPairs) return;

  // A particle of body s moves at most h·speedOf(s) in this sub-step (a sleeping body's speed
  // is that of its detection frame, frameShift / h). Each body's box grows by its own surface
  // reach (the margin) plus twice its own travel, so no pair that can touch within the
  // sub-step is missed; each particle then looks only as far as its own speed needs
  // (findContacts). (Growing every box by the fastest body's travel made each body of a pile
  // under a falling layer a probe in 18 pairs instead of 12: seed-scale.json.)
  auto speedOf = [&](int s) {
    const ContactScratch::Body& cs = contactScratch[size_t(s)];
    return cs.maxSpeed + cs.frameShift.norm() / float(h);
  };
  auto reachOf = [&](int s) {
    const BodyModel& m = *slots[size_t(s)].model;
    return m.surface.empty() ? 0.0f : (kContactGap + kContactMargin) * m.spacing;
  };
  auto grown = [&](int s) {
    Eigen::AlignedBox3f box = detectionBox(contactScratch[size_t(s)]);
    const float by = reachOf(s) + 2.0f * float(h) * speedOf(s);
    box.min().array() -= by;
    box.max().array() += by;
    return box;
  };

  // Broad phase: sweep over the grown boxes sorted along x; pairs come out in creation order.
  // Two sleeping bodies do not meet (nothing between them changes).
  std::vector<int>& sweep = scratch.sweep;
  std::vector<Eigen::AlignedBox3f>& boxes = scratch.boxes;
  std::vector<int>& rank = scratch.rank;
  std::vector<ContactScratch::Pair>& contactPairs = scratch.pairs;
  sweep.assign(order.begin(), order.end());
  boxes.resize(slots.size());
  for (int s : order) boxes[size_t(s)] = grown(s);
  rank.resize(slots.size());
  for (size_t k = 0; k < order.size(); ++k) rank[size_t(order[k])] = int(k);
  std::sort(sweep.begin(), sweep.end(), [&](int a, int b) {
    const float ma = boxes[size_t(a)].min().x(), mb = boxes[size_t(b)].min().x();
    return ma != mb ? ma < mb : rank[size_t(a)] < rank[size_t(b)];
  });
  for (size_t i = 0; i < sweep.size(); ++i) {
    const int a = sweep[i];
    for (size_t j = i + 1; j < sweep.size(); ++j) {
      const int b = sweep[j];
      if (boxes[size_t(b)].min().x() > boxes[size_t(a)].max().x()) break;
      if (!boxes[size_t(a)].intersects(boxes[size_t(b)])) continue;
      if (slots[size_t(a)].sleep.asleep && slots[size_t(b)].sleep.asleep) continue;
      const int first = rank[size_t(a)] < rank[size_t(b)] ? a : b;
      const int second = first == a ? b : a;
      if (!slots[size_t(second)].model->surface.empty()) contactPairs.push_back({first, second});
      if (!slots[size_t(first)].model->surface.empty()) contactPairs.push_back({second, first});
    }
  }
  std::sort(contactPairs.begin(), contactPairs.end(),
            [&](const ContactScratch::Pair& x, const ContactScratch::Pair& y) {
              const int xa = std::min(rank[size_t(x.probe)], rank[size_t(x.obstacle)]);
              const int ya = std::min(rank[size_t(y.probe)], rank[size_t(y.obstacle)]);
              if (xa != ya) return xa < ya;
              const int xb = std::max(rank[size_t(x.probe)], rank[size_t(x.obstacle)]);
              const int yb = std::max(rank[size_t(y.probe)], rank[size_t(y.obstacle)]);
              if (xb != yb) return xb < yb;
              return rank[size_t(x.probe)] < rank[size_t(y.probe)];
            });
  if (contactPairs.empty()) {
    scratch.deepPairs.clear();
    return;
  }

  // Each obstacle's grid covers only where its probes' particles are.
  for (const ContactScratch::Pair& p : contactPairs) {
    ContactScratch::Body& cs = contactScratch[size_t(p.obstacle)];
    if (!cs.obstacle) cs.region.setEmpty();
    cs.obstacle = true;
    // As far as a probe particle looks beyond the base reach (findContacts: h·(|v − v̄ₒ| +
    // the obstacle's fastest relative speed), with |v̄ₒ| ≤ speed and relative speeds ≤ 2·speed).
    Eigen::AlignedBox3f probeBox = detectionBox(contactScratch[size_t(p.probe)]);
    const float look = float(h) * (speedOf(p.probe) + 3.0f * speedOf(p.obstacle));
    probeBox.min().array() -= look;
    probeBox.max().array() += look;
    cs.region.extend(probeBox);
    for (int s : {p.probe, p.obstacle}) contactScratch[size_t(s)].involved = true;
  }
  for (int s : order)
    if (contactScratch[size_t(s)].involved)
      prepareGeometry(slots[size_t(s)], float(h), contactScratch[size_t(s)]);
  // An obstacle's grid, over the region its probes' particles look into (built by the thread
  // that then runs the obstacle's pairs, below).
  auto buildGrid = [&](int s) {
    const BodyModel& m = *slots[size_t(s)].model;
    ContactScratch::Body& cs = contactScratch[size_t(s)];
    const MatX3f& x = slots[size_t(s)].sleep.asleep ? cs.detectX : slots[size_t(s)].state.x;
    // The grid is kept while the surface has moved less than a quarter spacing since it was
    // built and the region still fits: lookups then widen by that drift (findContacts), so
    // resting and slowly moving bodies skip the rebuild.
    float drift = 0;
    const bool sameSurface = cs.gridModel == &m;
    const bool reusable = sameSurface && cs.gridRegion.contains(cs.region);
    if (reusable) drift = std::sqrt((x - cs.gridPositions).rowwise().squaredNorm().maxCoeff());
    if (!reusable || !(drift <= kGridSlack * m.spacing)) {
      cs.gridRegion = cs.region;
      cs.gridRegion.min().array() -= kGridSlack * m.spacing;
      cs.gridRegion.max().array() += kGridSlack * m.spacing;
      // Cells of one spacing: a triangle grown by its reach and the look-ahead (about half a
      // spacing on each side) lands in a few cells per axis, and most of a cell's triangles are
      // rejected by their bounds without the exact test.
      cs.grid.build(m.surface, x.col(0).data(), x.col(1).data(), x.col(2).data(), reachOf(s),
                    m.spacing, cs.gridRegion, sameSurface, kGridLookAhead * m.spacing);
      cs.gridPositions = x;
      cs.gridModel = &m;
      cs.gridBuiltAt = scratch.substeps;
      drift = 0;
    }
    cs.geometry.gridDrift = drift;
  };

  // A pair's clearances from the last sub-step, if its obstacle's grid is the same (after that
  // grid's build). Keys are unique, so each pair swaps with its own old entry.
  std::vector<ContactScratch::PairClearance>& clearances = scratch.clearancesNext;
  clearances.resize(contactPairs.size());
  auto carryClearances = [&](size_t k) {
    ContactScratch::PairClearance& c = clearances[k];
    c.key = {contactPairs[k].probe, contactPairs[k].obstacle};
    c.gridBuiltAt = contactScratch[size_t(c.key.second)].gridBuiltAt;
    const auto last = std::lower_bound(scratch.clearances.begin(), scratch.clearances.end(), c.key,
                                       [](const ContactScratch::PairClearance& x,
                                          const std::pair<int, int>& key) { return x.key < key; });
    if (last != scratch.clearances.end() && last->key == c.key &&
        last->gridBuiltAt == c.gridBuiltAt)
      std::swap(c.probe, last->probe);
    else
      c.probe.particles.clear();
  };

  // Narrow phase: each pair reads both bodies and its obstacle's grid and writes only its own
  // slot, so pairs run in parallel in any order.
  std::vector<std::vector<Contact>>& pairContacts = scratch.pairContacts;
  pairContacts.resize(contactPairs.size());
  scratch.pairDeep.assign(contactPairs.size(), 0);
  scratch.pairTests.assign(contactPairs.size(), 0);
  const bool deepRound = scratch.substeps % kDeepSearchEvery == 0;
  const bool creases = contactsCanRest(settings, h);
  // Pairs are looked at obstacle by obstacle (each obstacle's probes in pair order), so that an
  // obstacle's grid, triangle bounds and positions are still in cache for its next probe. In pair
  // order the other pairs in between evicted them: the seed-scale pile's contact phase took 5-8 %
  // longer (the large scene's, whose grids all fit in cache, the same).
  std::vector<int>& visitOrder = scratch.pairVisitOrder;
  visitOrder.resize(contactPairs.size());
  for (size_t k = 0; k < visitOrder.size(); ++k) visitOrder[k] = int(k);
  std::sort(visitOrder.begin(), visitOrder.end(), [&](int a, int b) {
    const int x = contactPairs[size_t(a)].obstacle, y = contactPairs[size_t(b)].obstacle;
    return x != y ? x < y : a < b;
  });
  auto visitPair = [&](int k) {
    const ContactScratch::Pair& p = contactPairs[size_t(k)];
    pairContacts[size_t(k)].clear();
    if (slots[size_t(p.probe)].sleep.asleep && slots[size_t(p.obstacle)].sleep.asleep) return;
    const bool deep =
        deepRound || std::binary_search(scratch.deepPairs.begin(), scratch.deepPairs.end(),
                                        std::make_pair(p.probe, p.obstacle));
    const ContactScratch::Body& probe = contactScratch[size_t(p.probe)];
    const ContactScratch::Body& obstacle = contactScratch[size_t(p.obstacle)];
    // The way out of an obstacle the probe overlaps by more than half: away from its centre, or,
    // for bodies that coincide, up for the body in the lower slot and down for the other.
    Vec3f apart = probe.geometry.box.center() - obstacle.geometry.box.center();
    const float size = probe.geometry.box.sizes().norm() + obstacle.geometry.box.sizes().norm();
    if (apart.norm() > 1e-4f * size)
      apart.normalize();
    else
      apart = Vec3f(0, p.probe < p.obstacle ? 1.0f : -1.0f, 0);
    std::vector<Contact>& found = pairContacts[size_t(k)];
    scratch.pairDeep[size_t(k)] =
        findContacts(probe.geometry, obstacle.geometry, float(h), deep, creases, apart, found,
                     &scratch.pairTests[size_t(k)], &clearances[size_t(k)].probe);
    // Distances found in the detection's frame, carried back to the actual positions (the
    // solver's start). One side at most is shifted, all of it by the same vector.
    const Vec3f shift = probe.frameShift - obstacle.frameShift;
    if (shift != Vec3f::Zero())
      for (Contact& c : found) c.distance -= c.normal.dot(shift);
  };
  // One obstacle at a time per thread: its grid, then its pairs. The obstacles go to whichever
  // thread is free (parallelForClaimed), since they differ widely in cost (a grid rebuilt or
  // kept, one probe or twenty): cut in two fixed halves, one thread waited for the other
  // (measured in docs/design.md §5.5).
  std::vector<int>& groups = scratch.obstacleVisits;
  groups.clear();
  for (size_t v = 0; v < visitOrder.size(); ++v)
    if (v == 0 || contactPairs[size_t(visitOrder[v])].obstacle !=
                      contactPairs[size_t(visitOrder[v - 1])].obstacle)
      groups.push_back(int(v));
  groups.push_back(int(visitOrder.size()));
  parallelForClaimed(int(groups.size()) - 1, minParallel, [&](int g) {
    const int begin = groups[size_t(g)], end = groups[size_t(g) + 1];
    buildGrid(contactPairs[size_t(visitOrder[size_t(begin)])].obstacle);
    for (int v = begin; v < end; ++v) {
      carryClearances(size_t(visitOrder[size_t(v)]));
      visitPair(visitOrder[size_t(v)]);
    }
  });
  scratch.deepPairs.clear();
  for (size_t k = 0; k < contactPairs.size(); ++k) {
    const ContactScratch::Pair& p = contactPairs[k];
    scratch.triangleTests += scratch.pairTests[k];
    if (!(slots[size_t(p.probe)].sleep.asleep && slots[size_t(p.obstacle)].sleep.asleep))
      scratch.triangleTestsOfAllPairs +=
          long(contactScratch[size_t(p.probe)].geometry.count) *
          long(contactScratch[size_t(p.obstacle)].geometry.triangles->size());
    if (scratch.pairDeep[k])
      scratch.deepPairs.push_back({contactPairs[k].probe, contactPairs[k].obstacle});
    // An awake body touching a sleeping one wakes it (and its island).
    if (pairContacts[k].empty()) continue;
    for (int s : {contactPairs[k].probe, contactPairs[k].obstacle})
      if (slots[size_t(s)].sleep.asleep) scratch.wake.push_back(s);
  }
  std::sort(scratch.deepPairs.begin(), scratch.deepPairs.end());
  std::sort(clearances.begin(), clearances.end(),
            [](const ContactScratch::PairClearance& x, const ContactScratch::PairClearance& y) {
              return x.key < y.key;
            });
  std::swap(scratch.clearances, clearances);
}

// Rolling resistance (contact/rolling_resistance.h; docs/design.md §5.5), after the solve and
// the impacts: each pair that touched in this sub-step (a body and a collider, or two bodies)
// exchanges a couple against its relative spin, up to c·ρ times the normal impulse its contacts
// carried (ρ the smaller rest radius of gyration). It acts on the velocities only, as damping
// does, by Δω × (x − xc) on every particle: the spin is taken from the particles' velocities as
// they are now (the solve's fitted spin is linear about the sub-step's start and, at one-second
// sub-steps, far from the particles' own), so each couple can only take energy away. Pairs go
// in key order, each seeing the spin the earlier ones left. Sleeping and pinned bodies take no
// couple, and the other side of their pair counts them as not spinning (so a ball on a swinging
// pinned bar is resisted against its own spin, not against the bar's).
void resistRolling(ContactScratch& scratch, const std::vector<SolverBody>& bodies,
                   std::vector<BodySlot>& slots, float coefficient, int minParallel) {
  const std::vector<int>& solverSlot = scratch.solverSlot;
  std::vector<ContactScratch::RollingPair>& pairs = scratch.rollingPairs;
  pairs.clear();
  for (const ContactPoint& cp : scratch.points) {
    const float load = cp.lambda[0] + cp.lambda[1];
    if (!(load > 0.0f)) continue;
    const std::pair<int, int> key =
        cp.obstacle < 0
            ? std::make_pair(cp.probe, -1 - cp.collider)
            : std::make_pair(std::min(cp.probe, cp.obstacle), std::max(cp.probe, cp.obstacle));
    pairs.push_back({key, load});
  }
  if (pairs.empty()) return;
  // In key order; a pair's loads summed in point order (stable), so the bits are the same
  // for any thread count.
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const auto& a, const auto& b) { return a.key < b.key; });
  size_t merged = 0;
  for (size_t k = 1; k < pairs.size(); ++k)
    if (pairs[k].key == pairs[merged].key)
      pairs[merged].load += pairs[k].load;
    else
      pairs[++merged] = pairs[k];
  pairs.resize(merged + 1);

  const int nb = static_cast<int>(bodies.size());
  scratch.rollingMotion.resize(size_t(nb));
  scratch.rollingSpinChange.assign(size_t(nb), Vec3::Zero());
  scratch.rollingTurns.assign(size_t(nb), 0);
  for (const auto& pair : pairs) {
    scratch.rollingTurns[size_t(pair.key.first)] = 1;
    if (pair.key.second >= 0) scratch.rollingTurns[size_t(pair.key.second)] = 1;
  }
  parallelFor(nb, minParallel, [&](int b) {
    const BodySlot& slot = slots[size_t(solverSlot[size_t(b)])];
    char& turns = scratch.rollingTurns[size_t(b)];
    turns = turns && !bodies[size_t(b)].immovable && slot.model->pinned.empty();
    if (!turns) return;
    const BodyState& s = slot.state;
    scratch.rollingMotion[size_t(b)] =
        rigidMotion(PointColumns{{s.x.col(0).data(), s.x.col(1).data(), s.x.col(2).data()}},
                    PointColumns{{s.v.col(0).data(), s.v.col(1).data(), s.v.col(2).data()}},
                    slot.model->mass.data(), slot.model->particleCount());
  });

  for (const auto& pair : pairs) {
    const int a = pair.key.first, b = pair.key.second;
    const bool aTurns = scratch.rollingTurns[size_t(a)] != 0;
    const bool bTurns = b >= 0 && scratch.rollingTurns[size_t(b)] != 0;
    if (!aTurns && !bTurns) continue;
    auto spinOf = [&](int body, bool turns) -> Vec3 {
      return turns ? Vec3(scratch.rollingMotion[size_t(body)].omega +
                          scratch.rollingSpinChange[size_t(body)])
                   : Vec3::Zero();
    };
    auto invInertiaOf = [&](int body, bool turns) -> Mat3 {
      return turns ? scratch.rollingMotion[size_t(body)].inverseInertia : Mat3::Zero();
    };
    float lever = coefficient * slots[size_t(solverSlot[size_t(a)])].model->gyrationRadius;
    if (b >= 0)
      lever =
          std::min(lever, coefficient * slots[size_t(solverSlot[size_t(b)])].model->gyrationRadius);
    const Vec3 couple =
        rollingCouple(invInertiaOf(a, aTurns), invInertiaOf(b, bTurns),
                      spinOf(a, aTurns) - spinOf(b, bTurns), double(lever) * pair.load);
    if (aTurns)
      scratch.rollingSpinChange[size_t(a)] +=
          scratch.rollingMotion[size_t(a)].inverseInertia * couple;
    if (bTurns)
      scratch.rollingSpinChange[size_t(b)] -=
          scratch.rollingMotion[size_t(b)].inverseInertia * couple;
  }

  parallelFor(nb, minParallel, [&](int b) {
    const Vec3f dw = scratch.rollingSpinChange[size_t(b)].cast<float>();
    if (!scratch.rollingTurns[size_t(b)] || dw == Vec3f::Zero()) return;
    BodyState& s = slots[size_t(solverSlot[size_t(b)])].state;
    const Vec3f c = scratch.rollingMotion[size_t(b)].centre.cast<float>();
    for (int i = 0; i < s.x.rows(); ++i)
      s.v.row(i) += dw.cross(Vec3f(s.x.row(i).transpose() - c)).transpose();
  });
}

int runSolvePhase(const WorkLayout& layout, const ContactSettings& settings, double h,
                  std::vector<BodySlot>& slots, const std::vector<int>& order,
                  const std::vector<Collider>& colliders, ContactScratch& scratch) {
  std::vector<ContactScratch::Body>& contactScratch = scratch.bodies;
  const std::vector<ContactScratch::Pair>& contactPairs = scratch.pairs;
  scratch.touching.clear();
  scratch.activeContacts = 0;
  scratch.sweepVisits = scratch.skippedVisits = 0;
  scratch.deepestContact = 0;
  // The bodies of the solve: those with a contact, in creation order.
  std::vector<SolverBody>& bodies = scratch.solverBodies;
  std::vector<int>& solverIndex = scratch.solverIndex;
  std::vector<int>& solverSlot = scratch.solverSlot;
  solverIndex.assign(slots.size(), -1);
  solverSlot.clear();
  auto enlist = [&](int s) {
    if (solverIndex[size_t(s)] < 0) solverIndex[size_t(s)] = 1;
  };
  for (size_t k = 0; k < contactPairs.size(); ++k)
    if (!scratch.pairContacts[k].empty()) {
      enlist(contactPairs[k].probe);
      enlist(contactPairs[k].obstacle);
    }
  for (int s : order)
    if (!contactScratch[size_t(s)].staticHits.empty()) enlist(s);
  for (int s : order)
    if (solverIndex[size_t(s)] >= 0) {
      solverIndex[size_t(s)] = int(solverSlot.size());
      solverSlot.push_back(s);
    }
  if (solverSlot.empty()) {
    scratch.warm.clear();
    scratch.impacts.clear();  // nothing touches: every impact is over
    return 0;
  }
  bodies.resize(solverSlot.size());
  const int minParallel = layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX;
  parallelFor(static_cast<int>(solverSlot.size()), minParallel,
              [&](int k) { prepareBody(slots[size_t(solverSlot[size_t(k)])], bodies[size_t(k)]); });

  // Every contact point: body–body in pair order, then static in body order; restitution the
  // larger of the two sides' (as Box2D), friction the body–body or the collider's.
  std::vector<ContactPoint>& points = scratch.points;
  points.clear();
  std::vector<ContactScratch::SoftPair>& softPairs = scratch.softPairs;
  softPairs.clear();
  for (size_t k = 0; k < contactPairs.size(); ++k) {
    const ContactScratch::Pair& pair = contactPairs[k];
    const BodySlot& probe = slots[size_t(pair.probe)];
    const BodySlot& obstacle = slots[size_t(pair.obstacle)];
    const float gap = kContactGap * obstacle.model->spacing;
    const float e = float(std::max(probe.stepParams.restitution, obstacle.stepParams.restitution));
    // A pair with a soft body bounces as a whole (soft_impact.h); its contacts are inelastic.
    const bool soft = impactsAsAWhole(probe) || impactsAsAWhole(obstacle);
    const std::array<int, 2> key{std::min(pair.probe, pair.obstacle),
                                 std::max(pair.probe, pair.obstacle)};
    for (const Contact& c : scratch.pairContacts[k]) {
      ContactPoint cp;
      cp.probe = solverIndex[size_t(pair.probe)];
      cp.obstacle = solverIndex[size_t(pair.obstacle)];
      cp.particle = c.particle;
      cp.triangle = c.triangle;
      cp.weights = c.weights;
      cp.normal = c.normal;
      cp.distance0 = c.distance - gap;
      cp.friction = settings.friction;
      cp.restitution = soft ? 0.0f : e;
      points.push_back(cp);
      if (soft)
        addSoftContact(softPairs, key, c.normal, key[0] != pair.probe, e, cp.distance0 < 0.0f);
    }
  }
  for (int s : order)
    for (const ContactScratch::StaticHit& hit : contactScratch[size_t(s)].staticHits) {
      const Collider& collider = colliders[size_t(hit.collider)];
      ContactPoint cp;
      cp.probe = solverIndex[size_t(s)];
      cp.particle = hit.particle;
      cp.collider = hit.collider;
      cp.normal = hit.normal;
      cp.distance0 = hit.distance;
      cp.friction = float(collider.friction);
      const float e =
          float(std::max(collider.restitution, slots[size_t(s)].stepParams.restitution));
      const bool soft = impactsAsAWhole(slots[size_t(s)]);
      cp.restitution = soft ? 0.0f : e;
      points.push_back(cp);
      if (soft)
        addSoftContact(softPairs, {s, -1 - hit.collider}, hit.normal, false, e,
                       cp.distance0 < 0.0f);
    }

  // Warm start: the impulses each contact carried at the last sub-step.
  auto keyOf = [&](const ContactPoint& cp) {
    return std::array<int, 3>{solverSlot[size_t(cp.probe)],
                              cp.obstacle >= 0 ? solverSlot[size_t(cp.obstacle)] : -1 - cp.collider,
                              cp.particle};
  };
  for (ContactPoint& cp : points) {
    ContactScratch::Warm probe;
    probe.key = keyOf(cp);
    const auto it = std::lower_bound(scratch.warm.begin(), scratch.warm.end(), probe, lessKey);
    if (it == scratch.warm.end() || it->key != probe.key) continue;
    for (int j = 0; j < 2; ++j) {
      cp.lambda[j] = it->lambda[j];
      cp.tangent[j] = it->tangent[j];
    }
    cp.warmResting = it->resting;
    cp.warmDistance0 = it->distance0;
    cp.warmSteadySubsteps = it->steadySubsteps;
  }

  // Islands: bodies joined by body–body contacts, sleeping bodies (immovable) joining nothing.
  const int nb = static_cast<int>(bodies.size());
  std::vector<int>& parent = scratch.islandParent;
  parent.resize(size_t(nb));
  for (int b = 0; b < nb; ++b) parent[size_t(b)] = b;
  for (const ContactPoint& cp : points) {
    if (cp.obstacle < 0 || bodies[size_t(cp.probe)].immovable ||
        bodies[size_t(cp.obstacle)].immovable)
      continue;
    const int a = findRoot(parent, cp.probe), b = findRoot(parent, cp.obstacle);
    if (a != b) parent[size_t(std::max(a, b))] = std::min(a, b);
  }
  std::vector<int> islandOf(size_t(nb), -1);
  int islands = 0;
  for (int b = 0; b < nb; ++b) {
    if (bodies[size_t(b)].immovable) continue;
    const int root = findRoot(parent, b);
    if (islandOf[size_t(root)] < 0) islandOf[size_t(root)] = islands++;
    islandOf[size_t(b)] = islandOf[size_t(root)];
  }
  scratch.islandBodies.resize(size_t(islands));
  scratch.islandPoints.resize(size_t(islands));
  for (int i = 0; i < islands; ++i) {
    scratch.islandBodies[size_t(i)].clear();
    scratch.islandPoints[size_t(i)].clear();
  }
  for (int b = 0; b < nb; ++b)
    if (islandOf[size_t(b)] >= 0) scratch.islandBodies[size_t(islandOf[size_t(b)])].push_back(b);
  for (int k = 0; k < static_cast<int>(points.size()); ++k) {
    const ContactPoint& cp = points[size_t(k)];
    // With the island of its movable side (detection pairs no two sleeping bodies).
    const int side = bodies[size_t(cp.probe)].immovable ? cp.obstacle : cp.probe;
    scratch.islandPoints[size_t(islandOf[size_t(side)])].push_back(k);
  }

  // A body resting on another meets it at |g|·h every sub-step (what gravity adds in one), so
  // approaches below twice that are resting contact, not impacts, whatever the threshold: at
  // long sub-steps (|g|·h = 9.8 m/s at 1 s) bouncing them pumped energy into every resting body
  // with restitution (restitution.json at 1-s sub-steps reached 10⁹ J). At the shipped
  // 1/240 s, 2|g|h = 0.08 m/s, below the default threshold of 1 m/s.
  const float threshold =
      std::max(settings.restitutionThreshold, float(restingApproach(settings, h)));
  ContactSolverSettings solver;
  solver.h = float(h);
  solver.restitutionThreshold = threshold;
  // Resting contacts (ContactPoint::resting): the bodies approach by about what gravity added
  // in the sub-step, |g|·h; below twice that, as for restitution. Only at sub-steps short
  // enough that this is slow (2|g|h ≤ kRestingSpeedLimit; 0.08 m/s at the shipped 1/240 s):
  // at long ones a sub-step's gravity alone is an impact, and particles must be stopped one by
  // one (the seed-scale pile at 1-s sub-steps strayed 0.66–0.84 of a diagonal from its bodies'
  // shapes with resting contacts, 0.6 allowed).
  solver.restingSpeed = contactsCanRest(settings, h) ? float(restingApproach(settings, h))
                                                     : -std::numeric_limits<float>::infinity();
  solver.up = settings.gravity.squaredNorm() > 0.0
                  ? Vec3f((-settings.gravity.normalized()).cast<float>())
                  : Vec3f::Zero();
  prepareSoftPairs(softPairs, bodies, solverIndex);
  // Islands share no movable body, so any order gives the same results: the small ones in
  // parallel, then each large one on all threads.
  std::vector<int> small, large;
  for (int i = 0; i < islands; ++i)
    (scratch.islandPoints[size_t(i)].size() >= size_t(kMinParallelSweep) ? large : small)
        .push_back(i);
  auto solve = [&](int i) {
    solveIsland(bodies, points, scratch.islandBodies[size_t(i)], scratch.islandPoints[size_t(i)],
                colliders, solver);
  };
  parallelForClaimed(static_cast<int>(small.size()), minParallel,
                     [&](int k) { solve(small[size_t(k)]); });
  for (int i : large) solve(i);
  parallelFor(nb, minParallel, [&](int b) {
    if (!bodies[size_t(b)].immovable) finishSolverBody(bodies[size_t(b)]);
  });
  gatherSoftImpulses(softPairs, points, solverSlot);
  runSoftImpacts(scratch, bodies, slots, float(h), threshold);
  if (settings.rollingResistance > 0.0f)
    resistRolling(scratch, bodies, slots, settings.rollingResistance, minParallel);

  for (int i = 0; i < islands; ++i) {
    scratch.sweepVisits += long(kVelocitySweeps) * long(scratch.islandPoints[size_t(i)].size());
    for (int k : scratch.islandPoints[size_t(i)])
      scratch.skippedVisits += points[size_t(k)].skippedVisits;
  }

  // Keep the impulses for the next sub-step; report the pairs that touched and the contacts
  // that carried load.
  std::vector<ContactScratch::Warm>& next = scratch.warmNext;
  next.clear();
  for (const ContactPoint& cp : points) {
    if (cp.obstacle >= 0) {
      const std::pair<int, int> pair{solverSlot[size_t(cp.probe)], solverSlot[size_t(cp.obstacle)]};
      if (scratch.touching.empty() || scratch.touching.back() != pair)
        scratch.touching.push_back(pair);
    }
    if (!(cp.lambda[0] > 0.0f || cp.lambda[1] > 0.0f)) continue;
    if (cp.obstacle >= 0) ++scratch.activeContacts;
    scratch.deepestContact = std::max(scratch.deepestContact, -cp.distance0);
    ContactScratch::Warm w;
    w.key = keyOf(cp);
    for (int j = 0; j < 2; ++j) {
      w.lambda[j] = cp.lambda[j];
      w.tangent[j] = cp.tangent[j];
    }
    w.resting = cp.resting;
    w.distance0 = cp.distance0;
    w.steadySubsteps = cp.steadySubsteps;
    next.push_back(w);
  }
  std::sort(next.begin(), next.end(), lessKey);
  std::swap(scratch.warm, next);
  return scratch.activeContacts;
}

}  // namespace sb
