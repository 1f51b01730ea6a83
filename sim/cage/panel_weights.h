// A dense float weight matrix W (rows × cols) stored in panels of sixteen rows, the layout the
// deform kernels read (deform_kernels.h): panel p holds, column by column, the weights of rows
// 16p … 16p + 15 as sixteen consecutive floats (rows past the last are zero), so one 64-byte
// load (or two 32-byte ones) is one column of a panel, and a panel (cols × 64 bytes) is
// contiguous. The storage is 64-byte aligned. Row-major access is by at(i, j).
#pragma once

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace sb::cage {

class PanelWeights {
 public:
  static constexpr int kPanelRows = 16;

  PanelWeights() = default;
  // All zeros. rows, cols ≥ 0.
  PanelWeights(int rows, int cols)
      : rows_(rows), cols_(cols), data_(std::size_t(panelCount(rows)) * stride(cols), 0.0f) {}

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int panels() const { return panelCount(rows_); }
  float& at(int i, int j) { return data_[index(i, j)]; }
  float at(int i, int j) const { return data_[index(i, j)]; }
  // Panel p: cols × 16 floats, column j at panel(p) + 16j.
  const float* panel(int p) const { return data_.data() + std::size_t(p) * stride(cols_); }
  void swap(PanelWeights& other) noexcept {
    std::swap(rows_, other.rows_);
    std::swap(cols_, other.cols_);
    data_.swap(other.data_);
  }

 private:
  // 64-byte aligned storage: a panel's column is one cache line.
  template <class T>
  struct Aligned {
    using value_type = T;
    Aligned() = default;
    template <class U>
    Aligned(const Aligned<U>&) {}
    T* allocate(std::size_t n) {
      return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64)));
    }
    void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(64)); }
    template <class U>
    bool operator==(const Aligned<U>&) const {
      return true;
    }
    template <class U>
    bool operator!=(const Aligned<U>&) const {
      return false;
    }
  };

  static int panelCount(int rows) { return (rows + kPanelRows - 1) / kPanelRows; }
  static std::size_t stride(int cols) { return std::size_t(cols) * kPanelRows; }
  std::size_t index(int i, int j) const {
    return std::size_t(i / kPanelRows) * stride(cols_) + std::size_t(j) * kPanelRows +
           std::size_t(i % kPanelRows);
  }

  int rows_ = 0, cols_ = 0;
  std::vector<float, Aligned<float>> data_;
};

}  // namespace sb::cage
