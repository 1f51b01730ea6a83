#include "sim/cage/deform_kernels.h"

namespace sb::cage {

namespace {

typedef float v4sf __attribute__((vector_size(16)));

// The loops themselves, inlined into one function per instruction set below.
// One row at a time: three sums (x, y, z), vectorised over the cage vertices.
__attribute__((always_inline)) inline void denseRowsOneByOne(const float* W, int m, const float* X,
                                                             const float* Y, const float* Z,
                                                             float* out, int begin, int end) {
  for (int i = begin; i < end; ++i) {
    const float* w = W + static_cast<long>(i) * m;
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
#pragma omp simd reduction(+ : sx, sy, sz)
    for (int j = 0; j < m; ++j) {
      sx += w[j] * X[j];
      sy += w[j] * Y[j];
      sz += w[j] * Z[j];
    }
    out[3 * static_cast<long>(i)] = sx;
    out[3 * static_cast<long>(i) + 1] = sy;
    out[3 * static_cast<long>(i) + 2] = sz;
  }
}

// Four rows at a time: twelve independent sums hide the multiply-add latency that three leave
// exposed, and each cage coordinate loaded serves four rows; the rest one by one.
__attribute__((always_inline)) inline void denseRowsByFour(const float* W, int m, const float* X,
                                                           const float* Y, const float* Z,
                                                           float* out, int begin, int end) {
  int i = begin;
  for (; i + 4 <= end; i += 4) {
    const float* w0 = W + static_cast<long>(i) * m;
    const float *w1 = w0 + m, *w2 = w1 + m, *w3 = w2 + m;
    float x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0, x2 = 0, y2 = 0, z2 = 0, x3 = 0, y3 = 0,
          z3 = 0;
#pragma omp simd reduction(+ : x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3)
    for (int j = 0; j < m; ++j) {
      const float cx = X[j], cy = Y[j], cz = Z[j];
      x0 += w0[j] * cx;
      y0 += w0[j] * cy;
      z0 += w0[j] * cz;
      x1 += w1[j] * cx;
      y1 += w1[j] * cy;
      z1 += w1[j] * cz;
      x2 += w2[j] * cx;
      y2 += w2[j] * cy;
      z2 += w2[j] * cz;
      x3 += w3[j] * cx;
      y3 += w3[j] * cy;
      z3 += w3[j] * cz;
    }
    float* o = out + 3 * static_cast<long>(i);
    const float sums[12] = {x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3};
    for (int k = 0; k < 12; ++k) o[k] = sums[k];
  }
  denseRowsOneByOne(W, m, X, Y, Z, out, i, end);
}

__attribute__((always_inline)) inline void denseRows(const float* W, int m, const float* X,
                                                     const float* Y, const float* Z, float* out,
                                                     int begin, int end, bool cached) {
  if (cached)
    denseRowsByFour(W, m, X, Y, Z, out, begin, end);
  else
    denseRowsOneByOne(W, m, X, Y, Z, out, begin, end);
}

__attribute__((always_inline)) inline void sparseRows(const int* outer, const int* inner,
                                                      const float* values, const float* cage4,
                                                      float* out, int begin, int end) {
  // One 16-byte load per nonzero; four independent accumulators hide the add latency.
  const v4sf* C = reinterpret_cast<const v4sf*>(cage4);
  for (int i = begin; i < end; ++i) {
    v4sf a0 = {0.0f, 0.0f, 0.0f, 0.0f}, a1 = a0, a2 = a0, a3 = a0;
    int k = outer[i];
    const int last = outer[i + 1];
    for (; k + 4 <= last; k += 4) {
      a0 += values[k] * C[inner[k]];
      a1 += values[k + 1] * C[inner[k + 1]];
      a2 += values[k + 2] * C[inner[k + 2]];
      a3 += values[k + 3] * C[inner[k + 3]];
    }
    for (; k < last; ++k) a0 += values[k] * C[inner[k]];
    const v4sf sum = (a0 + a1) + (a2 + a3);
    out[3 * static_cast<long>(i)] = sum[0];
    out[3 * static_cast<long>(i) + 1] = sum[1];
    out[3 * static_cast<long>(i) + 2] = sum[2];
  }
}

__attribute__((target("avx2,fma"))) void denseRowsWide(const float* W, int m, const float* X,
                                                       const float* Y, const float* Z, float* out,
                                                       int begin, int end, bool cached) {
  denseRows(W, m, X, Y, Z, out, begin, end, cached);
}

__attribute__((target("avx2,fma"))) void sparseRowsWide(const int* outer, const int* inner,
                                                        const float* values, const float* cage4,
                                                        float* out, int begin, int end) {
  sparseRows(outer, inner, values, cage4, out, begin, end);
}

}  // namespace

DeformIsa deformKernelIsa() {
  // A run-time test rather than ifunc-dispatched clones: ThreadSanitizer crashes in ifunc
  // resolvers, which run before it is set up.
  static const bool wide = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return wide ? DeformIsa::Avx2Fma : DeformIsa::Baseline;
}

void denseDeformRows(const float* W, int m, const float* X, const float* Y, const float* Z,
                     float* out, int begin, int end, bool cached, DeformIsa isa) {
  if (isa == DeformIsa::Avx2Fma)
    denseRowsWide(W, m, X, Y, Z, out, begin, end, cached);
  else
    denseRows(W, m, X, Y, Z, out, begin, end, cached);
}

void sparseDeformRows(const int* outer, const int* inner, const float* values, const float* cage4,
                      float* out, int begin, int end, DeformIsa isa) {
  if (isa == DeformIsa::Avx2Fma)
    sparseRowsWide(outer, inner, values, cage4, out, begin, end);
  else
    sparseRows(outer, inner, values, cage4, out, begin, end);
}

}  // namespace sb::cage
