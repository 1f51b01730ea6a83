// makeCage: input checks, the voxel frame, the retry at a coarser resolution when the budget is
// not reached, the final independent checks and the report. See auto_cage.h.
#include "sim/cage/auto_cage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "sim/base/parallel.h"
#include "sim/base/parallel_for.h"
#include "sim/cage/auto_cage_decimate.h"
#include "sim/cage/auto_cage_geometry.h"
#include "sim/cage/auto_cage_voxels.h"
#include "sim/mesh/closed_surface.h"

namespace sb::cage {

namespace {

using detail::GuardSet;
using detail::Tri;
using detail::Vec;

constexpr double kPi = 3.14159265358979323846;
// Empty voxels around the bounding box: the exterior flood starts there and must surround the
// occupied voxels (radius < 1.2) and the voxels the closing adds next to them.
constexpr int kPad = 4;
// Every point within kMargin voxels of the input lies in the voxel solid, so the first cage keeps
// the guard points kMargin away; collapses keep them kClearance away (both in voxels).
constexpr double kMargin = 0.25;
constexpr double kClearance = 0.1;
// The first limit on the distance of the cage's faces from the guard points (fraction of the
// bounding-box diagonal), relaxed by the decimation when it blocks the budget.
constexpr double kFirstDeviation = 0.03;
// The coarsest resolution tried when the budget is not reached at the requested one.
constexpr int kMinResolution = 8;

std::string str(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

void checkInput(const mesh::TriangleMesh& m, const CageOptions& o) {
  if (o.vertexBudget < 4)
    throw std::invalid_argument("vertexBudget: " + std::to_string(o.vertexBudget) +
                                " is below 4 (the smallest closed cage is a tetrahedron)");
  if (!(o.tightness >= 0.0 && o.tightness <= 1.0))
    throw std::invalid_argument("tightness: " + str(o.tightness) + " is outside [0, 1]");
  if (o.threads < 0)
    throw std::invalid_argument("threads: " + std::to_string(o.threads) + " is negative");
  if (m.vertices.empty()) throw std::invalid_argument("mesh: has no vertices");
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    if (!m.vertices[i].allFinite())
      throw std::invalid_argument("mesh: vertex " + std::to_string(i) +
                                  " has a non-finite coordinate");
  const int n = static_cast<int>(m.vertices.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (const int v : m.triangles[t])
      if (v < 0 || v >= n)
        throw std::invalid_argument("mesh: triangle " + std::to_string(t) + " has index " +
                                    std::to_string(v) + " outside [0, " + std::to_string(n) + ")");
}

double winding(const mesh::TriangleMesh& cage, const Vec& x) {
  double s = 0.0;
  for (const Tri& t : cage.triangles)
    s += detail::solidAngle(x, cage.vertices[static_cast<std::size_t>(t[0])],
                            cage.vertices[static_cast<std::size_t>(t[1])],
                            cage.vertices[static_cast<std::size_t>(t[2])]);
  return s / (4.0 * kPi);
}

double distanceTo(const mesh::TriangleMesh& cage, const Vec& x) {
  double d = std::numeric_limits<double>::infinity();
  for (const Tri& t : cage.triangles)
    d = std::min(d, detail::pointTriangleDistance(x, cage.vertices[static_cast<std::size_t>(t[0])],
                                                  cage.vertices[static_cast<std::size_t>(t[1])],
                                                  cage.vertices[static_cast<std::size_t>(t[2])]));
  return d;
}

// All pairs of triangles with overlapping boxes (the cage is small).
void checkNoSelfIntersection(const mesh::TriangleMesh& cage) {
  const std::size_t n = cage.triangles.size();
  std::vector<std::array<Vec, 3>> c(n);
  std::vector<Vec> lo(n), hi(n);
  for (std::size_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k)
      c[t][static_cast<std::size_t>(k)] =
          cage.vertices[static_cast<std::size_t>(cage.triangles[t][static_cast<std::size_t>(k)])];
    lo[t] = c[t][0].cwiseMin(c[t][1]).cwiseMin(c[t][2]);
    hi[t] = c[t][0].cwiseMax(c[t][1]).cwiseMax(c[t][2]);
  }
  for (std::size_t s = 0; s < n; ++s)
    for (std::size_t t = s + 1; t < n; ++t)
      if ((lo[s].array() <= hi[t].array()).all() && (lo[t].array() <= hi[s].array()).all() &&
          detail::trianglesIntersect(c[s], cage.triangles[s], c[t], cage.triangles[t]))
        throw std::runtime_error("automatic cage: final check failed: triangles " +
                                 std::to_string(s) + " and " + std::to_string(t) + " intersect");
}

// Every guard point inside (winding number 1) and at a positive distance; returns a lower bound
// of the smallest distance (voxels). A bucket whose ball lies clear of the cage is decided by its
// centre.
double checkEnclosure(const mesh::TriangleMesh& cage, const GuardSet& guards, int threads) {
  const int n = static_cast<int>(guards.buckets.size());
  std::vector<double> clearance(static_cast<std::size_t>(n));
  std::vector<int> outside(static_cast<std::size_t>(n), -1);
  parallelRanges(n, 2, threads, [&](int begin, int end) {
    for (int b = begin; b < end; ++b) {
      const GuardSet::Bucket& bucket = guards.buckets[static_cast<std::size_t>(b)];
      const double d = distanceTo(cage, bucket.centre);
      double& c = clearance[static_cast<std::size_t>(b)];
      if (d > bucket.radius) {
        c = d - bucket.radius;
        if (std::abs(winding(cage, bucket.centre) - 1.0) > 0.5)
          outside[static_cast<std::size_t>(b)] = bucket.begin;
        continue;
      }
      c = std::numeric_limits<double>::infinity();
      // The ball around the last evaluated point q, of radius its distance to the cage, holds no
      // cage: points in it share q's winding number and are at least (radius − |x − q|) away.
      Vec q = Vec::Zero();
      double radius = 0.0;
      for (int g = bucket.begin; g < bucket.end; ++g) {
        const Vec& x = guards.points[static_cast<std::size_t>(g)];
        const double fromQ = (x - q).norm();
        if (fromQ < radius) {
          c = std::min(c, radius - fromQ);
          continue;
        }
        q = x;
        radius = distanceTo(cage, x);
        c = std::min(c, radius);
        if (!(std::abs(winding(cage, x) - 1.0) < 0.5) && outside[static_cast<std::size_t>(b)] < 0)
          outside[static_cast<std::size_t>(b)] = g;
      }
    }
  });
  double smallest = std::numeric_limits<double>::infinity();
  for (int b = 0; b < n; ++b) {
    if (outside[static_cast<std::size_t>(b)] >= 0)
      throw std::runtime_error("automatic cage: final check failed: a guard point lies outside");
    smallest = std::min(smallest, clearance[static_cast<std::size_t>(b)]);
  }
  if (!(smallest > 0.0))
    throw std::runtime_error("automatic cage: final check failed: a guard point lies on the cage");
  return smallest;
}

// Input triangles (a vertex as a degenerate triangle when there are none) by the cells of
// kCell voxels their boxes overlap, for nearest-distance queries by growing shells of cells.
class TriangleIndex {
 public:
  static constexpr double kCell = 2.0;
  TriangleIndex(const std::vector<Vec>& v, const std::vector<Tri>& t,
                const std::array<int, 3>& cells)
      : v_(v), t_(t) {
    if (t_.empty())
      for (std::size_t i = 0; i < v.size(); ++i) t_.push_back({int(i), int(i), int(i)});
    for (int d = 0; d < 3; ++d) n_[d] = static_cast<int>(std::ceil(cells[d] / kCell)) + 1;
    std::vector<std::vector<int>> lists(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2]);
    for (std::size_t i = 0; i < t_.size(); ++i) {
      const Vec &a = v_[std::size_t(t_[i][0])], &b = v_[std::size_t(t_[i][1])],
                &c = v_[std::size_t(t_[i][2])];
      const std::array<int, 3> lo = cellOf(a.cwiseMin(b).cwiseMin(c)),
                               hi = cellOf(a.cwiseMax(b).cwiseMax(c));
      for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int x = lo[0]; x <= hi[0]; ++x) lists[index(x, y, z)].push_back(static_cast<int>(i));
    }
    start_.push_back(0);
    for (const auto& l : lists) {
      items_.insert(items_.end(), l.begin(), l.end());
      start_.push_back(static_cast<int>(items_.size()));
    }
  }
  double distance(const Vec& p) const {
    const std::array<int, 3> c = cellOf(p);
    double best = std::numeric_limits<double>::infinity();
    const int maxShell = std::max({n_[0], n_[1], n_[2]});
    for (int s = 0; s <= maxShell; ++s) {
      for (int z = c[2] - s; z <= c[2] + s; ++z)
        for (int y = c[1] - s; y <= c[1] + s; ++y)
          for (int x = c[0] - s; x <= c[0] + s; ++x) {
            if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) != s)
              continue;
            if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) continue;
            // A triangle's closest point lies in one of its cells, so a cell no nearer than the
            // best distance so far cannot improve it.
            const Vec cellLo = kCell * Vec(x, y, z);
            if ((p - p.cwiseMax(cellLo).cwiseMin(cellLo + Vec::Constant(kCell))).norm() >= best)
              continue;
            const std::size_t cell = index(x, y, z);
            for (int i = start_[cell]; i < start_[cell + 1]; ++i) {
              const Tri& t = t_[static_cast<std::size_t>(items_[static_cast<std::size_t>(i)])];
              best = std::min(best, detail::pointTriangleDistance(p, v_[std::size_t(t[0])],
                                                                  v_[std::size_t(t[1])],
                                                                  v_[std::size_t(t[2])]));
            }
          }
      // Cells beyond shell s are at least s·kCell away (p lies in its cell, which may be clamped).
      if (best <= s * kCell) break;
    }
    return best;
  }

 private:
  std::array<int, 3> cellOf(const Vec& p) const {
    std::array<int, 3> c{};
    for (int d = 0; d < 3; ++d)
      c[d] = std::clamp(static_cast<int>(std::floor(p[d] / kCell)), 0, n_[d] - 1);
    return c;
  }
  std::size_t index(int x, int y, int z) const {
    return std::size_t(x) +
           std::size_t(n_[0]) * (std::size_t(y) + std::size_t(n_[1]) * std::size_t(z));
  }
  const std::vector<Vec>& v_;
  std::vector<Tri> t_;
  std::array<int, 3> n_{};
  std::vector<int> start_, items_;
};

