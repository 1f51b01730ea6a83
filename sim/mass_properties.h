// Mass, centre of mass and inertia of a set of point masses: what both damping (the rigid
// motion a body's velocities are damped towards) and contacts (a body's response as a whole)
// need. Stateless kernel.
#pragma once

#include "sim/types.h"

namespace sb {

struct MassProperties {
  double mass = 0;                     // kg
  Vec3 centre = Vec3::Zero();          // m
  Mat3 inertia = Mat3::Zero();         // kg·m², about the centre, world axes
  Mat3 inverseInertia = Mat3::Zero();  // pseudo-inverse (flat or collinear sets), 1/(kg·m²)
};

// Points are #P×3 columns x, y, z (metres), masses in kg (> 0). Sums in double, in point order.
MassProperties massProperties(const float* x, const float* y, const float* z, const float* mass,
                              int count);

}  // namespace sb
