#include "sim/world/matching/goal_projection.h"

namespace sb {

namespace {

// The loop the two kernels share is vectorised (`omp simd`, and -fno-trapping-math for this file,
// see CMakeLists.txt); scalar, it cost ~10 ns per particle of a 10⁶-particle body (issue 17).
// Compiled for x86-64-v4 (AVX-512VL: twice the registers, so the goal's, the turn's and the
// reach's constants stay in registers; BM_QuadraticOneCluster's project ~2.8 → ~2.3 ns per
// particle), x86-64-v3 (AVX2: eight lanes per operation, the goal's and the reach's arithmetic
// is what bounds these loops) and the baseline; the loader picks by CPU. Lane-wise IEEE
// operations, no FMA, and the flag an integer OR: the same bits on every target and as a
// scalar loop (tests/sim/test_projection_targets.cpp builds the baseline alone with
// SB_GOAL_PROJECTION_BASELINE and compares). With clang the baseline alone (mass_properties.cpp
// says why).
#if !defined(SB_GOAL_PROJECTION_BASELINE) && !defined(__clang__)
#define SB_PROJECTION_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define SB_PROJECTION_CLONES
#endif

// The loop both kernels share: particles [begin, end) toward goal(i, g); with kVelocities also
// v = (v̂ + (x − x̂)/h) + h·g, x̂ the position before the projection, v̂ = v + T·(v − vc)
// (ProjectedVelocities; the product summed as the prediction sums it, the same bits).
template <bool kVelocities, typename Goal>
[[gnu::always_inline]] inline int projectStream(const PositionColumns& p, int begin, int end,
                                                float alpha, float reach2,
                                                const ProjectedVelocities* vel, Goal goal) {
  float* __restrict px = p.x;
  float* __restrict py = p.y;
  float* __restrict pz = p.z;
  float* __restrict v0 = kVelocities ? vel->v[0] : nullptr;
  float* __restrict v1 = kVelocities ? vel->v[1] : nullptr;
  float* __restrict v2 = kVelocities ? vel->v[2] : nullptr;
  float T[3][3] = {};
  float uc[3] = {}, f[3] = {};
  if constexpr (kVelocities)
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) T[a][b] = vel->turn[a][b];
      uc[a] = vel->turnCentre[a];
      f[a] = vel->fallSpeed[a];
    }
  const float T00 = T[0][0], T01 = T[0][1], T02 = T[0][2];
  const float T10 = T[1][0], T11 = T[1][1], T12 = T[1][2];
  const float T20 = T[2][0], T21 = T[2][1], T22 = T[2][2];
  const float ux = uc[0], uy = uc[1], uz = uc[2];
  const float f0 = f[0], f1 = f[1], f2 = f[2];
  const float invH = kVelocities ? vel->invH : 0.0f;
  int bad = 0;
#pragma omp simd reduction(| : bad)
  for (int i = begin; i < end; ++i) {
    float g0, g1, g2;
    goal(i, g0, g1, g2);
    const float ox = px[i], oy = py[i], oz = pz[i];
    float nx, ny, nz;
    bad |= projectPoint(ox, oy, oz, g0, g1, g2, alpha, reach2, nx, ny, nz);
    px[i] = nx;
    py[i] = ny;
    pz[i] = nz;
    if constexpr (kVelocities) {
      const float qx = v0[i], qy = v1[i], qz = v2[i];
      const float ex = qx - ux, ey = qy - uy, ez = qz - uz;
      v0[i] = ((qx + (T00 * ex + (T01 * ey + T02 * ez))) + (nx - ox) * invH) + f0;
      v1[i] = ((qy + (T10 * ex + (T11 * ey + T12 * ez))) + (ny - oy) * invH) + f1;
      v2[i] = ((qz + (T20 * ex + (T21 * ey + T22 * ez))) + (nz - oz) * invH) + f2;
    }
  }
  return bad;
}

