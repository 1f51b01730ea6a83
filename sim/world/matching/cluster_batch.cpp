#include "sim/world/matching/cluster_batch.h"

#include <algorithm>

#include "sim/world/matching/shape_matching.h"

// The 32-byte vector helpers below are internal and always inlined (they must be: the kernel is
// compiled for two targets whose ABIs pass such vectors differently, and an out-of-line helper
// built for one would be called from the other). GCC's ABI note for them does not apply; the
// file is built with -Wno-psabi (sim/CMakeLists.txt).

namespace sb {

namespace {

// Eight floats (or lane masks) operated on element-wise: GCC's vector extension, lowered to
// whatever SIMD the target has. Comparisons give masks of 0 / −1.
typedef float F8 __attribute__((vector_size(32)));
typedef int I8 __attribute__((vector_size(32)));

// Rotation steps per cluster and sub-step at most (as the general path); from a warm start one
// or two are the rule.
constexpr int kMaxRotationSteps = 12;
// Smallest pivot of the Hessian that counts as positive definite, relative to A scaled to a
// largest entry of 1.
constexpr float kDefiniteMargin = 1e-6f;

[[gnu::always_inline]] inline F8 splat(float v) {
  return F8{v, v, v, v, v, v, v, v};
}
[[gnu::always_inline]] inline F8 load(const float (&a)[kBatchLanes]) {
  F8 v;
  __builtin_memcpy(&v, a, sizeof v);
  return v;
}
[[gnu::always_inline]] inline void store(float (&a)[kBatchLanes], F8 v) {
  __builtin_memcpy(a, &v, sizeof v);
}
[[gnu::always_inline]] inline F8 select(I8 mask, F8 a, F8 b) {
  return mask ? a : b;
}
[[gnu::always_inline]] inline F8 sqrt8(F8 v) {
  F8 r;
  for (int l = 0; l < kBatchLanes; ++l) r[l] = __builtin_sqrtf(v[l]);
  return r;
}
[[gnu::always_inline]] inline F8 nonNegative(F8 v) {
  return v > splat(0.0f) ? v : splat(0.0f);
}
[[gnu::always_inline]] inline std::uint32_t bits(I8 mask) {
  std::uint32_t b = 0;
  for (int l = 0; l < kBatchLanes; ++l) b |= mask[l] ? (1u << l) : 0u;
  return b;
}
[[gnu::always_inline]] inline I8 isFinite(F8 v) {
  return (v - v) == splat(0.0f);  // x − x is NaN for NaN and ±Inf
}

// Row-major 3×3 matrices of lanes.
struct M3 {
  F8 m[9];
  [[gnu::always_inline]] F8& operator()(int a, int b) { return m[3 * a + b]; }
  [[gnu::always_inline]] F8 operator()(int a, int b) const { return m[3 * a + b]; }
};

[[gnu::always_inline]] inline M3 mul(const M3& A, const M3& B) {
  M3 C;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) C(a, b) = A(a, 0) * B(0, b) + A(a, 1) * B(1, b) + A(a, 2) * B(2, b);
  return C;
}

[[gnu::always_inline]] inline F8 det(const M3& A) {
  return A(0, 0) * (A(1, 1) * A(2, 2) - A(1, 2) * A(2, 1)) -
         A(0, 1) * (A(1, 0) * A(2, 2) - A(1, 2) * A(2, 0)) +
         A(0, 2) * (A(1, 0) * A(2, 1) - A(1, 1) * A(2, 0));
}

[[gnu::always_inline]] inline M3 rotationMatrix(F8 w, F8 x, F8 y, F8 z) {
  const F8 one = splat(1.0f), two = splat(2.0f);
  M3 R;
  R(0, 0) = one - two * (y * y + z * z);
  R(0, 1) = two * (x * y - w * z);
  R(0, 2) = two * (x * z + w * y);
  R(1, 0) = two * (x * y + w * z);
  R(1, 1) = one - two * (x * x + z * z);
  R(1, 2) = two * (y * z - w * x);
  R(2, 0) = two * (x * z - w * y);
  R(2, 1) = two * (y * z + w * x);
  R(2, 2) = one - two * (x * x + y * y);
  return R;
}

// For symmetric H = [[h00 h01 h02] [h01 h11 h12] [h02 h12 h22]]: (*x, *y, *z) = adj(H)·b, which is
// det(H)·H⁻¹b, and *definite = the pivots of H's LDLᵀ all exceed `margin` (tested as
// h00 > margin, m₂ > margin·h00, det > margin·m₂, with m₂ = h00·h11 − h01²).
[[gnu::always_inline]] inline void solveAdjugate(F8 h00, F8 h11, F8 h22, F8 h01, F8 h02, F8 h12,
                                                 const F8 (&b)[3], F8 margin, F8* x, F8* y, F8* z,
                                                 I8* definite) {
  const F8 c00 = h11 * h22 - h12 * h12, c01 = h02 * h12 - h01 * h22, c02 = h01 * h12 - h02 * h11;
  const F8 c11 = h00 * h22 - h02 * h02, c12 = h01 * h02 - h00 * h12, c22 = h00 * h11 - h01 * h01;
  const F8 det = h00 * c00 + h01 * c01 + h02 * c02;
  *definite = (h00 > margin) & (c22 > margin * h00) & (det > margin * c22);
  *x = c00 * b[0] + c01 * b[1] + c02 * b[2];
  *y = c01 * b[0] + c11 * b[1] + c12 * b[2];
  *z = c02 * b[0] + c12 * b[1] + c22 * b[2];
}

// Cube root for d in [0.512, 1.953] (the range volume restoration clamps to): Newton from the
// tangent at 1; three steps reach float precision there.
[[gnu::always_inline]] inline F8 cbrtNearOne(F8 d) {
  const F8 third = splat(1.0f / 3.0f), two = splat(2.0f);
  F8 y = splat(1.0f) + (d - splat(1.0f)) * third;
  for (int i = 0; i < 3; ++i) y = (two * y + d / (y * y)) * third;
  return y;
}

}  // namespace

