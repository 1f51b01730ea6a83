// Moving particles toward their goals: x ← x + α(g − x) for a range of particles, with g from a
// goal transform of the rest positions (docs/design.md §5.3). Stateless kernels, written over
// plain restrict pointers so that GCC vectorises them; each returns non-zero when a non-finite
// position appeared (x − x is 0 for finite x and NaN otherwise: an integer OR in the loop).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/world/matching/shape_matching.h"

namespace sb {

// Positions as #P-long columns (metres); the three columns do not overlap.
struct PositionColumns {
  float* x;
  float* y;
  float* z;
};
// Rest positions in the body frame as #P-long columns (metres).
struct RestColumns {
  const float* x;
  const float* y;
  const float* z;
};

[[gnu::always_inline]] inline int projectParticle(float* __restrict px, float* __restrict py,
                                                  float* __restrict pz, int i, float g0, float g1,
                                                  float g2, float alpha) {
  const float nx = px[i] + alpha * (g0 - px[i]);
  const float ny = py[i] + alpha * (g1 - py[i]);
  const float nz = pz[i] + alpha * (g2 - pz[i]);
  px[i] = nx;
  py[i] = ny;
  pz[i] = nz;
  return ((nx - nx) + (ny - ny) + (nz - nz)) != 0.0f;
}

// The same for a point (x, y, z), the result in (ox, oy, oz); then, where the particle is still
// farther than `reach` (m, squared: reach2) from its goal, the part beyond is dropped
// (docs/design.md §5.3, the body's reach): the same bits as projectParticle wherever the particle
// ends within reach.
[[gnu::always_inline]] inline int projectPoint(float x, float y, float z, float g0, float g1,
                                               float g2, float alpha, float reach2, float& ox,
                                               float& oy, float& oz) {
  const float nx = x + alpha * (g0 - x);
  const float ny = y + alpha * (g1 - y);
  const float nz = z + alpha * (g2 - z);
  const float dx = nx - g0, dy = ny - g1, dz = nz - g2;
  const float d2 = dx * dx + dy * dy + dz * dz;
  // Selects, not a branch, so that the loops around stay vectorised (the scale is computed
  // everywhere and used only beyond the reach, where d2 > reach2 ≥ 0).
  const bool beyond = d2 > reach2;
  const float scale = std::sqrt(reach2 / std::max(d2, std::numeric_limits<float>::min()));
  ox = beyond ? g0 + scale * dx : nx;
  oy = beyond ? g1 + scale * dy : ny;
  oz = beyond ? g2 + scale * dz : nz;
  return ((nx - nx) + (ny - ny) + (nz - nz)) != 0.0f;
}

// projectPoint on particle i of columns px, py, pz, in place.
[[gnu::always_inline]] inline int projectParticleWithin(float* __restrict px, float* __restrict py,
                                                        float* __restrict pz, int i, float g0,
                                                        float g1, float g2, float alpha,
                                                        float reach2) {
  return projectPoint(px[i], py[i], pz[i], g0, g1, g2, alpha, reach2, px[i], py[i], pz[i]);
}

// Particles [begin, end) toward goal(i, g) (g: 3 floats); a goal functor taken by value and
// restrict pointers keep the loop vectorised.
template <typename Goal>
int projectRange(const PositionColumns& p, int begin, int end, float alpha, Goal goal) {
  float* __restrict px = p.x;
  float* __restrict py = p.y;
  float* __restrict pz = p.z;
  int bad = 0;
  for (int i = begin; i < end; ++i) {
    float g[3];
    goal(i, g);
    bad |= projectParticle(px, py, pz, i, g[0], g[1], g[2], alpha);
  }
  return bad;
}

// The velocities of the particles a projection moves, formed in the same sweep: v = (v̂ + (x −
// x̂)/h) + h·g with x̂ the position before the projection (docs/design.md §5.3, step 5), and
// v̂ = v + T·(v − vc) the velocity the prediction carries (step 1), formed here from v rather than
// stored by the prediction and read back. #P-long columns, v read and written in place.
struct ProjectedVelocities {
  float* v[3];          // v in (as the prediction found it), v out, m/s
  float turn[3][3];     // T = R − I of the prediction's turn
  float turnCentre[3];  // vc, m/s
  float invH;           // 1/h, 1/s
  float fallSpeed[3];   // h·gravity, m/s
};

// Particles [begin, end) toward one goal transform g = L·r + t (+ Q·mono(r) when quadratic):
// a body with one cluster, or the whole-body level; none ends farther than `reach` (m) from its
// goal (projectParticleWithin). Pure streaming; with `velocities`, their v too.
int projectOntoTransform(const PositionColumns& p, const RestColumns& r, int begin, int end,
                         const GoalTransform& T, bool quadratic, float alpha, float reach,
                         const ProjectedVelocities* velocities = nullptr);

}  // namespace sb
