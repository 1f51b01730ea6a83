// The last values of a quantity, one per frame, for ImGui's plot widgets (a ring buffer that
// PlotLines reads with its values_offset). No GL, no ImGui.
#pragma once

#include <algorithm>
#include <array>

namespace sb::app {

class PlotHistory {
 public:
  // 10 s of simulated time at one sample per 1/60-s frame.
  static constexpr int kCapacity = 600;

  void add(float value) {
    values_[static_cast<std::size_t>(next_)] = value;
    next_ = (next_ + 1) % kCapacity;
    count_ = std::min(count_ + 1, kCapacity);
  }
  void clear() { next_ = count_ = 0; }
  int count() const { return count_; }
  // PlotLines(…, data(), count(), offset()): oldest first.
  const float* data() const { return values_.data(); }
  int offset() const { return count_ < kCapacity ? 0 : next_; }
  float last() const {
    return count_ ? values_[static_cast<std::size_t>((next_ + kCapacity - 1) % kCapacity)] : 0.0f;
  }
  float largest() const {
    float m = 0.0f;
    for (int i = 0; i < count_; ++i) m = std::max(m, values_[static_cast<std::size_t>(i)]);
    return m;
  }

 private:
  std::array<float, kCapacity> values_{};
  int next_ = 0, count_ = 0;
};

}  // namespace sb::app
