// The deform kernels (sim/cage/deform_kernels.h), both instruction sets, against the same sums
// formed in double: within float rounding of Σ|w|·|c| per row, whichever kernel the CPU picks.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "sim/cage/deform_kernels.h"

namespace sb::cage {
namespace {

struct Case {
  int rows = 0, m = 0;
  std::vector<float> W, X, Y, Z, cage4;  // W row-major rows × m; cage4 (x, y, z, 0) per column
  std::vector<int> outer, inner;         // the nonzeros of W (about a third), compressed rows
  std::vector<float> values;
};

// Random weights (some negative, as mean value coordinates outside the kernel) and a cage
// offset far from the origin (large coordinates, small differences: where rounding shows).
Case makeCase(int rows, int m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> w(-0.2f, 1.0f), c(-1.0f, 1.0f), keep(0.0f, 1.0f);
  Case k;
  k.rows = rows;
  k.m = m;
  k.W.resize(size_t(rows) * size_t(m));
  for (float& x : k.W) x = w(rng);
  for (int j = 0; j < m; ++j) {
    k.X.push_back(100.0f + c(rng));
    k.Y.push_back(-50.0f + c(rng));
    k.Z.push_back(c(rng));
    k.cage4.insert(k.cage4.end(), {k.X.back(), k.Y.back(), k.Z.back(), 0.0f});
  }
  k.outer.push_back(0);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < m; ++j)
      if (keep(rng) < 0.3f) {
        k.inner.push_back(j);
        k.values.push_back(k.W[size_t(i) * size_t(m) + size_t(j)]);
      }
    k.outer.push_back(int(k.inner.size()));
  }
  return k;
}

// Every row against its double sum over the given nonzeros (all of W when dense).
void expectClose(const Case& k, const std::vector<float>& out, bool sparse, const char* what) {
  for (int i = 0; i < k.rows; ++i) {
    double sum[3] = {0, 0, 0}, scale[3] = {0, 0, 0};
    auto add = [&](int j, double weight) {
      const double p[3] = {k.X[size_t(j)], k.Y[size_t(j)], k.Z[size_t(j)]};
      for (int a = 0; a < 3; ++a) {
        sum[a] += weight * p[a];
        scale[a] += std::abs(weight * p[a]);
      }
    };
    if (sparse) {
      for (int n = k.outer[size_t(i)]; n < k.outer[size_t(i) + 1]; ++n)
        add(k.inner[size_t(n)], k.values[size_t(n)]);
    } else {
      for (int j = 0; j < k.m; ++j) add(j, k.W[size_t(i) * size_t(k.m) + size_t(j)]);
    }
    // Float accumulation of m products, in any order, fused or not: within m·u·Σ|w·c| (u the
    // float unit round-off), doubled for the inputs' own rounding.
    for (int a = 0; a < 3; ++a)
      ASSERT_NEAR(out[3 * size_t(i) + size_t(a)], sum[a], 2.0 * k.m * 6e-8 * scale[a])
          << what << " row " << i << " axis " << a;
  }
}

void checkIsa(DeformIsa isa, bool cached, const char* what) {
  // Odd sizes: vector remainders in the dense loop, rows left over from its fours (37 = 4·9 + 1,
  // halves of 18 and 19), and the sparse loop's unrolled tail.
  for (const auto& [rows, m] : {std::pair{37, 164}, std::pair{300, 7}, std::pair{5, 1}}) {
    const Case k = makeCase(rows, m, unsigned(rows * 131 + m));
    std::vector<float> dense(3 * size_t(rows), NAN), sparse(3 * size_t(rows), NAN);
    // In two ranges, as the threads call it: each row written once, by its range.
    const int half = rows / 2;
    for (auto [b, e] : {std::pair{0, half}, std::pair{half, rows}}) {
      denseDeformRows(k.W.data(), m, k.X.data(), k.Y.data(), k.Z.data(), dense.data(), b, e, cached,
                      isa);
      sparseDeformRows(k.outer.data(), k.inner.data(), k.values.data(), k.cage4.data(),
                       sparse.data(), b, e, isa);
    }
    expectClose(k, dense, false, what);
    expectClose(k, sparse, true, what);
  }
}

TEST(DeformKernels, BaselineMatchesDoubleSums) {
  checkIsa(DeformIsa::Baseline, false, "baseline, one row at a time");
  checkIsa(DeformIsa::Baseline, true, "baseline, four rows at a time");
}

TEST(DeformKernels, WideMatchesDoubleSums) {
  if (deformKernelIsa() != DeformIsa::Avx2Fma) GTEST_SKIP() << "this CPU has no AVX2 + FMA";
  checkIsa(DeformIsa::Avx2Fma, false, "AVX2 + FMA, one row at a time");
  checkIsa(DeformIsa::Avx2Fma, true, "AVX2 + FMA, four rows at a time");
}

}  // namespace
}  // namespace sb::cage
