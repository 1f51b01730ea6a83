// A uniform grid over one body's surface triangles: finds every triangle within a given reach
// of a point by looking at one cell. Built from the surface's positions at one moment; the
// Contacts phase keeps it while the surface drifts less than a quarter spacing from there.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "sim/base/csr.h"
#include "sim/base/types.h"
#include "sim/mesh/closed_surface.h"
#include "sim/world/contact/box_tree.h"

namespace sb {

class SurfaceGrid {
 public:
  // Each triangle is entered in every cell its bounding box, grown by `reach` (metres, ≥ 0),
  // overlaps, so candidates(p) holds every triangle within `reach` of p for every p inside
  // `region` (only that part of space is gridded: where the particles that will ask are). Cells
  // are cubes of about `cellSize` metres (> 0), made larger when the grid would exceed
  // maxCellsPerAxis. Points are #P×3 columns x, y, z. sameTriangles: the triangles are those of
  // the last build (the surface moved), so the box tree is refit, not built anew (a speed-up
  // only: BoxTree::refit). lookAhead (metres, ≥ 0): cells also hold the triangles within
  // reach + lookAhead, so a look-up (forEachNear) with extra ≤ lookAhead reads one cell.
  void build(const std::vector<mesh::Triangle>& triangles, const float* x, const float* y,
             const float* z, float reach, float cellSize, const Eigen::AlignedBox3f& region,
             bool sameTriangles = false, float lookAhead = 0.0f);

  // The bounding box of all triangles grown by the reach, clipped to the region: outside it no
  // triangle is in reach (or the point is outside the region).
  const Eigen::AlignedBox3f& bounds() const { return bounds_; }
  float reach() const { return reach_; }

  // Triangle indices entered in p's cell, ascending; empty when p is outside bounds().
  struct Range {
    const int* begin;
    const int* end;
  };
  Range candidates(const Vec3f& p) const;

  // Calls visit(t) for the triangles t that may lie within reach() + extra of p (extra ≥ 0,
  // metres) and whose build-time box and plane are within sqrt(bound()) of p; bound() (m²) is read
  // again after each visit, so a search for the closest triangle can lower it as it goes. A
  // triangle may come up more than once. Looks at p's cell when extra ≤ the build's lookAhead,
  // else at the cells that overlap p ± (extra − lookAhead); when those are
  // more than maxCellsPerLookup (a fast particle, a long sub-step), it searches every triangle's
  // box nearest first in the box tree instead (without a tree — a non-finite position — it passes
  // over the gridded triangles once): a look-up never costs more than maxCellsPerLookup cells or
  // one visit per triangle within the bound, whatever the speeds. (It passed over every gridded
  // triangle there, and a soak whose drags and gravity changes made particles fast spent 500 ms
  // per step on those passes.) An empty grid (no triangle near the region) visits nothing.
  //
  // clearanceSquared, when given, is set to a lower bound (m²) on the squared distance from p to
  // every triangle of the surface at build time, visited or not: outside bounds(), the distance
  // to the box of all triangles; inside, when the look-up read cells (not the box tree), the
  // smaller of (reach + lookAhead)² (a triangle not entered in those cells is farther than
  // that) and the bounds of their triangles; else 0 (no bound).
  template <typename Bound, typename Visit>
  void forEachNear(const Vec3f& p, float extra, const Bound& bound, const Visit& visit,
                   float* clearanceSquared = nullptr) const;

  // Metres: how far a distance or a bound computed in this grid's coordinates may be off by
  // float rounding (32 ε times the largest coordinate of the region and the surface).
  float roundingTolerance() const { return planeTolerance_; }

  // A lower bound (m²) on the squared distance from p = (x, y, z, 1) to triangle t at build time,
  // to skip triangles without the exact test: the larger of the squared distances to its
  // bounding box and to its plane. (The box alone let 81 % of the seed-scale pile's look-ups
  // make exact tests that found nothing in reach: a tilted triangle's box is far larger than
  // the triangle.) Four lanes at once, no branch but the last.
  float distanceLowerBoundSquared(int t, const Eigen::Array4f& p) const {
    const TriangleBound& b = triangleBounds_[size_t(t)];
    const Eigen::Array4f gap = (b.min - p).max(p - b.max).max(0.0f);
    const Eigen::Array4f gap2 = gap * gap;
    const float box = (gap2[0] + gap2[1]) + gap2[2];  // x, y, z in order: the 3-float form's sum
    // Less the plane's rounding (planeTolerance_), so the bound never exceeds what the exact
    // test computes and a skipped triangle is one the exact test would not have taken.
    const float plane = std::abs((b.plane * p).sum()) - planeTolerance_;
    const float plane2 = plane > 0.0f ? plane * plane : 0.0f;
    return plane2 > box ? plane2 : box;  // a NaN plane (non-finite positions) leaves the box
  }
  // p as distanceLowerBoundSquared takes it.
  static Eigen::Array4f lanes(const Vec3f& p) { return Eigen::Array4f(p.x(), p.y(), p.z(), 1.0f); }

  // Every triangle's build-time box in a hierarchy, for a search of the whole surface (the deep
  // contact search); empty when the grid is (or a position was not finite).
  const BoxTree& boxTree() const { return boxTree_; }

  static constexpr int maxCellsPerAxis = 48;
  static constexpr long long maxCellsPerLookup = 64;
  static constexpr long long maxEntriesPerLookup = 96;
  bool empty() const { return allTriangles_.empty(); }

