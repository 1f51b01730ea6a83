#include "sim/world/mass_properties.h"

#include <Eigen/Geometry>
#include <algorithm>

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

RigidMotion rigidMotion(const PointColumns& x, const PointColumns& v, const float* w, int count) {
  const float *px = x.c[0], *py = x.c[1], *pz = x.c[2];
  const float *vx = v.c[0], *vy = v.c[1], *vz = v.c[2];
  const float ox = px[0], oy = py[0], oz = pz[0];
  constexpr int kLanes = 8, kBlock = 512;
  // Σw, Σw·d, Σw·v, Σw·d dᵀ (6), Σw·d × v with d = x − x₀.
  double W = 0, D[3] = {0, 0, 0}, V[3] = {0, 0, 0}, C[6] = {0, 0, 0, 0, 0, 0}, X[3] = {0, 0, 0};
  for (int b0 = 0; b0 < count; b0 += kBlock) {
    const int b1 = std::min(count, b0 + kBlock);
    float acc[16][kLanes] = {};
    auto add = [&](int i, int l) {
      const float wi = w[i];
      const float dx = px[i] - ox, dy = py[i] - oy, dz = pz[i] - oz;
      const float ux = vx[i], uy = vy[i], uz = vz[i];
      acc[0][l] += wi;
      acc[1][l] += wi * dx;
      acc[2][l] += wi * dy;
      acc[3][l] += wi * dz;
      acc[4][l] += wi * ux;
      acc[5][l] += wi * uy;
      acc[6][l] += wi * uz;
      acc[7][l] += wi * dx * dx;
      acc[8][l] += wi * dy * dy;
      acc[9][l] += wi * dz * dz;
      acc[10][l] += wi * dx * dy;
      acc[11][l] += wi * dy * dz;
      acc[12][l] += wi * dz * dx;
      acc[13][l] += wi * (dy * uz - dz * uy);
      acc[14][l] += wi * (dz * ux - dx * uz);
      acc[15][l] += wi * (dx * uy - dy * ux);
    };
    int i = b0;
    for (; i + kLanes <= b1; i += kLanes)
      for (int l = 0; l < kLanes; ++l) add(i + l, l);
    for (; i < b1; ++i) add(i, 0);
    double t[16];
    for (int k = 0; k < 16; ++k) {
      t[k] = 0;
      for (int l = 0; l < kLanes; ++l) t[k] += double(acc[k][l]);
    }
    W += t[0];
    for (int a = 0; a < 3; ++a) {
      D[a] += t[1 + a];
      V[a] += t[4 + a];
      X[a] += t[13 + a];
    }
    for (int a = 0; a < 6; ++a) C[a] += t[7 + a];
  }
  RigidMotion r;
  const Vec3 dc = Vec3(D[0], D[1], D[2]) / W;
  r.centre = Vec3(ox, oy, oz) + dc;
  r.velocity = Vec3(V[0], V[1], V[2]) / W;
  Mat3 spread;  // Σ w r rᵀ about the centre
  spread << C[0], C[3], C[5], C[3], C[1], C[4], C[5], C[4], C[2];
  spread -= W * dc * dc.transpose();
  const Mat3 inertia = spread.trace() * Mat3::Identity() - spread;
  r.angularMomentum = Vec3(X[0], X[1], X[2]) - W * dc.cross(r.velocity);
  r.inverseInertia = symmetricPseudoInverse<3>(inertia, 1e-9);
  r.omega = r.inverseInertia * r.angularMomentum;
  return r;
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
