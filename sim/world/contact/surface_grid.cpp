#include "sim/world/contact/surface_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sb {

void SurfaceGrid::build(const std::vector<mesh::Triangle>& triangles, const float* x,
                        const float* y, const float* z, float reach, float cellSize,
                        const Eigen::AlignedBox3f& region, bool sameTriangles, float lookAhead) {
  reach_ = reach;
  lookAhead_ = lookAhead;
  Eigen::AlignedBox3f surfaceBox;
  for (const mesh::Triangle& t : triangles)
    for (int i : t) surfaceBox.extend(Vec3f(x[i], y[i], z[i]));
  surfaceBox_ = surfaceBox;
  bounds_ = surfaceBox;
  bounds_.min().array() -= reach;
  bounds_.max().array() += reach;
  bounds_ = bounds_.intersection(region);
  allTriangles_.clear();
  if (bounds_.isEmpty() || !bounds_.sizes().allFinite()) {  // no particle can ask: an empty grid
    boxTree_.build({});
    bounds_.setEmpty();  // contains and intersects nothing
    dims_.setZero();
    cells_.start.assign(1, 0);
    cells_.items.clear();
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
  triangleBounds_.resize(triangles.size());
  // The points that ask lie within the region, the triangles within their bounds.
  float magnitude = 0;
  for (const Eigen::AlignedBox3f& b : {region, surfaceBox})
    magnitude = std::max({magnitude, b.min().cwiseAbs().maxCoeff(), b.max().cwiseAbs().maxCoeff()});
  planeTolerance_ = 32.0f * std::numeric_limits<float>::epsilon() * magnitude;
  for (size_t t = 0; t < triangles.size(); ++t) {
    Eigen::AlignedBox3f box;
    for (int i : triangles[t]) box.extend(Vec3f(x[i], y[i], z[i]));
    triangleBoxes_[t] = box;
    const mesh::Triangle& f = triangles[t];
    const Vec3f a(x[f[0]], y[f[0]], z[f[0]]);
    Vec3f n = (Vec3f(x[f[1]], y[f[1]], z[f[1]]) - a).cross(Vec3f(x[f[2]], y[f[2]], z[f[2]]) - a);
    const float length = n.norm();
    n = length > 0.0f ? Vec3f(n / length) : Vec3f::Zero();  // collapsed: no plane bound
    triangleBounds_[t] = {Eigen::Array4f(box.min().x(), box.min().y(), box.min().z(), 1.0f),
                          Eigen::Array4f(box.max().x(), box.max().y(), box.max().z(), 1.0f),
                          Eigen::Array4f(n.x(), n.y(), n.z(), -n.dot(a))};
    box.min().array() -= reach + lookAhead;
    box.max().array() += reach + lookAhead;
    cellBoxes_[t] = box.intersects(bounds_)
                        ? Eigen::AlignedBox3i(cellOf(box.min()), cellOf(box.max()))
                        : Eigen::AlignedBox3i();  // empty: entered nowhere
    if (!cellBoxes_[t].isEmpty()) allTriangles_.push_back(int(t));
  }
  if (sameTriangles)
    boxTree_.refit(triangleBoxes_);
  else
    boxTree_.build(triangleBoxes_);
  buildCsr(
      dims_.prod(),
      [&](const auto& emit) {
        for (size_t t = 0; t < triangles.size(); ++t) {
          const Eigen::AlignedBox3i& cells = cellBoxes_[t];
          if (cells.isEmpty()) continue;
          for (int k = cells.min().z(); k <= cells.max().z(); ++k)
            for (int j = cells.min().y(); j <= cells.max().y(); ++j)
              for (int i = cells.min().x(); i <= cells.max().x(); ++i)
                emit(cellIndex(i, j, k), int(t));
        }
      },
      cells_);
}

Eigen::Vector3i SurfaceGrid::cellOf(const Vec3f& p) const {
  Eigen::Vector3i c;
  // Clamped in float first: a far or non-finite point must not overflow the int conversion.
  for (int a = 0; a < 3; ++a) {
    const float f = std::floor((p[a] - origin_[a]) * invCell_);
    c[a] = !(f > 0.0f) ? 0 : f >= float(dims_[a] - 1) ? dims_[a] - 1 : int(f);
  }
  return c;
}

SurfaceGrid::Range SurfaceGrid::candidates(const Vec3f& p) const {
  if (allTriangles_.empty() || !bounds_.contains(p)) return {nullptr, nullptr};
  const Eigen::Vector3i c = cellOf(p);
  const int k = cellIndex(c[0], c[1], c[2]);
  return {cells_.begin(k), cells_.end(k)};
}

}  // namespace sb