std::vector<ClusterBatch> buildClusterBatches(const Csr& clusterMembers,
                                              const float* const memberRest[3],
                                              const float* memberWeight,
                                              const std::vector<ClusterRestModel>& rest) {
  std::vector<ClusterBatch> batches;
  const int clusterCount = clusterMembers.rows();
  ClusterBatch batch;
  auto flush = [&] {
    if (batch.count == 0) return;
    // Unused lanes repeat lane 0 (valid data; their results are ignored).
    for (int l = batch.count; l < kBatchLanes; ++l) {
      batch.cluster[l] = batch.cluster[0];
      for (int s = 0; s < kBatchMaxMembers; ++s) {
        batch.particle[s][l] = batch.particle[s][0];
        for (int a = 0; a < 3; ++a) batch.q0[a][s][l] = batch.q0[a][s][0];
        batch.w[s][l] = batch.w[s][0];
      }
      batch.mass[l] = batch.mass[0];
      for (int a = 0; a < 3; ++a) batch.sumWq0[a][l] = batch.sumWq0[a][0];
    }
    batches.push_back(batch);
    batch = ClusterBatch{};
  };
  for (int c = 0; c < clusterCount; ++c) {
    const int begin = clusterMembers.start[size_t(c)], size = clusterMembers.size(c);
    if (size < 1 || size > kBatchMaxMembers) continue;
    const int l = batch.count++;
    batch.cluster[l] = c;
    batch.memberSlots = std::max(batch.memberSlots, size);
    for (int s = 0; s < kBatchMaxMembers; ++s) {
      const int k = begin + std::min(s, size - 1);  // padding slots repeat the last member...
      batch.particle[s][l] = clusterMembers.items[size_t(k)];
      for (int a = 0; a < 3; ++a) batch.q0[a][s][l] = memberRest[a][k];
      batch.w[s][l] = s < size ? memberWeight[k] : 0.0f;  // ...with weight 0
    }
    batch.mass[l] = float(rest[size_t(c)].mass);
    for (int a = 0; a < 3; ++a) batch.sumWq0[a][l] = float(rest[size_t(c)].sumWq0[a]);
    if (batch.count == kBatchLanes) flush();
  }
  flush();
  return batches;
}

