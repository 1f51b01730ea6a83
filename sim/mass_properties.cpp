#include "sim/mass_properties.h"

#include "sim/cluster_rest.h"

namespace sb {

MassProperties massProperties(const float* x, const float* y, const float* z, const float* mass,
                              int count) {
  MassProperties mp;
  for (int i = 0; i < count; ++i) {
    mp.mass += mass[i];
    mp.centre += double(mass[i]) * Vec3(x[i], y[i], z[i]);
  }
  mp.centre /= mp.mass;
  for (int i = 0; i < count; ++i) {
    const Vec3 r = Vec3(x[i], y[i], z[i]) - mp.centre;
    mp.inertia += double(mass[i]) * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
  }
  mp.inverseInertia = symmetricPseudoInverse<3>(mp.inertia, 1e-9);
  return mp;
}

}  // namespace sb
