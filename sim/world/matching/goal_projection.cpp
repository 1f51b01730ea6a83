#include "sim/world/matching/goal_projection.h"

namespace sb {

namespace {

// Both loops are vectorised (`omp simd`, and -fno-trapping-math for this file, see
// CMakeLists.txt); scalar, they cost ~10 ns per particle of a 10⁶-particle body (issue 17).
// Compiled for x86-64-v3 (AVX2: eight lanes per operation, the goal's and the reach's arithmetic
// is what bounds these loops) and the baseline; the loader picks by CPU. Lane-wise IEEE
// operations, no FMA, and the flag an integer OR: the same bits on either target and as a
// scalar loop (tests/sim/test_projection_targets.cpp builds the baseline alone with
// SB_GOAL_PROJECTION_BASELINE and compares).
#ifndef SB_GOAL_PROJECTION_BASELINE
#define SB_PROJECTION_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SB_PROJECTION_CLONES
#endif

SB_PROJECTION_CLONES int projectLinear(float* __restrict px, float* __restrict py,
                                       float* __restrict pz, const float* __restrict rx,
                                       const float* __restrict ry, const float* __restrict rz,
                                       int begin, int end, const GoalTransform& T, float alpha,
                                       float reach2) {
  const float L00 = T.L(0, 0), L01 = T.L(0, 1), L02 = T.L(0, 2);
  const float L10 = T.L(1, 0), L11 = T.L(1, 1), L12 = T.L(1, 2);
  const float L20 = T.L(2, 0), L21 = T.L(2, 1), L22 = T.L(2, 2);
  const float tx = T.t.x(), ty = T.t.y(), tz = T.t.z();
  int bad = 0;
#pragma omp simd reduction(| : bad)
  for (int i = begin; i < end; ++i) {
    const float x = rx[i], y = ry[i], z = rz[i];
    const float g0 = L00 * x + L01 * y + L02 * z + tx;
    const float g1 = L10 * x + L11 * y + L12 * z + ty;
    const float g2 = L20 * x + L21 * y + L22 * z + tz;
    bad |= projectParticleWithin(px, py, pz, i, g0, g1, g2, alpha, reach2);
  }
  return bad;
}

SB_PROJECTION_CLONES int projectQuadratic(float* __restrict px, float* __restrict py,
                                          float* __restrict pz, const float* __restrict rx,
                                          const float* __restrict ry, const float* __restrict rz,
                                          int begin, int end, const GoalTransform& T, float alpha,
                                          float reach2) {
  float C[3][10];  // per row: L (3), Q (6), t
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) C[a][j] = T.L(a, j);
    for (int j = 0; j < 6; ++j) C[a][3 + j] = T.Q(a, j);
    C[a][9] = T.t[a];
  }
  int bad = 0;
#pragma omp simd reduction(| : bad)
  for (int i = begin; i < end; ++i) {
    const float x = rx[i], y = ry[i], z = rz[i];
    const float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, zx = z * x;
    float g[3];
    for (int a = 0; a < 3; ++a)
      g[a] = C[a][0] * x + C[a][1] * y + C[a][2] * z + C[a][3] * xx + C[a][4] * yy + C[a][5] * zz +
             C[a][6] * xy + C[a][7] * yz + C[a][8] * zx + C[a][9];
    bad |= projectParticleWithin(px, py, pz, i, g[0], g[1], g[2], alpha, reach2);
  }
  return bad;
}

#undef SB_PROJECTION_CLONES

}  // namespace

int projectOntoTransform(const PositionColumns& p, const RestColumns& r, int begin, int end,
                         const GoalTransform& T, bool quadratic, float alpha, float reach) {
  const float reach2 = reach * reach;
  return quadratic ? projectQuadratic(p.x, p.y, p.z, r.x, r.y, r.z, begin, end, T, alpha, reach2)
                   : projectLinear(p.x, p.y, p.z, r.x, r.y, r.z, begin, end, T, alpha, reach2);
}

}  // namespace sb
