#include "sim/world/mass_properties.h"

#include <Eigen/Geometry>

#include "sim/base/linalg.h"

namespace sb {

MassProperties massProperties(const PointColumns& x, const float* mass, int count) {
  MassProperties mp;
  for (int i = 0; i < count; ++i) {
    mp.mass += mass[i];
    mp.centre += double(mass[i]) * x.row(i);
  }
  mp.centre /= mp.mass;
  for (int i = 0; i < count; ++i) {
    const Vec3 r = x.row(i) - mp.centre;
    mp.inertia += double(mass[i]) * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
  }
  mp.inverseInertia = symmetricPseudoInverse<3>(mp.inertia, 1e-9);
  return mp;
}

Vec3 centreOfMass(const PointColumns& x, const float* mass, int count) {
  Vec3 sum = Vec3::Zero();
  double total = 0;
  for (int i = 0; i < count; ++i) {
    sum += double(mass[i]) * x.row(i);
    total += mass[i];
  }
  return sum / total;
}

Vec3 linearMomentum(const PointColumns& v, const float* mass, int count) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < count; ++i) p += double(mass[i]) * v.row(i);
  return p;
}

Vec3 angularMomentum(const PointColumns& x, const PointColumns& v, const float* mass, int count,
                     const Vec3& about) {
  Vec3 L = Vec3::Zero();
  for (int i = 0; i < count; ++i) {
    const Vec3 r = x.row(i) - about;
    L += double(mass[i]) * r.cross(v.row(i));
  }
  return L;
}

}  // namespace sb
