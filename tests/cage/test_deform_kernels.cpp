// The deform kernels (sim/cage/deform_kernels.h), both instruction sets, against the same sums
// formed in double: within float rounding of Σ|w|·|c| per row, whichever kernel the CPU picks;
// and the dense kernel's promise that a row's bits do not depend on what shares the call.
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

PanelWeights panelsOf(const Case& k) {
  PanelWeights P(k.rows, k.m);
  for (int i = 0; i < k.rows; ++i)
    for (int j = 0; j < k.m; ++j) P.at(i, j) = k.W[size_t(i) * size_t(k.m) + size_t(j)];
  return P;
}

// The dense kernel on `count` copies of the case's cage, each shifted by its index (so a row
// written for the wrong cage shows), over the panels split in two ranges as the threads call it.
std::vector<std::vector<float>> densePanels(const Case& k, const PanelWeights& P, int count,
                                            DeformIsa isa) {
  std::vector<std::vector<float>> cages(static_cast<size_t>(count)), outs(cages.size());
  std::vector<const float*> in;
  std::vector<float*> out;
  for (int c = 0; c < count; ++c) {
    for (const std::vector<float>* axis : {&k.X, &k.Y, &k.Z})
      for (float v : *axis) cages[size_t(c)].push_back(v + float(c));
    outs[size_t(c)].assign(3 * size_t(k.rows), NAN);
    in.push_back(cages[size_t(c)].data());
    out.push_back(outs[size_t(c)].data());
  }
  const int half = P.panels() / 2;
  for (auto [b, e] : {std::pair{0, half}, std::pair{half, P.panels()}})
    panelDeformRows(P, in.data(), out.data(), count, b, e, isa);
  return outs;
}

void checkIsa(DeformIsa isa, const char* what) {
  // Odd sizes: a last panel part-filled (37 = 16·2 + 5, 300 = 16·18 + 12, 5), ranges that leave
  // single lane groups over from the lone cage's fours, and the sparse loop's unrolled tail.
  for (const auto& [rows, m] : {std::pair{37, 164}, std::pair{300, 7}, std::pair{5, 1}}) {
    const Case k = makeCase(rows, m, unsigned(rows * 131 + m));
    const PanelWeights P = panelsOf(k);
    // One cage alone and with others, as every grouping the kernels have (8 + 4 + 1, 8 + 3,
    // 4 + 3, 4 + 2, 4 + 1).
    const std::vector<std::vector<float>> one = densePanels(k, P, 1, isa);
    expectClose(k, one[0], false, what);
    for (const int count : {13, 11, 7, 6, 5}) {
      const std::vector<std::vector<float>> many = densePanels(k, P, count, isa);
      EXPECT_TRUE(many[0] == one[0]) << what << ": cage 0 of " << count << " is not its bits alone";
      for (int c = 1; c < count; ++c) {
        Case shifted = k;
        for (std::vector<float>* axis : {&shifted.X, &shifted.Y, &shifted.Z})
          for (float& v : *axis) v += float(c);
        expectClose(shifted, many[size_t(c)], false, what);
      }
    }
    std::vector<float> sparse(3 * size_t(rows), NAN);
    const int half = rows / 2;
    for (auto [b, e] : {std::pair{0, half}, std::pair{half, rows}})
      sparseDeformRows(k.outer.data(), k.inner.data(), k.values.data(), k.cage4.data(),
                       sparse.data(), b, e, isa);
    expectClose(k, sparse, true, what);
  }
}

TEST(DeformKernels, BaselineMatchesDoubleSums) {
  checkIsa(DeformIsa::Baseline, "baseline");
}

TEST(DeformKernels, WideMatchesDoubleSums) {
  if (!deformIsaSupported(DeformIsa::Avx2Fma)) GTEST_SKIP() << "this CPU has no AVX2 + FMA";
  checkIsa(DeformIsa::Avx2Fma, "AVX2 + FMA");
}

// 16 lanes: the same fused chains as AVX2, so the same bits, for every grouping of cages.
TEST(DeformKernels, Avx512MatchesDoubleSumsAndAvx2BitForBit) {
  if (!deformIsaSupported(DeformIsa::Avx512)) GTEST_SKIP() << "this CPU has no AVX-512";
  checkIsa(DeformIsa::Avx512, "AVX-512");
  for (const auto& [rows, m] : {std::pair{37, 164}, std::pair{300, 7}}) {
    const Case k = makeCase(rows, m, unsigned(rows * 7 + m));
    const PanelWeights P = panelsOf(k);
    for (const int count : {1, 3, 4, 9, 13})
      EXPECT_TRUE(densePanels(k, P, count, DeformIsa::Avx512) ==
                  densePanels(k, P, count, DeformIsa::Avx2Fma))
          << rows << " rows, " << count << " cages";
  }
}

}  // namespace
}  // namespace sb::cage
