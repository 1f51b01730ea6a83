// Mass, centre of mass, inertia and momenta of a set of point masses: what damping (the rigid
// motion a body's velocities are damped towards), contacts (a body's response as a whole) and
// the World's queries (centreOfMass, linearMomentum, angularMomentum) need. Stateless kernels;
// every sum is formed in double, in point order.
#pragma once

#include <array>
#include <vector>

#include "sim/base/types.h"

namespace sb {

// Column pointers of #P-long float arrays (x, y, z), e.g. a body's positions or velocities.
struct PointColumns {
  const float* c[3];
  Vec3 row(int i) const { return Vec3(c[0][i], c[1][i], c[2][i]); }
};

struct MassProperties {
  double mass = 0;                     // kg
  Vec3 centre = Vec3::Zero();          // m
  Mat3 inertia = Mat3::Zero();         // kg·m², about the centre, world axes
  Mat3 inverseInertia = Mat3::Zero();  // pseudo-inverse (flat or collinear sets), 1/(kg·m²)
};

// Points x (metres), masses in kg (> 0), `count` points.
MassProperties massProperties(const PointColumns& x, const float* mass, int count);

// The rigid motion of a set of weighted points with velocities: centre xc, velocity vc and
// angular velocity ω with the same linear and angular momentum (ω = I⁻¹L, pseudo-inverse for
// flat or collinear sets). Weights are masses, or masses with pinned particles made
// immovable; then the rigid motion is what the pins allow.
struct RigidMotion {
  Vec3 centre = Vec3::Zero();           // xc, m
  Vec3 velocity = Vec3::Zero();         // vc, m/s
  Vec3 omega = Vec3::Zero();            // ω, rad/s
  Vec3 angularMomentum = Vec3::Zero();  // L about xc, kg·m²/s (weights as masses)
  Mat3 inverseInertia = Mat3::Zero();   // about xc, 1/(kg·m²)
};
// One pass over the points: float sums in eight lanes per block of kRigidMotionBlock points,
// relative to the first point (no cancellation far from the origin), blocks added in double.
RigidMotion rigidMotion(const PointColumns& x, const PointColumns& v, const float* weight,
                        int count);
// The same motion with the blocks summed on the pool's threads (sim/base/parallel.h) when the
// set is large; the blocks' sums are added in block order, so the result has the same bits as
// rigidMotion for any thread count.
RigidMotion rigidMotionOnThreads(const PointColumns& x, const PointColumns& v, const float* weight,
                                 int count);
inline constexpr int kRigidMotionBlock = 512;

// The same motion summed where a sweep over the points passes by, block by block: start with the
// origin (the first point where the sweep will put it), add the blocks of points [begin, end)
// (whole blocks of kRigidMotionBlock points, a partial one only at the end; any order, any thread)
// once they are final, then rigidMotionOf adds the blocks in block order: the same bits as
// rigidMotion.
struct RigidMotionSums {
  float origin[3] = {0, 0, 0};
  std::vector<std::array<double, 16>> blocks;  // per block, see mass_properties.cpp
};
void startRigidMotionSums(RigidMotionSums& sums, const float origin[3], int count);
void sumRigidMotionBlocks(const PointColumns& x, const PointColumns& v, const float* weight,
                          int begin, int end, RigidMotionSums& sums);
RigidMotion rigidMotionOf(const RigidMotionSums& sums);

// Σ mᵢ xᵢ / Σ mᵢ (m).
Vec3 centreOfMass(const PointColumns& x, const float* mass, int count);
// Σ mᵢ vᵢ (kg·m/s).
Vec3 linearMomentum(const PointColumns& v, const float* mass, int count);
// Σ mᵢ (xᵢ − about) × vᵢ (kg·m²/s).
Vec3 angularMomentum(const PointColumns& x, const PointColumns& v, const float* mass, int count,
                     const Vec3& about);

}  // namespace sb
