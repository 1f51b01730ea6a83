#include "sim/world/contact/body_contact.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/mesh/closest_point.h"

namespace sb {

namespace {

constexpr float kNoPlane = -std::numeric_limits<float>::infinity();
// Triangles a grid look-up remembers having tested exactly (a look-up tests ~2 distinct ones).
constexpr int kRemembered = 16;

// Unit normal of triangle t at the current positions and the signed distance of p from its
// plane; false for a collapsed triangle.
bool facePlane(const ContactGeometry& body, const mesh::Triangle& f, const Vec3f& p, Vec3f* normal,
               float* distance) {
  const Vec3f a = body.position(f[0]);
  const Vec3f n = (body.position(f[1]) - a).cross(body.position(f[2]) - a);
  const float len = n.norm();
  if (!(len > 0.0f)) return false;
  *normal = n / len;
  *distance = (p - a).dot(*normal);
  return true;
}

// Calls visit(t) for the closest triangle, its three neighbours and, when `fan` names a corner
// (0, 1, 2), the triangles around that corner.
template <typename Visit>
void forEachNearbyFace(const ContactGeometry& obstacle, int triangle, int fan, const Visit& visit) {
  const mesh::SurfaceTopology& topo = *obstacle.topology;
  visit(triangle);
  for (int k = 0; k < 3; ++k) visit(topo.neighbours[size_t(triangle)][size_t(k)]);
  if (fan < 0) return;
  const int v = (*obstacle.triangles)[size_t(triangle)][size_t(fan)];
  for (const int* t = topo.vertexTriangles.begin(v); t != topo.vertexTriangles.end(v); ++t)
    visit(*t);
}

struct Closest {
  int triangle = -1;
  mesh::TrianglePoint<float> point{};
  Vec3f position = Vec3f::Zero();
  float distanceSquared = 0;  // the bound to beat while triangle < 0
};

// Takes triangle t when its closest point to p is closer than the best so far (ties: the lower
// index, so the result does not depend on the order triangles come in); returns whether it did.
bool consider(const ContactGeometry& obstacle, const Vec3f& p, int t, Closest& best) {
  const mesh::Triangle& tri = (*obstacle.triangles)[size_t(t)];
  const Vec3f a = obstacle.position(tri[0]), b = obstacle.position(tri[1]),
              c = obstacle.position(tri[2]);
  const mesh::TrianglePoint<float> q = mesh::closestPointOnTriangle(p, a, b, c);
  const Vec3f closest = q.weights[0] * a + q.weights[1] * b + q.weights[2] * c;
  const float d2 = (p - closest).squaredNorm();
  if (d2 < best.distanceSquared || (d2 == best.distanceSquared && t < best.triangle)) {
    best = {t, q, closest, d2};
    return true;
  }
  return false;
}

// The closest triangle of the whole surface to p (nearest, ties to the lower index): triangles
// whose (build-time) boxes are farther than the best so far plus the grid's drift cannot be
// closer (as in the grid look-up). The boxes come in a hierarchy, nearer subtrees first, so most
// of the surface goes for a few node tests; without a tree (an empty grid, or a non-finite
// position) every triangle is tried. best.triangle < 0 when the surface has none.
void closestOnSurface(const ContactGeometry& obstacle, const Vec3f& p, Closest& best, long& tests) {
  const SurfaceGrid& grid = *obstacle.grid;
  const float drift = obstacle.gridDrift;
  best.triangle = -1;
  best.distanceSquared = std::numeric_limits<float>::infinity();
  float bound = best.distanceSquared;
  auto take = [&](int t) {
    ++tests;
    if (consider(obstacle, p, t, best)) {
      const float d = std::sqrt(best.distanceSquared);
      bound = drift > 0.0f ? (d + drift) * (d + drift) : best.distanceSquared;
    }
  };
  const Eigen::Array4f p4 = SurfaceGrid::lanes(p);
  if (!grid.boxTree().empty()) {
    grid.boxTree().visitNear(
        p, [&] { return bound; },
        [&](int t) {
          if (!(grid.distanceLowerBoundSquared(t, p4) > bound)) take(t);
        });
  } else {
    const bool haveBoxes = !grid.empty();
    for (int t = 0; t < int(obstacle.triangles->size()); ++t)
      if (!haveBoxes || !(grid.distanceLowerBoundSquared(t, p4) > bound)) take(t);
  }
}

// Whether p is inside the obstacle's closed surface (by the pseudo-normal of its closest
// feature).
bool insideSurface(const ContactGeometry& obstacle, const Vec3f& p, long& tests) {
  Closest best;
  closestOnSurface(obstacle, p, best, tests);
  if (best.triangle < 0) return false;
  const Vec3f side =
      mesh::pseudoNormal(*obstacle.triangles, *obstacle.topology, obstacle.x[0], obstacle.x[1],
                         obstacle.x[2], best.triangle, best.point.feature);
  return (p - best.position).dot(side) < 0.0f;
}

}  // namespace

bool findContacts(const ContactGeometry& probe, const ContactGeometry& obstacle, float h, bool deep,
                  bool creases, const Vec3f& apart, std::vector<Contact>& out, long* triangleTests,
                  ProbeClearance* clearance) {
  long tests = 0;
  // Bodies more than halfway into each other (each one's box centre within the other's box, the
  // probe's inside the obstacle): pushed through by others, dragged or spawned into each other.
  // There a particle's closest face can be on the obstacle's far side, and pushing particles out
  // through their closest faces pulled such bodies together until they coincided — a state
  // every contact holds, each particle lying on the other's surface (two cubes overlapping by
  // 60 % merged within a second; bunnies in the soak moved as one). In such a pair every inside
  // particle is held along `apart`: none pulls the bodies together, and the deepest one along
  // `apart` pushes them apart (by its depth to the obstacle's far extent, rate-bounded by the
  // solver's position sweeps).
  const Vec3f probeCentre = probe.box.center();
  const bool overlapping = deep && probe.box.contains(obstacle.box.center()) &&
                           obstacle.box.contains(probeCentre) &&
                           insideSurface(obstacle, probeCentre, tests);
  int deepestAlong = -1;
  float deepestDistance = 0;
  const std::vector<mesh::Triangle>& tris = *obstacle.triangles;
  const SurfaceGrid& grid = *obstacle.grid;
  bool foundDeep = false;
  // No particle moves further relative to the obstacle than this in the sub-step: particles
  // outside the grid's bounds grown by it are skipped before any per-particle arithmetic (unless
  // a deep search is asked for and they are inside the obstacle's box).
  const float drift = obstacle.gridDrift;
  const float maxExtra =
      h * (probe.maxRelativeSpeed + (probe.meanVelocity - obstacle.meanVelocity).norm() +
           obstacle.maxRelativeSpeed) +
      drift;
  Eigen::AlignedBox3f near = grid.bounds();
  near.min().array() -= maxExtra;
  near.max().array() += maxExtra;
  const float touch = obstacle.gap + obstacle.margin;
  if (clearance && clearance->particles.size() != size_t(probe.count))
    clearance->particles.assign(size_t(probe.count), ProbeClearance::Known{});
  // What a known distance must exceed a threshold by, for the rounding of bounds and distances.
  const float tolerance = 4.0f * grid.roundingTolerance() + 1e-3f * grid.reach();
  for (int i = 0; i < probe.count; ++i) {
    const Vec3f p = probe.position(i);
    const bool inBox = deep && obstacle.box.contains(p);
    if (!inBox && (grid.empty() || !near.contains(p))) continue;
    const Vec3f relative = probe.velocity(i) - obstacle.meanVelocity;
    const float extra = h * (relative.norm() + obstacle.maxRelativeSpeed);
    // Only triangles within reach + extra of p matter: a closest point farther than that might
    // not be the surface's closest point (the grid holds every triangle within that distance,
    // no more), so such a particle is left alone — it is far outside, or deeper inside than it
    // can have got in one sub-step (the deep search below handles those).
    const float reach = grid.reach() + extra;
    ProbeClearance::Known* known = clearance ? &clearance->particles[size_t(i)] : nullptr;
    if (known) {
      // A lower bound on its distance to the surface now (negative: none).
      const float now = known->clearance - (p - known->at).norm() - drift;
      if (now >= reach + tolerance && (!inBox || (known->outside && now > tolerance))) continue;
    }
    Closest best;
    best.distanceSquared = reach * reach;
    // The grid and its triangle boxes are from positions up to `drift` old: look that much
    // further, and a box may be that much closer than its triangle is now.
    float bound = drift > 0.0f ? (reach + drift) * (reach + drift) : best.distanceSquared;
    // Triangles whose boxes are farther than `bound` cannot be closer. A look-up over several
    // cells meets a triangle once per cell it is entered in; a second exact test cannot change
    // `best` (same distance, same index), so the triangles tested are remembered (up to
    // kRemembered; past that, repeats are tested again). In the seed-scale pile 55 % of the
    // exact tests were repeats.
    int tested[kRemembered];
    int testedCount = 0;
    float clearanceSquared = 0;
    grid.forEachNear(
        p, extra + drift, [&] { return bound; },
        [&](int t) {
          if (std::find(tested, tested + testedCount, t) != tested + testedCount) return;
          if (testedCount < kRemembered) tested[testedCount++] = t;
          ++tests;
          if (consider(obstacle, p, t, best)) {
            const float d = std::sqrt(best.distanceSquared);
            bound = drift > 0.0f ? (d + drift) * (d + drift) : best.distanceSquared;
          }
        },
        known ? &clearanceSquared : nullptr);
    if (known) *known = {p, best.triangle < 0 ? std::sqrt(clearanceSquared) : 0.0f, false};
    bool deepHit = false;
    if (best.triangle < 0) {
      if (!inBox) continue;
      // Nothing in reach, inside the obstacle's box: the closest triangle of the whole surface,
      // kept only if the particle is inside (a particle deeper than one sub-step's travel: an
      // overlapping start or a drag into the body).
      closestOnSurface(obstacle, p, best, tests);
      if (best.triangle < 0) continue;
      deepHit = true;
    }
    const Vec3f side = mesh::pseudoNormal(tris, *obstacle.topology, obstacle.x[0], obstacle.x[1],
                                          obstacle.x[2], best.triangle, best.point.feature);
    const Vec3f offset = p - best.position;
    const bool inside = offset.dot(side) < 0.0f;
    const float distance = std::sqrt(best.distanceSquared);
    if (deepHit) {
      // Its exact distance now, less the drift: a bound on its distance to the grid's surface.
      if (known && !inside) *known = {p, std::max(distance - drift, 0.0f), true};
      if (!inside) continue;
      foundDeep = true;
    }
    if (!inside && distance >= touch + extra) continue;
    if (overlapping && inside) {
      // No deeper than the slop: stopped along `apart`, not pushed (the deepest one does that).
      const float along = p.dot(apart);
      if (deepestAlong < 0 || along < deepestDistance) {
        deepestAlong = int(out.size());
        deepestDistance = along;
      }
      out.push_back(
          {i, best.triangle, best.point.weights, apart, std::max(-distance, -probe.slop)});
      continue;
    }

    // Which corner's fan to consider too: the feature's corner, or none.
    const int feature = int(best.point.feature);
    const int vertexFeature = int(mesh::TriangleFeature::Vertex0);
    if (!inside) {
      // The adjacent face that separates most.
      float bestPlane = kNoPlane;
      Vec3f bestNormal = Vec3f::Zero();
      forEachNearbyFace(obstacle, best.triangle,
                        feature >= vertexFeature ? feature - vertexFeature : -1, [&](int t) {
                          Vec3f n;
                          float d;
                          if (facePlane(obstacle, tris[size_t(t)], p, &n, &d) && d > bestPlane) {
                            bestPlane = d;
                            bestNormal = n;
                          }
                        });
      // Only where the surface is convex around the closest point: there no face plane is
      // farther than the closest point. In a concave crease one can be far farther (a particle
      // 1 mm off a neighbour's crease was let approach 3 cm along it, fell in, was pushed out,
      // and buzzed at 0.24 m/s for ever): there the direction to the closest point is used.
      if (bestPlane > kNoPlane && bestPlane <= distance) {
        out.push_back({i, best.triangle, best.point.weights, bestNormal, bestPlane});
        continue;
      }
    } else if (!deepHit) {
      // The face it came in through: outside its plane at the start of the sub-step, least deep
      // now, among the closest triangle, its neighbours and the fan of a corner it is near.
      const Vec3f start = p - h * relative;
      int fan = -1;
      for (int k = 0; k < 3; ++k)
        if (best.point.weights[k] >= 0.5f) fan = k;
      float bestPlane = kNoPlane;
      Vec3f bestNormal = Vec3f::Zero();
      forEachNearbyFace(obstacle, best.triangle, fan, [&](int t) {
        Vec3f n;
        float d;
        if (!facePlane(obstacle, tris[size_t(t)], p, &n, &d)) return;
        const Vec3f a = obstacle.position(tris[size_t(t)][0]);
        if (!((start - a).dot(n) >= 0.0f)) return;  // not entered through this face
        if (d < 0.0f && d > bestPlane) {
          bestPlane = d;
          bestNormal = n;
        }
      });
      // Trusted only as deep as the particle can have come in this sub-step.
      const float travel = h * relative.norm();
      if (bestPlane > kNoPlane && -bestPlane <= 1.5f * travel + distance + obstacle.gap &&
          -bestPlane > distance * 1.0001f) {
        out.push_back({i, best.triangle, best.point.weights, bestNormal, bestPlane});
        continue;
      }
    }
    if (creases && inside && !deepHit && feature != int(mesh::TriangleFeature::Face)) {
      // Inside, closest to an edge or a corner: there the surface is concave (the inside points
      // closest to a convex edge lie on its bisector only). Outside a concave crease is in front
      // of every face that meets there, and the plane through the crease along the direction to
      // it is not (a particle 7 mm behind one face met that plane and stayed inside for ever): the
      // face it is deepest behind is held instead. Only where contacts can rest (`creases`):
      // this is for particles lodged at rest, and at 1-s sub-steps, where everything is an
      // impact, holding face planes left a soft body of the pile 0.37 diagonals from its shape
      // (0.27 without).
      float worst = 0.0f;
      Vec3f worstNormal = Vec3f::Zero();
      forEachNearbyFace(obstacle, best.triangle,
                        feature >= vertexFeature ? feature - vertexFeature : -1, [&](int t) {
                          Vec3f n;
                          float d;
                          if (!facePlane(obstacle, tris[size_t(t)], p, &n, &d)) return;
                          const Vec3f a = obstacle.position(tris[size_t(t)][0]);
                          // Only faces through the closest point.
                          if (std::abs((best.position - a).dot(n)) > 1e-3f * distance + 1e-6f)
                            return;
                          if (d < worst) {
                            worst = d;
                            worstNormal = n;
                          }
                        });
      if (worst < 0.0f) {
        out.push_back({i, best.triangle, best.point.weights, worstNormal, worst});
        continue;
      }
    }
    Vec3f normal;
    if (distance > 1e-6f * obstacle.gap + std::numeric_limits<float>::min()) {
      normal = (inside ? -offset : offset) / distance;
    } else {
      const float len = side.norm();
      if (!(len > 0.0f)) continue;  // collapsed surface: no usable direction
      normal = side / len;
    }
    out.push_back({i, best.triangle, best.point.weights, normal, inside ? -distance : distance});
  }
  if (deepestAlong >= 0) {
    float extent = -std::numeric_limits<float>::infinity();
    for (int v = 0; v < obstacle.count; ++v)
      extent = std::max(extent, obstacle.position(v).dot(apart));
    out[size_t(deepestAlong)].distance = deepestDistance - extent;
  }
  if (triangleTests) *triangleTests += tests;
  return foundDeep || overlapping;
}

}  // namespace sb
