#include "sim/surface_grid.h"

#include <algorithm>
#include <cmath>

namespace sb {

void SurfaceGrid::build(const std::vector<Triangle>& triangles, const float* x, const float* y,
                        const float* z, float reach, float cellSize,
                        const Eigen::AlignedBox3f& region) {
  reach_ = reach;
  bounds_.setEmpty();
  for (const Triangle& t : triangles)
    for (int i : t) bounds_.extend(Vec3f(x[i], y[i], z[i]));
  bounds_.min().array() -= reach;
  bounds_.max().array() += reach;
  bounds_ = bounds_.intersection(region);
  if (bounds_.isEmpty()) {  // no particle can ask: an empty grid
    dims_.setZero();
    cellStart_.assign(1, 0);
    entries_.clear();
    return;
  }
  const Vec3f extent = bounds_.sizes();
  float cell = std::max(cellSize, extent.maxCoeff() / float(maxCellsPerAxis));
  if (!(cell > 0.0f) || !std::isfinite(cell)) cell = 1.0f;  // empty or point-like surface
  invCell_ = 1.0f / cell;
  origin_ = bounds_.min();
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::clamp(int(std::ceil(extent[a] * invCell_)), 1, maxCellsPerAxis);

  cellBoxes_.resize(triangles.size());
  triangleBoxes_.resize(triangles.size());
  cellStart_.assign(size_t(dims_.prod()) + 1, 0);
  for (size_t t = 0; t < triangles.size(); ++t) {
    Eigen::AlignedBox3f box;
    for (int i : triangles[t]) box.extend(Vec3f(x[i], y[i], z[i]));
    triangleBoxes_[t] = box;
    box.min().array() -= reach;
    box.max().array() += reach;
    if (!box.intersects(bounds_)) {
      cellBoxes_[t] = Eigen::AlignedBox3i();  // empty: entered nowhere
      continue;
    }
    const Eigen::AlignedBox3i cells(cellOf(box.min()), cellOf(box.max()));
    cellBoxes_[t] = cells;
    for (int k = cells.min().z(); k <= cells.max().z(); ++k)
      for (int j = cells.min().y(); j <= cells.max().y(); ++j)
        for (int i = cells.min().x(); i <= cells.max().x(); ++i)
          ++cellStart_[size_t(cellIndex(i, j, k)) + 1];
  }
  for (size_t k = 1; k < cellStart_.size(); ++k) cellStart_[k] += cellStart_[k - 1];
  entries_.resize(size_t(cellStart_.back()));
  fill_.assign(cellStart_.begin(), cellStart_.end() - 1);
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Eigen::AlignedBox3i& cells = cellBoxes_[t];
    if (cells.isEmpty()) continue;
    for (int k = cells.min().z(); k <= cells.max().z(); ++k)
      for (int j = cells.min().y(); j <= cells.max().y(); ++j)
        for (int i = cells.min().x(); i <= cells.max().x(); ++i)
          entries_[size_t(fill_[size_t(cellIndex(i, j, k))]++)] = int(t);
  }
}

Eigen::Vector3i SurfaceGrid::cellOf(const Vec3f& p) const {
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a)
    c[a] = std::clamp(int(std::floor((p[a] - origin_[a]) * invCell_)), 0, dims_[a] - 1);
  return c;
}

SurfaceGrid::Range SurfaceGrid::candidates(const Vec3f& p) const {
  if (!bounds_.contains(p)) return {nullptr, nullptr};
  const Eigen::Vector3i c = cellOf(p);
  const size_t k = size_t(cellIndex(c[0], c[1], c[2]));
  return {entries_.data() + cellStart_[k], entries_.data() + cellStart_[k + 1]};
}

}  // namespace sb