 private:
  Eigen::AlignedBox3f bounds_;
  Eigen::AlignedBox3f surfaceBox_;  // of all triangles at build time, not grown
  float reach_ = 0;
  float lookAhead_ = 0;
  Vec3f origin_ = Vec3f::Zero();
  float invCell_ = 1.0f;
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  Csr cells_;                      // the triangles entered in each cell, ascending
  std::vector<int> allTriangles_;  // every triangle entered in some cell, ascending
  std::vector<Eigen::AlignedBox3f> triangleBoxes_;  // per triangle, not grown
  // The same boxes as (x, y, z, 1) corners, and the plane (unit normal n, −n·a): the bound is
  // the look-ups' inner loop (a third of the contact search's own time in the seed-scale scene),
  // and in this form it is a few packed operations (the 3-float box test compiled to six
  // compare-and-jumps). The fourth lane of the corners is 1 like p's, so it adds no gap.
  struct TriangleBound {
    Eigen::Array4f min, max, plane;
  };
  std::vector<TriangleBound> triangleBounds_;
  // Metres: bound on the float rounding of a plane distance and of the exact test's distance,
  // for points and triangles within the grid's coordinates (32 ε times their largest magnitude).
  float planeTolerance_ = 0;
  BoxTree boxTree_;  // over triangleBoxes_
  // Scratch kept between builds so a rebuild does not allocate: each triangle's cell range.
  std::vector<Eigen::AlignedBox3i> cellBoxes_;
  int cellIndex(int i, int j, int k) const { return (k * dims_.y() + j) * dims_.x() + i; }
  Eigen::Vector3i cellOf(const Vec3f& p) const;
};

template <typename Bound, typename Visit>
void SurfaceGrid::forEachNear(const Vec3f& p, float extra, const Bound& bound, const Visit& visit,
                              float* clearanceSquared) const {
  // Outside bounds(), the distance to the box of all triangles bounds the distance to each.
  const bool inside = bounds_.contains(p);
  if (clearanceSquared) {
    const float outside = inside ? 0.0f : surfaceBox_.squaredExteriorDistance(p);
    *clearanceSquared = std::isfinite(outside) ? outside : 0.0f;
  }
  if (allTriangles_.empty()) return;  // also: bounds_ is empty, cellOf has no cell to clamp to
  const Eigen::Array4f p4 = lanes(p);
  // Every triangle not entered in the cells read has its box grown by reach + lookAhead apart
  // from p, as p's own cell is among them (cellOf is monotone), or does not meet bounds() at all;
  // those read lower it to their bounds.
  float clearance = (reach_ + lookAhead_) * (reach_ + lookAhead_);
  auto visitRange = [&](const int* begin, const int* end) {
    for (const int* t = begin; t != end; ++t) {
      const float d2 = distanceLowerBoundSquared(*t, p4);
      clearance = d2 < clearance ? d2 : clearance;
      if (!(d2 > bound())) visit(*t);
    }
  };
  // Every triangle within reach + extra of p has its grown box (reach + lookAhead) within
  // extra − lookAhead of p, so it is entered in a cell overlapping p ± (extra − lookAhead) and
  // bounds() (the three boxes meet pairwise, so they meet: cellOf clamps to bounds()).
  const float widen = std::max(extra - lookAhead_, 0.0f);  // 0: one cell, with a look-ahead
  const Eigen::AlignedBox3f reached(p.array() - std::max(extra, 0.0f),
                                    p.array() + std::max(extra, 0.0f));
  if (!reached.intersects(bounds_)) return;
  const Eigen::Vector3i lo = cellOf(Vec3f(p.array() - widen));
  const Eigen::Vector3i hi = widen > 0.0f ? cellOf(Vec3f(p.array() + widen)) : lo;
  const Eigen::Vector3i span = hi - lo + Eigen::Vector3i::Ones();
  // Entries in those cells, most of them to be rejected by their boxes: a crumpled or folded
  // surface can pack hundreds of triangles into one cell, and the tree then rejects them by the
  // dozen.
  long long entries = maxEntriesPerLookup + 1;
  if (1LL * span.x() * span.y() * span.z() <= maxCellsPerLookup) {
    entries = 0;
    for (int k = lo.z(); k <= hi.z(); ++k)
      for (int j = lo.y(); j <= hi.y(); ++j)
        entries += cells_.start[size_t(cellIndex(hi.x(), j, k)) + 1] -
                   cells_.start[size_t(cellIndex(lo.x(), j, k))];
  }
  if (entries > maxEntriesPerLookup) {
    if (boxTree_.empty())
      visitRange(allTriangles_.data(), allTriangles_.data() + allTriangles_.size());
    else
      boxTree_.visitNear(p, bound, [&](int t) {
        if (!(distanceLowerBoundSquared(t, p4) > bound())) visit(t);
      });
    return;
  }
  for (int k = lo.z(); k <= hi.z(); ++k)
    for (int j = lo.y(); j <= hi.y(); ++j)
      for (int i = lo.x(); i <= hi.x(); ++i) {
        const int c = cellIndex(i, j, k);
        visitRange(cells_.begin(c), cells_.end(c));
      }
  if (clearanceSquared && inside) *clearanceSquared = clearance;
}

}  // namespace sb
