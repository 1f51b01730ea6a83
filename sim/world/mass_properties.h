// Mass, centre of mass, inertia and momenta of a set of point masses: what damping (the rigid
// motion a body's velocities are damped towards), contacts (a body's response as a whole) and
// the World's queries (centreOfMass, linearMomentum, angularMomentum) need. Stateless kernels;
// every sum is formed in double, in point order.
#pragma once

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

// Σ mᵢ xᵢ / Σ mᵢ (m).
Vec3 centreOfMass(const PointColumns& x, const float* mass, int count);
// Σ mᵢ vᵢ (kg·m/s).
Vec3 linearMomentum(const PointColumns& v, const float* mass, int count);
// Σ mᵢ (xᵢ − about) × vᵢ (kg·m²/s).
Vec3 angularMomentum(const PointColumns& x, const PointColumns& v, const float* mass, int count,
                     const Vec3& about);

}  // namespace sb
