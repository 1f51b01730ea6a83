#include "sim/cage/deform_kernels.h"

namespace sb::cage {

namespace {

typedef float v4sf __attribute__((vector_size(16)));

// The loops themselves, inlined into one function per instruction set below.
__attribute__((always_inline)) inline void denseRows(const float* W, int m, const float* X,
                                                     const float* Y, const float* Z, float* out,
                                                     int begin, int end) {
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
                                                       int begin, int end) {
  denseRows(W, m, X, Y, Z, out, begin, end);
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
                     float* out, int begin, int end, DeformIsa isa) {
  if (isa == DeformIsa::Avx2Fma)
    denseRowsWide(W, m, X, Y, Z, out, begin, end);
  else
    denseRows(W, m, X, Y, Z, out, begin, end);
}

void sparseDeformRows(const int* outer, const int* inner, const float* values, const float* cage4,
                      float* out, int begin, int end, DeformIsa isa) {
  if (isa == DeformIsa::Avx2Fma)
    sparseRowsWide(outer, inner, values, cage4, out, begin, end);
  else
    sparseRows(outer, inner, values, cage4, out, begin, end);
}

}  // namespace sb::cage
