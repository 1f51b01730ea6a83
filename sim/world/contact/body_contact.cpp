#include "sim/world/contact/body_contact.h"

#include <cmath>
#include <limits>

#include "sim/world/mass_properties.h"

namespace sb {

namespace {

// The contact path's closest point on a triangle: Ericson's form throughout, including the
// dot-product weights inside the face, where mesh::closestPointOnTriangle uses cross products.
// Kept as it was so that the library layout change leaves contact results (and their cost)
// unchanged; it goes when contacts move to the shared kernel with the contact rework, whose
// results change anyway.
mesh::TrianglePoint<float> closestPointForContact(const Vec3f& p, const Vec3f& a, const Vec3f& b,
                                                  const Vec3f& c) {
  using mesh::TriangleFeature;
  const Vec3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return {Vec3f(1, 0, 0), TriangleFeature::Vertex0};
  const Vec3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return {Vec3f(0, 1, 0), TriangleFeature::Vertex1};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float t = d1 / (d1 - d3);
    return {Vec3f(1 - t, t, 0), TriangleFeature::Edge0};
  }
  const Vec3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return {Vec3f(0, 0, 1), TriangleFeature::Vertex2};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float t = d2 / (d2 - d6);
    return {Vec3f(1 - t, 0, t), TriangleFeature::Edge2};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f) {
    const float t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {Vec3f(0, 1 - t, t), TriangleFeature::Edge1};
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) return {Vec3f(1, 0, 0), TriangleFeature::Vertex0};  // collapsed triangle
  const float v = vb / sum, w = vc / sum;
  return {Vec3f(1 - v - w, v, w), TriangleFeature::Face};
}

}  // namespace

void findContacts(const ContactBody& probe, const ContactBody& obstacle, float h,
                  std::vector<Contact>& out) {
  const std::vector<mesh::Triangle>& tris = *obstacle.triangles;
  const SurfaceGrid& grid = *obstacle.grid;
  if (grid.empty()) return;  // no triangle near any probe
  // No particle moves further relative to the obstacle than this in the sub-step: particles
  // outside the grid's bounds grown by it are skipped before any per-particle arithmetic.
  const float drift = obstacle.gridDrift;
  const float maxExtra =
      h * (probe.maxRelativeSpeed + (probe.meanVelocity - obstacle.meanVelocity).norm() +
           obstacle.maxRelativeSpeed) +
      drift;
  Eigen::AlignedBox3f near = grid.bounds();
  near.min().array() -= maxExtra;
  near.max().array() += maxExtra;
  for (int i = 0; i < probe.count; ++i) {
    const Vec3f p = probe.position(i);
    if (!near.contains(p)) continue;
    const float extra =
        h * ((probe.velocity(i) - obstacle.meanVelocity).norm() + obstacle.maxRelativeSpeed);
    // Only triangles within reach + extra of p matter: a closest point farther than that might
    // not be the surface's closest point (the grid holds every triangle within that distance,
    // no more), so such a particle is left alone — it is far outside, or deeper inside than it
    // can have got in one sub-step.
    const float reach = grid.reach() + extra;
    float best = reach * reach;
    int bestTriangle = -1;
    mesh::TrianglePoint<float> bestPoint{};
    Vec3f bestClosest = Vec3f::Zero();
    // The grid and its triangle boxes are from positions up to `drift` old: look that much
    // further, and a box may be that much closer than its triangle is now.
    float bound = drift > 0.0f ? (reach + drift) * (reach + drift) : best;
    grid.forEachCell(p, extra + drift, [&](const SurfaceGrid::Range& range) {
      for (const int* t = range.begin; t != range.end; ++t) {
        if (grid.boxDistanceSquared(*t, p) > bound) continue;  // cannot be closer
        const mesh::Triangle& tri = tris[size_t(*t)];
        const Vec3f a = obstacle.position(tri[0]), b = obstacle.position(tri[1]),
                    c = obstacle.position(tri[2]);
        const mesh::TrianglePoint<float> q = closestPointForContact(p, a, b, c);
        const Vec3f closest = q.weights[0] * a + q.weights[1] * b + q.weights[2] * c;
        const float d2 = (p - closest).squaredNorm();
        if (d2 < best || (d2 == best && *t < bestTriangle)) {  // ties: lowest index, any order
          best = d2;
          bound = drift > 0.0f ? (std::sqrt(d2) + drift) * (std::sqrt(d2) + drift) : d2;
          bestTriangle = *t;
          bestPoint = q;
          bestClosest = closest;
        }
      }
    });
    if (bestTriangle < 0) continue;
    const Vec3f side = mesh::pseudoNormal(tris, *obstacle.topology, obstacle.x[0], obstacle.x[1],
                                    obstacle.x[2], bestTriangle, bestPoint.feature);
    const Vec3f offset = p - bestClosest;
    const bool inside = offset.dot(side) < 0.0f;
    const float distance = std::sqrt(best);
    if (!inside && distance >= obstacle.gap) continue;
    Vec3f normal;
    if (distance > 1e-6f * obstacle.gap + std::numeric_limits<float>::min()) {
      normal = (inside ? -offset : offset) / distance;
    } else {
      const float len = side.norm();
      if (!(len > 0.0f)) continue;  // collapsed surface: no usable direction
      normal = side / len;
    }
    out.push_back({i, bestTriangle, bestPoint.weights, normal});
  }
}