SB_PROJECTION_CLONES int projectLinear(const PositionColumns& p, const RestColumns& r, int begin,
                                       int end, const GoalTransform& T, float alpha, float reach2,
                                       const ProjectedVelocities* vel) {
  const float* __restrict rx = r.x;
  const float* __restrict ry = r.y;
  const float* __restrict rz = r.z;
  const float L00 = T.L(0, 0), L01 = T.L(0, 1), L02 = T.L(0, 2);
  const float L10 = T.L(1, 0), L11 = T.L(1, 1), L12 = T.L(1, 2);
  const float L20 = T.L(2, 0), L21 = T.L(2, 1), L22 = T.L(2, 2);
  const float tx = T.t.x(), ty = T.t.y(), tz = T.t.z();
  auto goal = [=](int i, float& g0, float& g1, float& g2) {
    const float x = rx[i], y = ry[i], z = rz[i];
    g0 = L00 * x + L01 * y + L02 * z + tx;
    g1 = L10 * x + L11 * y + L12 * z + ty;
    g2 = L20 * x + L21 * y + L22 * z + tz;
  };
  return vel ? projectStream<true>(p, begin, end, alpha, reach2, vel, goal)
             : projectStream<false>(p, begin, end, alpha, reach2, vel, goal);
}

SB_PROJECTION_CLONES int projectQuadratic(const PositionColumns& p, const RestColumns& r, int begin,
                                          int end, const GoalTransform& T, float alpha,
                                          float reach2, const ProjectedVelocities* vel) {
  const float* __restrict rx = r.x;
  const float* __restrict ry = r.y;
  const float* __restrict rz = r.z;
  // Per row: L (3), Q (6), t; handed to the goal as scalars (with this table captured and the
  // goal returned through a float[3], GCC 12 left the loop scalar).
  float C[3][10];
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) C[a][j] = T.L(a, j);
    for (int j = 0; j < 6; ++j) C[a][3 + j] = T.Q(a, j);
    C[a][9] = T.t[a];
  }
  const float a0 = C[0][0], a1 = C[0][1], a2 = C[0][2], a3 = C[0][3], a4 = C[0][4], a5 = C[0][5],
              a6 = C[0][6], a7 = C[0][7], a8 = C[0][8], a9 = C[0][9];
  const float b0 = C[1][0], b1 = C[1][1], b2 = C[1][2], b3 = C[1][3], b4 = C[1][4], b5 = C[1][5],
              b6 = C[1][6], b7 = C[1][7], b8 = C[1][8], b9 = C[1][9];
  const float c0 = C[2][0], c1 = C[2][1], c2 = C[2][2], c3 = C[2][3], c4 = C[2][4], c5 = C[2][5],
              c6 = C[2][6], c7 = C[2][7], c8 = C[2][8], c9 = C[2][9];
  auto goal = [=](int i, float& g0, float& g1, float& g2) {
    const float x = rx[i], y = ry[i], z = rz[i];
    const float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, zx = z * x;
    g0 = a0 * x + a1 * y + a2 * z + a3 * xx + a4 * yy + a5 * zz + a6 * xy + a7 * yz + a8 * zx + a9;
    g1 = b0 * x + b1 * y + b2 * z + b3 * xx + b4 * yy + b5 * zz + b6 * xy + b7 * yz + b8 * zx + b9;
    g2 = c0 * x + c1 * y + c2 * z + c3 * xx + c4 * yy + c5 * zz + c6 * xy + c7 * yz + c8 * zx + c9;
  };
  return vel ? projectStream<true>(p, begin, end, alpha, reach2, vel, goal)
             : projectStream<false>(p, begin, end, alpha, reach2, vel, goal);
}

#undef SB_PROJECTION_CLONES

}  // namespace

int projectOntoTransform(const PositionColumns& p, const RestColumns& r, int begin, int end,
                         const GoalTransform& T, bool quadratic, float alpha, float reach,
                         const ProjectedVelocities* velocities) {
  const float reach2 = reach * reach;
  return quadratic ? projectQuadratic(p, r, begin, end, T, alpha, reach2, velocities)
                   : projectLinear(p, r, begin, end, T, alpha, reach2, velocities);
}

}  // namespace sb
