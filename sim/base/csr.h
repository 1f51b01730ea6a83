// Compressed sparse rows: lists of integers per row, stored flat (libigl and CSR matrices do the
// same). Row r holds items[start[r] .. start[r+1]); start has rows + 1 entries, start[0] = 0.
#pragma once

#include <cstddef>
#include <vector>

namespace sb {

struct Csr {
  std::vector<int> start{0};  // #rows + 1, non-decreasing
  std::vector<int> items;     // #entries

  int rows() const { return static_cast<int>(start.size()) - 1; }
  int size(int row) const { return start[std::size_t(row) + 1] - start[std::size_t(row)]; }
  const int* begin(int row) const { return items.data() + start[std::size_t(row)]; }
  const int* end(int row) const { return items.data() + start[std::size_t(row) + 1]; }
};

// Builds `out` with `rows` rows from the (row, item) pairs that visit(emit) emits by calling
// emit(row, item), 0 ≤ row < rows. visit is called twice (a counting pass, then a filling
// pass) and must emit the same pairs both times; within a row, items keep the order in which
// they were emitted. Reuses out's storage (no allocation once it is large enough).
template <typename Visit>
void buildCsr(int rows, const Visit& visit, Csr& out) {
  out.start.assign(std::size_t(rows) + 1, 0);
  visit([&](int row, int) { ++out.start[std::size_t(row) + 1]; });
  for (std::size_t r = 1; r < out.start.size(); ++r) out.start[r] += out.start[r - 1];
  out.items.resize(std::size_t(out.start.back()));
  // The fill cursor of row r lives in start[r] while filling; shifting start back afterwards
  // restores the row beginnings without a second array.
  visit([&](int row, int item) { out.items[std::size_t(out.start[std::size_t(row)]++)] = item; });
  for (std::size_t r = out.start.size() - 1; r > 0; --r) out.start[r] = out.start[r - 1];
  out.start[0] = 0;
}

}  // namespace sb