void prepareRigidResponse(ContactBody& body, float rigidShare) {
  const MassProperties mp =
      massProperties(PointColumns{{body.x[0], body.x[1], body.x[2]}}, body.mass, body.count);
  body.centre = mp.centre.cast<float>();
  body.invTotalMass = float(1.0 / mp.mass);
  body.invInertia = mp.inverseInertia.cast<float>();
  body.rigidShare = rigidShare;
  body.shift = body.turn = body.deltaV = body.deltaW = Vec3f::Zero();
}

void applyRigidResponse(ContactBody& body) {
  if (body.shift.isZero() && body.turn.isZero() && body.deltaV.isZero() && body.deltaW.isZero())
    return;
  for (int i = 0; i < body.count; ++i) {
    if (body.invMass[i] == 0.0f) continue;  // pinned (the share is 0 then anyway)
    const Vec3f r = body.position(i) - body.centre;
    const Vec3f dx = body.shift + body.turn.cross(r);
    const Vec3f dv = body.deltaV + body.deltaW.cross(r);
    for (int a = 0; a < 3; ++a) {
      body.x[a][i] += dx[a];
      body.v[a][i] += dv[a];
    }
  }
  body.shift = body.turn = body.deltaV = body.deltaW = Vec3f::Zero();
}

namespace {

// How much the contact point of a body moves per unit impulse along unit d (its effective
// inverse mass): the particles' own share plus the rigid share at lever arm r.
float inverseMassAlong(const ContactBody& b, float localInvMass, const Vec3f& r, const Vec3f& d) {
  const Vec3f rd = r.cross(d);
  return (1.0f - b.rigidShare) * localInvMass +
         b.rigidShare * (b.invTotalMass + rd.dot(b.invInertia * rd));
}

// The impulse on the first of two touching points (the second gets its opposite) that stops
// their approach along unit n, whose effective inverse mass along n is k (> 0), and removes,
// Coulomb-style, up to friction × that impulse of their sliding velocity; kAlong(t) is the
// effective inverse mass along a unit tangent t. `relative` approaches: relative·n < 0.
template <typename InverseMassAlong>
Vec3f contactImpulse(const Vec3f& relative, const Vec3f& n, float k, float friction,
                     const InverseMassAlong& kAlong) {
  const float approach = relative.dot(n);
  const float normalImpulse = -approach / k;
  Vec3f impulse = normalImpulse * n;
  const Vec3f sliding = relative - approach * n;
  const float slide = sliding.norm();
  if (slide > 0.0f && friction > 0.0f) {
    const Vec3f t = sliding / slide;
    const float kt = kAlong(t);
    if (kt > 0.0f) impulse -= std::min(slide / kt, friction * normalImpulse) * t;
  }
  return impulse;
}

}  // namespace