void setBatchShapeLane(ClusterBatchShape& shape, int lane, const Mat3& plastic,
                       const ClusterShape& derived, const Eigen::Vector3f& restCentre) {
  const Vec3 s0 = plastic * restCentre.cast<double>();
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      shape.AqqInv[3 * a + b][lane] = float(derived.AqqInv(a, b));
      shape.S[3 * a + b][lane] = float(plastic(a, b));
    }
    shape.s0[a][lane] = float(s0[a]);
  }
  shape.flat[lane] = derived.flat ? 1.0f : 0.0f;
}

// Compiled twice: for x86-64-v3 (AVX2: one register per vector of eight lanes, twice the
// registers of SSE, about 2× faster here) and for the baseline; the loader picks the one the CPU
// runs. Both give the same bits: every lane operation is a correctly rounded IEEE operation and
// -ffp-contract=off keeps multiplies and adds unfused.
// (A test defines SB_CLUSTER_BATCH_BASELINE to build the baseline alone and compare the bits.)
// clang 14 refuses the helpers' 32-byte vector arguments inside the clones (an ABI error raised
// before they are inlined), so a clang build compiles the baseline alone: the same bits, only
// slower. clang builds the CI's second-compiler and sanitizer stages, never a shipped binary.
#if !defined(SB_CLUSTER_BATCH_BASELINE) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
ClusterBatchGoals
matchClusterBatch(const ClusterBatch& batch, const ClusterBatchShape& shape,
                  const float* const x[3], const BodyParams& params, ClusterBatchLanes& lanes) {
  const F8 zero = splat(0.0f), one = splat(1.0f), half = splat(0.5f);
  // Moments about the reference point: Σ w d and Σ w d q⁰ᵀ with d = x − ref.
  const F8 ref[3] = {load(lanes.ref[0]), load(lanes.ref[1]), load(lanes.ref[2])};
  F8 wd[3] = {zero, zero, zero};
  M3 wdq;
  for (F8& v : wdq.m) v = zero;
  for (int s = 0; s < batch.memberSlots; ++s) {
    const F8 w = load(batch.w[s]);
    const int* p = batch.particle[s];
    F8 d[3];
    for (int a = 0; a < 3; ++a) {
      const float* xa = x[a];
      const F8 xs = {xa[p[0]], xa[p[1]], xa[p[2]], xa[p[3]],
                     xa[p[4]], xa[p[5]], xa[p[6]], xa[p[7]]};
      d[a] = w * (xs - ref[a]);
    }
    const F8 q[3] = {load(batch.q0[0][s]), load(batch.q0[1][s]), load(batch.q0[2][s])};
    for (int a = 0; a < 3; ++a) {
      wd[a] += d[a];
      for (int b = 0; b < 3; ++b) wdq(a, b) += d[a] * q[b];
    }
  }
  // Centre of mass and A_pq = (Σ w p q⁰ᵀ)·Sᵖᵀ with p = x − x_cm.
  const F8 invMass = one / load(batch.mass);
  F8 dc[3], centre[3];
  for (int a = 0; a < 3; ++a) {
    dc[a] = wd[a] * invMass;
    centre[a] = ref[a] + dc[a];
  }
  M3 Apq0, S, Apq;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      Apq0(a, b) = wdq(a, b) - dc[a] * load(batch.sumWq0[b]);
      S(a, b) = load(shape.S[3 * a + b]);
    }
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      Apq(a, b) = Apq0(a, 0) * S(b, 0) + Apq0(a, 1) * S(b, 1) + Apq0(a, 2) * S(b, 2);

  // Rotation: maximise f(R) = tr(RᵀA) over rotations, from the warm start, on A scaled by its
  // largest entry. Each step picks an axis u and turns about it by the angle that maximises f
  // along that axis, which has a closed form: with B = A·Rᵀ, turning by θ about u (world frame)
  // gives f(θ) = const + g₁·sin θ + g₂·cos θ, g₁ = u·τ, g₂ = tr B − uᵀBu, τ = axial(B − Bᵀ)
  // (the gradient), so θ* = atan2(g₁, g₂). The axis is Newton's direction H⁻¹τ where the
  // Hessian H = tr(B_s)·I − B_s is positive definite (closestRotation() takes the same Newton
  // step; near the maximum θ* equals its length, so convergence is quadratic) and the gradient
  // τ or a coordinate axis elsewhere (below): from a saddle, where Müller's gradient step crawls,
  // the exact angle leaves in one or two steps. No step ever lowers f. A lane stops when H is
  // definite and θ* < 1e-4 (error then ~1e-8); lanes exactly on a saddle or not done in time go to
  // the general path.
  F8 scale = zero;
  for (const F8& v : Apq.m) {
    const F8 a = v < zero ? -v : v;
    scale = a > scale ? a : scale;
  }
  I8 usable = (scale > splat(1e-30f)) & isFinite(scale);
  const F8 invScale = one / select(usable, scale, one);
  M3 An;
  for (int e = 0; e < 9; ++e) An.m[e] = Apq.m[e] * invScale;
  F8 qw = load(lanes.rotation[0]), qx = load(lanes.rotation[1]), qy = load(lanes.rotation[2]),
     qz = load(lanes.rotation[3]);
  {  // exactly unit, as the steps below keep it
    const F8 inv = one / sqrt8(qw * qw + qx * qx + qy * qy + qz * qz);
    qw *= inv;
    qx *= inv;
    qy *= inv;
    qz *= inv;
  }
  I8 active = usable, converged = {};
  for (int it = 0; it < kMaxRotationSteps; ++it) {
    bool any = false;
    for (int l = 0; l < kBatchLanes; ++l) any |= active[l] != 0;
    if (!any) break;
    const M3 R = rotationMatrix(qw, qx, qy, qz);
    M3 B;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        B(a, b) = An(a, 0) * R(b, 0) + An(a, 1) * R(b, 1) + An(a, 2) * R(b, 2);
    const F8 tau[3] = {B(2, 1) - B(1, 2), B(0, 2) - B(2, 0), B(1, 0) - B(0, 1)};
    const F8 traceB = B(0, 0) + B(1, 1) + B(2, 2);
    const F8 h00 = B(1, 1) + B(2, 2), h11 = B(0, 0) + B(2, 2), h22 = B(0, 0) + B(1, 1);
    const F8 h01 = -half * (B(0, 1) + B(1, 0)), h02 = -half * (B(0, 2) + B(2, 0)),
             h12 = -half * (B(1, 2) + B(2, 1));
    // Newton's axis H⁻¹τ, up to its length (normalised below): the adjugate times τ, whose
    // entries are independent of each other (no division chain). H is positive definite beyond
    // the margin when its LDLᵀ pivots h00, m₂/h00 and det/m₂ are (m₂ the leading 2×2 minor).
    const F8 margin = splat(kDefiniteMargin);
    F8 u0, u1, u2;
    I8 definite;
    solveAdjugate(h00, h11, h22, h01, h02, h12, tau, margin, &u0, &u1, &u2, &definite);
    // Lanes off the maximum's basin need more work; most sub-steps have none, and skipping the
    // work then changes no lane's result.
    const bool anySaddle = bits(active & ~definite) != 0;
    if (anySaddle) {
      // Not definite: Newton's direction for H + μI, μ from Gershgorin's bound so that the
      // shifted matrix is diagonally dominant (positive definite): between Newton and gradient.
      const F8 a01 = h01 < zero ? -h01 : h01, a02 = h02 < zero ? -h02 : h02,
               a12 = h12 < zero ? -h12 : h12;
      F8 gersh = h00 - a01 - a02;
      gersh = select(h11 - a01 - a12 < gersh, h11 - a01 - a12, gersh);
      gersh = select(h22 - a02 - a12 < gersh, h22 - a02 - a12, gersh);
      const F8 mu = select(gersh < splat(0.1f), splat(0.1f) - gersh, zero);
      F8 m0, m1, m2;
      I8 shiftedDefinite;  // always, by diagonal dominance
      solveAdjugate(h00 + mu, h11 + mu, h22 + mu, h01, h02, h12, tau, zero, &m0, &m1, &m2,
                    &shiftedDefinite);
      u0 = select(definite, u0, m0);
      u1 = select(definite, u1, m1);
      u2 = select(definite, u2, m2);
    }
    // τ = 0: a maximum if definite, else a saddle. An axis too short to normalise (τ nearly
    // along a direction where H is almost singular) is replaced by the gradient, still uphill.
    I8 still = tau[0] * tau[0] + tau[1] * tau[1] + tau[2] * tau[2] < splat(1e-30f);
    F8 len2 = u0 * u0 + u1 * u1 + u2 * u2;
    const I8 tiny = len2 < splat(1e-30f);
    u0 = select(tiny, tau[0], u0);
    u1 = select(tiny, tau[1], u1);
    u2 = select(tiny, tau[2], u2);
    len2 = select(tiny, u0 * u0 + u1 * u1 + u2 * u2, len2);
    const F8 invLen = one / sqrt8(select(still, one, len2));
    u0 *= invLen;
    u1 *= invLen;
    u2 *= invLen;
    F8 g1 = u0 * tau[0] + u1 * tau[1] + u2 * tau[2];
    const F8 Bu0 = B(0, 0) * u0 + B(0, 1) * u1 + B(0, 2) * u2;
    const F8 Bu1 = B(1, 0) * u0 + B(1, 1) * u1 + B(1, 2) * u2;
    const F8 Bu2 = B(2, 0) * u0 + B(2, 1) * u1 + B(2, 2) * u2;
    F8 g2 = traceB - (u0 * Bu0 + u1 * Bu1 + u2 * Bu2);
    // Where H is not definite the gradient axis alone zig-zags; the coordinate axes, for which
    // g₁ = τₐ and g₂ = Hₐₐ, are candidates too, and the axis with the largest exact gain
    // √(g₁² + g₂²) − g₂ is taken. A negative-curvature axis gains most: a turn by up to π
    // that leaves the saddle.
    F8 gain = sqrt8(g1 * g1 + g2 * g2) - g2;
    const F8 hDiag[3] = {h00, h11, h22};
    for (int a = 0; a < 3 && anySaddle; ++a) {
      const F8 gainA = sqrt8(tau[a] * tau[a] + hDiag[a] * hDiag[a]) - hDiag[a];
      const I8 better = ~definite & (gainA > gain);
      gain = select(better, gainA, gain);
      g1 = select(better, tau[a], g1);
      g2 = select(better, hDiag[a], g2);
      u0 = select(better, a == 0 ? one : zero, u0);
      u1 = select(better, a == 1 ? one : zero, u1);
      u2 = select(better, a == 2 ? one : zero, u2);
      still &= ~better;
    }
    // cos θ*, sin θ* and the half angle (θ* ∈ (−π, π]); the sin(θ/2) = sin θ / (2 cos(θ/2)) form
    // keeps small angles exact, the square-root form serves angles beyond π/2.
    const F8 invR = one / sqrt8(select(still, one, g1 * g1 + g2 * g2));
    const F8 c = g2 * invR, s = g1 * invR;
    const F8 ch = sqrt8(nonNegative(half * (one + c)));  // |c| may exceed 1 by round-off
    F8 sh = s / (ch + ch);
    if (bits(active & ~(c > zero)) != 0) {  // a turn beyond π/2 somewhere
      const F8 shWide = sqrt8(nonNegative(half * (one - c)));
      sh = select(c > zero, sh, select(s < zero, -shWide, shWide));
    }
    const F8 hx = sh * u0, hy = sh * u1, hz = sh * u2;
    // (ch, sh·u) ⊗ q. Both factors are unit quaternions up to round-off, so the product's norm
    // is 1 within a few ulp and one Newton step of 1/√n (n ≈ 1) renormalises it to float
    // precision without a square root.
    F8 nw = ch * qw - (hx * qx + hy * qy + hz * qz);
    F8 nx = ch * qx + hx * qw + (hy * qz - hz * qy);
    F8 ny = ch * qy + hy * qw + (hz * qx - hx * qz);
    F8 nz = ch * qz + hz * qw + (hx * qy - hy * qx);
    const F8 invNorm = half * (splat(3.0f) - (nw * nw + nx * nx + ny * ny + nz * nz));
    const I8 step = active & ~still;
    qw = select(step, nw * invNorm, qw);
    qx = select(step, nx * invNorm, qx);
    qy = select(step, ny * invNorm, qy);
    qz = select(step, nz * invNorm, qz);
    // A step below 1e-4 rad from where H is definite leaves an error of ~1e-8: done.
    const I8 done = active & definite & (still | ((c > zero) & (s * s < splat(1e-8f))));
    converged |= done;
    active &= ~done & ~(still & ~definite);
  }
  ClusterBatchGoals out;
  out.fallback = bits(~converged);

  // Goal: g = Tlin·q + x_cm with Tlin = R (rigid) or βA + (1 − β)R (linear), A = A_pq·A_qq⁺
  // (volume restored, departure from R bounded); re-expressed in the body-frame rest position r
  // through q = Sᵖ r − s0: L = Tlin·Sᵖ, t = x_cm − Tlin·s0.
  const M3 R = rotationMatrix(qw, qx, qy, qz);
  M3 T = R;
  if (params.mode == Mode::Linear) {
    M3 AqqInv;
    for (int e = 0; e < 9; ++e) AqqInv.m[e] = load(shape.AqqInv[e]);
    M3 A = mul(Apq, AqqInv);
    const F8 detA = det(A);
    F8 size2 = zero;
    for (const F8& v : A.m) size2 += v * v;
    const F8 size = sqrt8(size2);
    // Inverted or flat: no volume to restore, the rotation is the goal (as the general path).
    // A flat cluster's fit is singular, but its float determinant is round-off of either sign:
    // decided from its rest shape instead. (Tested on the determinant alone, such clusters of a
    // box's face switched between the rotation and a fit scaled by 1/∛(clamped round-off) from
    // sub-step to sub-step, and the box's particles shook at ~0.3 m/s for ever.)
    const I8 flat = ~(detA > splat(1e-12f) * size * size * size) | (load(shape.flat) > half);
    if (params.preserveVolume) {
      const float minScale = float(kMinVolumeScale);  // bounds shared with goalTransform
      const F8 lo = splat(minScale * minScale * minScale);
      const F8 hi = splat(1.0f / (minScale * minScale * minScale));
      F8 d = detA < lo ? lo : detA;
      d = d > hi ? hi : d;
      const F8 inv = one / cbrtNearOne(d);
      for (F8& v : A.m) v *= inv;
    }
    F8 dep2 = zero;
    for (int e = 0; e < 9; ++e) {
      A.m[e] = select(flat, R.m[e], A.m[e]);
      dep2 += (A.m[e] - R.m[e]) * (A.m[e] - R.m[e]);
    }
    const F8 limit = splat(float(kMaxFitDeparture));
    const F8 shrink = select(dep2 > limit * limit, limit / sqrt8(dep2), one);
    const F8 beta = splat(float(appliedBeta(params.beta)));
    for (int e = 0; e < 9; ++e) {
      const F8 bounded = R.m[e] + shrink * (A.m[e] - R.m[e]);
      T.m[e] = beta * bounded + (one - beta) * R.m[e];
    }
  }
  const M3 L = mul(T, S);
  I8 finite = isFinite(centre[0]) & isFinite(centre[1]) & isFinite(centre[2]);
  for (int a = 0; a < 3; ++a) {
    const F8 t = centre[a] - (T(a, 0) * load(shape.s0[0]) + T(a, 1) * load(shape.s0[1]) +
                              T(a, 2) * load(shape.s0[2]));
    finite &= isFinite(t);
    store(out.t[a], t);
  }
  for (int e = 0; e < 9; ++e) {
    finite &= isFinite(L.m[e]);
    store(out.L[e], L.m[e]);
  }
  // The lanes' state advances where the result stands (padding lanes included, so they stay
  // warm); elsewhere it keeps the input, the general path's warm start.
  const I8 keep = converged & finite;
  for (int a = 0; a < 3; ++a) store(lanes.ref[a], select(keep, centre[a], load(lanes.ref[a])));
  const F8 q[4] = {qw, qx, qy, qz};
  for (int k = 0; k < 4; ++k) store(lanes.rotation[k], select(keep, q[k], load(lanes.rotation[k])));
  const std::uint32_t used = (1u << batch.count) - 1u;
  out.nonFinite = bits(~finite) & used;
  out.fallback &= used & ~out.nonFinite;
  return out;
}

}  // namespace sb
