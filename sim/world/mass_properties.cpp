#include "sim/world/mass_properties.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cassert>
#include <climits>
#include <type_traits>
#include <vector>

#include "sim/base/linalg.h"
#include "sim/base/parallel_for.h"

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

namespace {

// Σw, Σw·d (3), Σw·v (3), Σw·d dᵀ (xx, yy, zz, xy, yz, zx), Σw·d × v (3), d = x − origin.
using RigidSums = std::array<double, 16>;
static_assert(std::is_same_v<RigidSums, decltype(RigidMotionSums::blocks)::value_type>);

// The sums over points [b0, b1), at most one block: float sums in eight lanes, added in double.
// Compiled for x86-64-v4 (AVX-512VL: 32 registers of eight lanes, so the sixteen accumulators and
// the terms all stay in registers: ~0.5 ns per point in cache), x86-64-v3 (AVX2: sixteen
// registers, nine accumulators spilled to the stack: ~1.4 ns; the baseline's SSE pairs ~1.2 ns
// more, issue 17) and the baseline; the loader picks by CPU. Same bits on each: lane-wise IEEE
// operations, fixed order, no FMA (tests/sim/test_rigid_motion_targets.cpp builds the baseline
// alone with SB_MASS_PROPERTIES_BASELINE and compares). With clang (the sanitizer and fuzz
// builds) the baseline alone, as cluster_batch.cpp: under ThreadSanitizer the loader's CPU
// check (an ifunc resolver) runs before the sanitizer's runtime and the program crashed at start.
#if !defined(SB_MASS_PROPERTIES_BASELINE) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
RigidSums
rigidBlockSums(const PointColumns& x, const PointColumns& v, const float* w, const float origin[3],
               int b0, int b1) {
  const float *px = x.c[0], *py = x.c[1], *pz = x.c[2];
  const float *vx = v.c[0], *vy = v.c[1], *vz = v.c[2];
  const float ox = origin[0], oy = origin[1], oz = origin[2];
  constexpr int kLanes = 8;
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
  for (; i + kLanes <= b1; i += kLanes) {
    // The lanes as one vector (without `omp simd` GCC 12 left this loop scalar, issue 17):
    // lane-wise IEEE operations, the same bits.
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) add(i + l, l);
  }
  for (; i < b1; ++i) add(i, 0);
  RigidSums t;
  for (int k = 0; k < 16; ++k) {
    t[size_t(k)] = 0;
    for (int l = 0; l < kLanes; ++l) t[size_t(k)] += double(acc[k][l]);
  }
  return t;
}

void addSums(RigidSums& total, const RigidSums& block) {
  for (size_t k = 0; k < total.size(); ++k) total[k] += block[k];
}

// The motion from the sums over all points.
RigidMotion rigidMotionFromSums(const RigidSums& s, const float origin[3]) {
  const double W = s[0];
  RigidMotion r;
  const Vec3 dc = Vec3(s[1], s[2], s[3]) / W;
  r.centre = Vec3(origin[0], origin[1], origin[2]) + dc;
  r.velocity = Vec3(s[4], s[5], s[6]) / W;
  Mat3 spread;  // Σ w r rᵀ about the centre
  spread << s[7], s[10], s[12], s[10], s[8], s[11], s[12], s[11], s[9];
  spread -= W * dc * dc.transpose();
  const Mat3 inertia = spread.trace() * Mat3::Identity() - spread;
  r.angularMomentum = Vec3(s[13], s[14], s[15]) - W * dc.cross(r.velocity);
  r.inverseInertia = symmetricPseudoInverse<3>(inertia, 1e-9);
  r.omega = r.inverseInertia * r.angularMomentum;
  return r;
}

}  // namespace

RigidMotion rigidMotion(const PointColumns& x, const PointColumns& v, const float* w, int count) {
  const float origin[3] = {x.c[0][0], x.c[1][0], x.c[2][0]};
  RigidSums total{};
  for (int b0 = 0; b0 < count; b0 += kRigidMotionBlock)
    addSums(total, rigidBlockSums(x, v, w, origin, b0, std::min(count, b0 + kRigidMotionBlock)));
  return rigidMotionFromSums(total, origin);
}

void startRigidMotionSums(RigidMotionSums& sums, const float origin[3], int count) {
  std::copy(origin, origin + 3, sums.origin);
  sums.blocks.resize(size_t((count + kRigidMotionBlock - 1) / kRigidMotionBlock));
}

void sumRigidMotionBlocks(const PointColumns& x, const PointColumns& v, const float* w, int begin,
                          int end, RigidMotionSums& sums) {
  assert(begin % kRigidMotionBlock == 0);
  for (int b0 = begin; b0 < end; b0 += kRigidMotionBlock)
    sums.blocks[size_t(b0 / kRigidMotionBlock)] =
        rigidBlockSums(x, v, w, sums.origin, b0, std::min(end, b0 + kRigidMotionBlock));
}

RigidMotion rigidMotionOf(const RigidMotionSums& sums) {
  RigidSums total{};
  for (const RigidSums& block : sums.blocks) addSums(total, block);  // block order: the same bits
  return rigidMotionFromSums(total, sums.origin);
}

RigidMotion rigidMotionOnThreads(const PointColumns& x, const PointColumns& v, const float* w,
                                 int count) {
  const float origin[3] = {x.c[0][0], x.c[1][0], x.c[2][0]};
  RigidMotionSums sums;
  startRigidMotionSums(sums, origin, count);
  parallelFor(int(sums.blocks.size()), count >= kMinParallelParticles ? 2 : INT32_MAX, [&](int b) {
    sumRigidMotionBlocks(x, v, w, b * kRigidMotionBlock,
                         std::min(count, (b + 1) * kRigidMotionBlock), sums);
  });
  return rigidMotionOf(sums);
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
