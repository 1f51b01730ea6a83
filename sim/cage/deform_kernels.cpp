#include "sim/cage/deform_kernels.h"

#include <algorithm>
#include <cstddef>

namespace sb::cage {

namespace {

typedef float v4sf __attribute__((vector_size(16)));
typedef float v8sf __attribute__((vector_size(32)));
typedef float v16sf __attribute__((vector_size(64)));

constexpr int kPanel = PanelWeights::kPanelRows;

// Lane groups: a panel's 16 rows are one group of a 16-lane vector V or two of an 8-lane one.
// Group g is rows 16·(g / H) + L·(g % H) … + L − 1 (L lanes, H = 16 / L groups per panel).
template <class V>
constexpr int kLanes = int(sizeof(V) / sizeof(float));

// R consecutive lane groups from g against B cages: 3RB sums of L lanes, one per row, axis and
// cage. Column by column, so each lane is one chain of multiply-adds in column order, the same
// for every V, R and B.
template <class V, int R, int B>
__attribute__((always_inline)) inline void groupBlock(const PanelWeights& W, int g,
                                                      const float* const* cages,
                                                      float* const* outs) {
  constexpr int L = kLanes<V>, H = kPanel / L;
  const int m = W.cols();
  V sum[R][B][3];
#pragma GCC unroll 4
  for (int r = 0; r < R; ++r)
#pragma GCC unroll 8
    for (int b = 0; b < B; ++b)
#pragma GCC unroll 3
      for (int a = 0; a < 3; ++a) sum[r][b][a] = V{};
  const float* column[R];  // each group's first column
#pragma GCC unroll 4
  for (int r = 0; r < R; ++r) column[r] = W.panel((g + r) / H) + L * ((g + r) % H);
  for (int j = 0; j < m; ++j) {
    V w[R];
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r) w[r] = *reinterpret_cast<const V*>(column[r] + kPanel * j);
#pragma GCC unroll 8
    for (int b = 0; b < B; ++b) {
      const float x = cages[b][j], y = cages[b][m + j], z = cages[b][2 * m + j];
#pragma GCC unroll 4
      for (int r = 0; r < R; ++r) {
        sum[r][b][0] += w[r] * x;
        sum[r][b][1] += w[r] * y;
        sum[r][b][2] += w[r] * z;
      }
    }
  }
  for (int r = 0; r < R; ++r) {
    const int row0 = kPanel * ((g + r) / H) + L * ((g + r) % H);
    const int n = std::min(L, W.rows() - row0);
    for (int b = 0; b < B; ++b) {
      float* o = outs[b] + 3 * static_cast<long>(row0);
      for (int i = 0; i < n; ++i) {
        o[3 * i] = sum[r][b][0][i];
        o[3 * i + 1] = sum[r][b][1][i];
        o[3 * i + 2] = sum[r][b][2][i];
      }
    }
  }
}

// A W of a few MB (every scene body's) stays in cache while its cages use it; a larger one
// streams from memory.
inline bool inCache(const PanelWeights& W) {
  return std::size_t(W.rows()) * std::size_t(W.cols()) * sizeof(float) <= (std::size_t(4) << 20);
}

// Every cage against the lane groups [begin, end): Many cages per pass over the groups while
// there are that many, then four, then the rest one pass each. Each pass keeps 3·Many or twelve
// sums (the vector registers: 16 for 8 lanes, 32 for 16, less the column loads and the
// broadcasts). A lone cage takes four groups at a time (twelve sums) when W is in cache, and
// one when it streams from memory: one stream the prefetcher keeps up with (100k rows of 242
// columns, one thread, on the 2-core VM: four streams 24 GB/s, one 37 GB/s).
template <class V, int Many>
__attribute__((always_inline)) inline void groupRows(const PanelWeights& W,
                                                     const float* const* cages, float* const* outs,
                                                     int count, int begin, int end) {
  int k = 0;
  for (; k + Many <= count; k += Many)
    for (int g = begin; g < end; ++g) groupBlock<V, 1, Many>(W, g, cages + k, outs + k);
  if constexpr (Many > 4)
    for (; k + 4 <= count; k += 4)
      for (int g = begin; g < end; ++g) groupBlock<V, 1, 4>(W, g, cages + k, outs + k);
  const int left = count - k;
  if (left == 3) {
    for (int g = begin; g < end; ++g) groupBlock<V, 1, 3>(W, g, cages + k, outs + k);
  } else if (left == 2) {
    for (int g = begin; g < end; ++g) groupBlock<V, 1, 2>(W, g, cages + k, outs + k);
  } else if (left == 1) {
    int g = begin;
    if (inCache(W))
      for (; g + 4 <= end; g += 4) groupBlock<V, 4, 1>(W, g, cages + k, outs + k);
    for (; g < end; ++g) groupBlock<V, 1, 1>(W, g, cages + k, outs + k);
  }
}

template <class V, int Many>
__attribute__((always_inline)) inline void panelRows(const PanelWeights& W,
                                                     const float* const* cages, float* const* outs,
                                                     int count, int panelBegin, int panelEnd) {
  constexpr int H = kPanel / kLanes<V>;
  groupRows<V, Many>(W, cages, outs, count, H * panelBegin, H * panelEnd);
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

void panelRowsBaseline(const PanelWeights& W, const float* const* cages, float* const* outs,
                       int count, int begin, int end) {
  panelRows<v8sf, 4>(W, cages, outs, count, begin, end);
}

__attribute__((target("avx2,fma"))) void panelRowsAvx2(const PanelWeights& W,
                                                       const float* const* cages,
                                                       float* const* outs, int count, int begin,
                                                       int end) {
  panelRows<v8sf, 4>(W, cages, outs, count, begin, end);
}

__attribute__((target("avx512f,fma"))) void panelRowsAvx512(const PanelWeights& W,
                                                            const float* const* cages,
                                                            float* const* outs, int count,
                                                            int begin, int end) {
  panelRows<v16sf, 8>(W, cages, outs, count, begin, end);
}

__attribute__((target("avx2,fma"))) void sparseRowsWide(const int* outer, const int* inner,
                                                        const float* values, const float* cage4,
                                                        float* out, int begin, int end) {
  sparseRows(outer, inner, values, cage4, out, begin, end);
}

}  // namespace

bool deformIsaSupported(DeformIsa isa) {
  // A run-time test rather than ifunc-dispatched clones: ThreadSanitizer crashes in ifunc
  // resolvers, which run before it is set up.
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  static const bool avx512 = avx2 && __builtin_cpu_supports("avx512f");
  switch (isa) {
    case DeformIsa::Baseline:
      return true;
    case DeformIsa::Avx2Fma:
      return avx2;
    case DeformIsa::Avx512:
      return avx512;
  }
  return false;
}

DeformIsa deformKernelIsa() {
  static const DeformIsa best = deformIsaSupported(DeformIsa::Avx512)    ? DeformIsa::Avx512
                                : deformIsaSupported(DeformIsa::Avx2Fma) ? DeformIsa::Avx2Fma
                                                                         : DeformIsa::Baseline;
  return best;
}

void panelDeformRows(const PanelWeights& W, const float* const* cages, float* const* outs,
                     int count, int panelBegin, int panelEnd, DeformIsa isa) {
  switch (isa) {
    case DeformIsa::Avx512:
      return panelRowsAvx512(W, cages, outs, count, panelBegin, panelEnd);
    case DeformIsa::Avx2Fma:
      return panelRowsAvx2(W, cages, outs, count, panelBegin, panelEnd);
    case DeformIsa::Baseline:
      break;
  }
  panelRowsBaseline(W, cages, outs, count, panelBegin, panelEnd);
}

void sparseDeformRows(const int* outer, const int* inner, const float* values, const float* cage4,
                      float* out, int begin, int end, DeformIsa isa) {
  if (isa != DeformIsa::Baseline)  // 16-byte gathers: nothing to gain from 16 lanes
    sparseRowsWide(outer, inner, values, cage4, out, begin, end);
  else
    sparseRows(outer, inner, values, cage4, out, begin, end);
}

}  // namespace sb::cage
