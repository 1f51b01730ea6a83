// Static colliders that particles cannot enter, with Coulomb-style friction.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "sim/base/types.h"

namespace sb {

struct Collider {
  enum class Shape { Plane, Box, Sphere, Capsule };
  Shape shape = Shape::Plane;
  // Plane: points x with normal·x < offset are inside (the solid half-space).
  Vec3 normal = Vec3::UnitY();  // unit length
  double offset = 0.0;          // metres
  // Box: centre, half extents (metres, > 0) and orientation (rotation matrix, box → world).
  // Sphere: centre and radius. Capsule: segment from centre−axis to centre+axis, radius.
  Vec3 centre = Vec3::Zero();
  Vec3 halfExtents = Vec3::Constant(0.5);
  Mat3 rotation = Mat3::Identity();
  double radius = 0.5;
  Vec3 axis = Vec3(0.0, 0.5, 0.0);
  // Friction coefficient μ ≥ 0: tangential speed lost per contact, relative to the normal
  // speed removed; a large μ makes contact sticky.
  double friction = 0.5;
  // Restitution e in [0, 1] (as BodyParams::restitution; a contact uses the larger of the
  // collider's and the body's).
  double restitution = 0.0;

  static Collider plane(const Vec3& normal, double offset, double friction = 0.5);
  static Collider box(const Vec3& centre, const Vec3& halfExtents, const Mat3& rotation,
                      double friction = 0.5);
  static Collider sphere(const Vec3& centre, double radius, double friction = 0.5);
  static Collider capsule(const Vec3& a, const Vec3& b, double radius, double friction = 0.5);
};

const char* colliderShapeName(Collider::Shape shape);

// Signed distance from p to the collider surface (negative inside) and the outward surface
// normal at the closest point. Pure function; used by the Collide phase and the tests.
double colliderDistance(const Collider& collider, const Vec3& p, Vec3* normal);

// colliderDistance to collider `index` of a scene's `colliders`, on the part of its surface that
// is not buried in another of them (docs/design.md §5.5, "Buried faces"): the static solid is
// their union, and a ramp's end sunk into the floor is no surface a body can rest on. A surface
// point is buried when it lies deeper inside another collider than p itself does (by more than
// 1 µm): a particle pressed into the floor beside a wall still meets the wall's side. Inside a
// box, p leaves through the nearest face that is not buried (the nearest face when all are).
// Returns false when the closest surface point of a plane, sphere or capsule, or of a box seen
// from outside, is buried: the other collider's contact holds p there. `colliders` as the
// World's (vector of colliders), index in [0, size).
bool exposedColliderDistance(const std::vector<Collider>& colliders, int index, const Vec3& p,
                             double* distance, Vec3* normal);

// The second half of exposedColliderDistance, for a caller that already has colliderDistance's
// answer for collider `index` at p in *distance and *normal (the static contact pass computes it
// for every near collider and asks about burial only within reach): moves it onto the exposed
// part of the surface and returns as exposedColliderDistance does.
bool moveOntoExposedSurface(const std::vector<Collider>& colliders, int index, const Vec3& p,
                            double* distance, Vec3* normal);

// A lower bound on colliderDistance(collider, p) over every p in `box` (metres, world frame),
// exact for a plane, conservative (possibly −∞ or ≤ 0 when the box reaches into or around the
// collider) otherwise: a body whose box is farther than its particles' reach from a collider
// needs no per-particle test against it. A non-empty box with finite corners.
double colliderDistanceLowerBound(const Collider& collider, const Eigen::AlignedBox3d& box);

}  // namespace sb
