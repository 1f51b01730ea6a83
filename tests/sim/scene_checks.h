// Independent measures of a running scene for the shipped-scene tests: how deep particles sit
// inside other bodies and below colliders, how far a body is from a rigid copy of its rest
// shape. Nothing here uses the simulator's contact code, so a bug there cannot hide itself.
#pragma once

#include <array>
#include <vector>

#include "sim/scene/scene.h"

namespace sb::test {

// Generalized winding number of the closed triangle mesh (vertices x, triangles tris) at p:
// the sum of the triangles' signed solid angles seen from p (Van Oosterom–Strackee) over 4π.
// ±1 inside a closed mesh (the sign follows the orientation), 0 outside.
double windingNumber(const Vec3& p, const Eigen::MatrixX3d& x,
                     const std::vector<std::array<int, 3>>& tris);

// Exact Euclidean distance from p to the triangle (a, b, c) (closest point on the face, an edge
// or a vertex).
double pointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Particle spacing of a body: the mean length of the unique edges of its cage triangles over its
// rest positions (world.restPositions, i.e. the mesh as placed by the scene file). This is the
// length scale that contact tolerances are relative to.
double particleSpacing(const Scene& scene, int body);

// Diagonal of the axis-aligned bounding box of the body's current particles.
double boundingBoxDiagonal(const Scene& scene, int body);

// The deepest particle of one body inside another.
struct Penetration {
  double depth = 0.0;  // metres; 0 when no particle is inside any other body
  // depth / min(spacing of the penetrating body, spacing of the penetrated body); 0 when none
  double relativeDepth = 0.0;
  int body = -1;      // scene body index of the penetrating particle
  int particle = -1;  // its index within the body
  int into = -1;      // scene body index it is inside
};

// For every particle p of every body A and every other body B with cage triangles: p is inside B
// when |winding number of B's current cage at p| > 0.5; its depth is then the distance to B's
// closest cage triangle. Only particles inside B's bounding box are tested (a point outside the
// box cannot be inside the closed surface). Returns the particle with the largest relative depth.
Penetration deepestPenetration(const Scene& scene);

// The lowest particle relative to the static colliders.
struct ColliderClearance {
  double distance = 0.0;          // signed distance (negative = inside the collider), metres
  double relativeDistance = 0.0;  // distance / particle spacing of the body
  int body = -1;
  int particle = -1;
  int collider = -1;
};

// Minimum over bodies, particles and colliders of sb::colliderDistance, taking the entry with the
// smallest distance relative to its body's particle spacing. distance is +inf without colliders.
ColliderClearance lowestColliderClearance(const Scene& scene);

// Largest distance between a particle and the best rigid placement (least-squares rotation and
// translation, equal weights) of the body's rest shape onto its current positions: 0 for a body
// that moves rigidly, grows with any stretch, shear or bend.
double maxDeviationFromRigidFit(const Scene& scene, int body);

}  // namespace sb::test