void resolveContact(ContactBody& probe, ContactBody& obstacle, const Contact& contact,
                    float friction) {
  const int p = contact.particle;
  const mesh::Triangle& tri = (*obstacle.triangles)[size_t(contact.triangle)];
  const Vec3f& w = contact.weights;
  const Vec3f& n = contact.normal;
  const float sp = probe.rigidShare, so = obstacle.rigidShare;
  const float localP = probe.invMass[p];
  float localO = 0;
  for (int c = 0; c < 3; ++c) localO += w[c] * w[c] * obstacle.invMass[tri[size_t(c)]];

  // Current positions and velocities of the two touching points, rigid corrections included.
  const Vec3f xp = probe.position(p);
  Vec3f xo = Vec3f::Zero(), vo = Vec3f::Zero();
  for (int c = 0; c < 3; ++c) {
    xo += w[c] * obstacle.position(tri[size_t(c)]);
    vo += w[c] * obstacle.velocity(tri[size_t(c)]);
  }
  const Vec3f rp = xp - probe.centre, ro = xo - obstacle.centre;

  // Applies a position correction (kind 0) or an impulse (kind 1) J to the probe point and −J
  // to the obstacle point, split between the particles and the rigid motions.
  auto apply = [&](const Vec3f& J, int kind) {
    float* const* probeArrays = kind == 0 ? probe.x : probe.v;
    float* const* obstacleArrays = kind == 0 ? obstacle.x : obstacle.v;
    const Vec3f jp = (1.0f - sp) * localP * J;
    for (int a = 0; a < 3; ++a) {
      probeArrays[a][p] += jp[a];
      for (int c = 0; c < 3; ++c) {
        const int j = tri[size_t(c)];
        obstacleArrays[a][j] -= (1.0f - so) * w[c] * obstacle.invMass[j] * J[a];
      }
    }
    Vec3f& probeLinear = kind == 0 ? probe.shift : probe.deltaV;
    Vec3f& probeAngular = kind == 0 ? probe.turn : probe.deltaW;
    Vec3f& obstacleLinear = kind == 0 ? obstacle.shift : obstacle.deltaV;
    Vec3f& obstacleAngular = kind == 0 ? obstacle.turn : obstacle.deltaW;
    probeLinear += sp * probe.invTotalMass * J;
    probeAngular += sp * (probe.invInertia * rp.cross(J));
    obstacleLinear -= so * obstacle.invTotalMass * J;
    obstacleAngular -= so * (obstacle.invInertia * ro.cross(J));
  };

  const float k =
      inverseMassAlong(probe, localP, rp, n) + inverseMassAlong(obstacle, localO, ro, n);
  if (!(k > 0.0f)) return;  // everything involved is pinned

  // Positions: push apart along the normal until the gap is restored.
  const Vec3f xpNow = correctedPosition(probe, p);
  const Vec3f xoNow = xo + obstacle.shift + obstacle.turn.cross(ro);
  const float violation = (xpNow - xoNow).dot(n) - obstacle.gap;
  if (violation < 0.0f) apply((-violation / k) * n, 0);

  // Velocities: no approach along the normal, then Coulomb friction on the sliding part.
  const Vec3f relative = (probe.velocity(p) + probe.deltaV + probe.deltaW.cross(rp)) -
                         (vo + obstacle.deltaV + obstacle.deltaW.cross(ro));
  if (!(relative.dot(n) < 0.0f)) return;  // separating or resting
  apply(contactImpulse(relative, n, k, friction,
                       [&](const Vec3f& t) {
                         return inverseMassAlong(probe, localP, rp, t) +
                                inverseMassAlong(obstacle, localO, ro, t);
                       }),
        1);
}

void resolveStaticContact(ContactBody& body, int particle, const Vec3f& normal, float distance,
                          float friction) {
  const int p = particle;
  const float share = body.rigidShare;
  const float local = body.invMass[p];
  const Vec3f r = body.position(p) - body.centre;
  auto apply = [&](const Vec3f& J, int kind) {
    float* const* arrays = kind == 0 ? body.x : body.v;
    for (int a = 0; a < 3; ++a) arrays[a][p] += (1.0f - share) * local * J[a];
    (kind == 0 ? body.shift : body.deltaV) += share * body.invTotalMass * J;
    (kind == 0 ? body.turn : body.deltaW) += share * (body.invInertia * r.cross(J));
  };
  const float k = inverseMassAlong(body, local, r, normal);
  if (!(k > 0.0f)) return;  // pinned
  if (distance < 0.0f) apply((-distance / k) * normal, 0);

  const Vec3f relative = body.velocity(p) + body.deltaV + body.deltaW.cross(r);
  if (!(relative.dot(normal) < 0.0f)) return;  // separating or resting
  apply(contactImpulse(relative, normal, k, friction,
                       [&](const Vec3f& t) { return inverseMassAlong(body, local, r, t); }),
        1);
}

}  // namespace sb
