// buildCsr against the obvious vector-of-vectors construction.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "sim/base/csr.h"

namespace sb {
namespace {

TEST(Csr, RowsHoldTheEmittedItemsInEmissionOrder) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> row(0, 9), item(-50, 50);
  std::vector<std::pair<int, int>> pairs(200);
  for (auto& p : pairs) p = {row(rng), item(rng)};
  Csr csr;
  buildCsr(
      12,  // rows 10 and 11 stay empty
      [&](const auto& emit) {
        for (const auto& [r, i] : pairs) emit(r, i);
      },
      csr);
  std::vector<std::vector<int>> expected(12);
  for (const auto& [r, i] : pairs) expected[size_t(r)].push_back(i);
  ASSERT_EQ(csr.rows(), 12);
  ASSERT_EQ(csr.start.front(), 0);
  ASSERT_EQ(csr.start.back(), 200);
  for (int r = 0; r < 12; ++r) {
    EXPECT_EQ(std::vector<int>(csr.begin(r), csr.end(r)), expected[size_t(r)]) << "row " << r;
    EXPECT_EQ(csr.size(r), int(expected[size_t(r)].size()));
  }
}

TEST(Csr, RebuildingReusesStorageAndForgetsTheOldRows) {
  Csr csr;
  buildCsr(
      3,
      [](const auto& emit) {
        for (int k = 0; k < 30; ++k) emit(k % 3, k);
      },
      csr);
  buildCsr(
      2, [](const auto& emit) { emit(1, 5); }, csr);
  EXPECT_EQ(csr.rows(), 2);
  EXPECT_EQ(csr.size(0), 0);
  ASSERT_EQ(csr.size(1), 1);
  EXPECT_EQ(*csr.begin(1), 5);
}

TEST(Csr, NoRows) {
  Csr csr;
  buildCsr(
      0, [](const auto&) {}, csr);
  EXPECT_EQ(csr.rows(), 0);
  EXPECT_TRUE(csr.items.empty());
}

}  // namespace
}  // namespace sb
