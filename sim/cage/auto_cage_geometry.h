// Geometric predicates of the automatic cage (internal to sim/cage): solid angles for winding
// numbers, triangle–triangle intersection aware of shared corners, and the guard points with
// their buckets. Everything works in the voxel frame of auto_cage.cpp (one unit = one voxel), in
// which the first cage's corners are small integers, so coplanar voxel faces test exactly
// coplanar.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sb::cage::detail {

using Vec = Eigen::Vector3d;
using Tri = std::array<int, 3>;

// Signed solid angle (steradians, in (−2π, 2π)) of triangle (a, b, c) seen from p: positive when
// p sees the triangle counter-clockwise, i.e. p is on its inner side (Van Oosterom & Strackee).
// A closed, outward-oriented surface's solid angles sum to 4π inside and 0 outside.
double solidAngle(const Vec& p, const Vec& a, const Vec& b, const Vec& c);

// Distance from p to triangle (a, b, c).
double pointTriangleDistance(const Vec& p, const Vec& a, const Vec& b, const Vec& c);

// Whether triangles t = (t0, t1, t2) and u = (u0, u1, u2) intersect anywhere other than in the
// corners they share. ids name the corners (equal ids = the same vertex; −1 never matches); two
// shared corners mean a shared edge, which counts as an intersection only when the two
// triangles fold onto each other (dihedral angle under ~2.6°). Touching counts as intersecting
// (conservative); exactly coplanar triangles are tested in their plane.
bool trianglesIntersect(const std::array<Vec, 3>& t, const Tri& tIds, const std::array<Vec, 3>& u,
                        const Tri& uIds);

// Guard points (the points that must stay strictly inside the cage) sorted into cubic buckets of
// kBucketSize voxels, so a test over a region visits whole buckets: a bucket whose bounding ball
// the moved surfaces do not reach has one winding number for all its points.
struct GuardSet {
  static constexpr int kBucketSize = 2;
  std::vector<Vec> points;        // sorted by bucket
  std::array<int, 3> dims{};      // bucket grid size
  std::vector<int> bucketOfCell;  // dims[0]·dims[1]·dims[2]: index into buckets or −1
  struct Bucket {
    int begin, end;  // range of points
    Vec lo, hi;      // the points' bounding box
    Vec centre;      // its centre
    double radius;   // the points are within radius of centre
  };
  std::vector<Bucket> buckets;
  // The buckets whose cell overlaps [lo, hi] (voxel frame), ascending.
  void bucketsIn(const Vec& lo, const Vec& hi, std::vector<int>& out) const;
};

// Most guard points makeGuards builds (~2.6 GB while they are sorted): many triangles much longer
// than a voxel need k²/2 samples each, so a soup of large triangles would otherwise exhaust memory.
inline constexpr long long kMaxGuardPoints = 50000000;

// Input vertices plus samples on every triangle at most `spacing` apart (the centroid for a small
// triangle), in the voxel frame; `cells` bounds the grid (points must lie in [0, cells)). Throws
// std::invalid_argument ("mesh: ...") when that would be more than kMaxGuardPoints points.
GuardSet makeGuards(const std::vector<Vec>& vertices, const std::vector<Tri>& triangles,
                    double spacing, const std::array<int, 3>& cells);

}  // namespace sb::cage::detail