// One-sided Hausdorff distance cage → input (voxels): the largest distance from points on the
// cage (its vertices and samples ≤ 1 voxel apart on its triangles) to the input.
double hausdorff(const mesh::TriangleMesh& cage, const TriangleIndex& index, int threads) {
  std::vector<Vec> samples(cage.vertices);
  for (const Tri& t : cage.triangles) {
    const Vec &a = cage.vertices[std::size_t(t[0])], &b = cage.vertices[std::size_t(t[1])],
              &c = cage.vertices[std::size_t(t[2])];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int k = std::clamp(static_cast<int>(std::ceil(longest)), 1, 64);
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j)
        samples.push_back((1.0 - double(i + j) / k) * a + double(i) / k * b + double(j) / k * c);
  }
  std::vector<double> d(samples.size());
  parallelRanges(static_cast<int>(samples.size()), 64, threads, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      d[static_cast<std::size_t>(i)] = index.distance(samples[static_cast<std::size_t>(i)]);
  });
  return *std::max_element(d.begin(), d.end());
}

}  // namespace

CageResult makeCage(const mesh::TriangleMesh& input, const CageOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  checkInput(input, options);
  Vec lo = input.vertices[0], hi = lo;
  for (const Vec& v : input.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Vec extent = hi - lo;
  const double longest = extent.maxCoeff();
  if (!(longest > 0.0))
    throw std::invalid_argument("mesh: all vertices coincide (nothing to enclose)");
  const int threads =
      options.threads > 0 ? std::min(options.threads, threadCount()) : threadCount();

  CageResult result;
  CageReport& report = result.report;
  int resolution = 24 + static_cast<int>(std::lround(options.tightness * 104.0));
  for (;;) {
    // The voxel frame: one unit per voxel, origin at the padded grid's corner.
    const double h = longest / resolution;
    const Vec origin = lo - Vec::Constant(kPad * h);
    std::array<int, 3> cells{};
    for (int d = 0; d < 3; ++d)
      cells[static_cast<std::size_t>(d)] = static_cast<int>(std::ceil(extent[d] / h)) + 2 * kPad;
    std::vector<Vec> local(input.vertices.size());
    for (std::size_t i = 0; i < local.size(); ++i) local[i] = (input.vertices[i] - origin) / h;

    const GuardSet guards = detail::makeGuards(local, input.triangles, 1.0, cells);
    mesh::TriangleMesh cage =
        detail::voxelSurface(local, input.triangles, cells, 0.5 * std::sqrt(3.0) + kMargin);
    report.fineVertices = static_cast<int>(cage.vertices.size());
    detail::decimateCage(cage, guards, options.vertexBudget, kClearance,
                         kFirstDeviation * extent.norm() / h);
    if (static_cast<int>(cage.vertices.size()) > options.vertexBudget &&
        resolution > kMinResolution) {
      resolution = std::max(kMinResolution, resolution * 2 / 3);
      continue;
    }

    result.cage.triangles = cage.triangles;
    result.cage.vertices.resize(cage.vertices.size());
    for (std::size_t i = 0; i < cage.vertices.size(); ++i)
      result.cage.vertices[i] = origin + h * cage.vertices[i];
    try {
      mesh::validateClosedSurface(result.cage, "automatic cage");
    } catch (const mesh::SurfaceError& e) {
      throw std::runtime_error(std::string("automatic cage: final check failed: ") + e.what());
    }
    // The checks see the cage as written (back in the voxel frame from world coordinates).
    for (std::size_t i = 0; i < cage.vertices.size(); ++i)
      cage.vertices[i] = (result.cage.vertices[i] - origin) / h;
    checkNoSelfIntersection(cage);
    report.minClearance = h * checkEnclosure(cage, guards, threads);
    report.hausdorff = h * hausdorff(cage, TriangleIndex(local, input.triangles, cells), threads);
    report.voxelResolution = resolution;
    report.guardPoints = static_cast<int>(guards.points.size());
    break;
  }
  report.vertices = static_cast<int>(result.cage.vertices.size());
  report.triangles = static_cast<int>(result.cage.triangles.size());
  report.diagonal = extent.norm();
  report.hausdorffRelative = report.hausdorff / report.diagonal;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace sb::cage
