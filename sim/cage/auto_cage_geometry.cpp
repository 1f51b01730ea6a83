// Predicates of the automatic cage: see auto_cage_geometry.h.
#include "sim/cage/auto_cage_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "sim/mesh/closest_point.h"

namespace sb::cage::detail {

namespace {

// Six times the signed volume of tetrahedron (a, b, c, d).
double orient(const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
  return (b - a).dot((c - a).cross(d - a));
}

using Vec2 = Eigen::Vector2d;

double orient2(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

// Closed triangle (boundary included) contains p, in either orientation.
bool insideTriangle2(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c) {
  const double d1 = orient2(a, b, p), d2 = orient2(b, c, p), d3 = orient2(c, a, p);
  return (d1 >= 0 && d2 >= 0 && d3 >= 0) || (d1 <= 0 && d2 <= 0 && d3 <= 0);
}

// Closed segments pq and rs meet (collinear overlap included).
bool segmentsMeet2(const Vec2& p, const Vec2& q, const Vec2& r, const Vec2& s) {
  const double o1 = orient2(p, q, r), o2 = orient2(p, q, s), o3 = orient2(r, s, p),
               o4 = orient2(r, s, q);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return true;
  const auto onSegment = [](const Vec2& a, const Vec2& b, const Vec2& x) {
    return x.x() >= std::min(a.x(), b.x()) && x.x() <= std::max(a.x(), b.x()) &&
           x.y() >= std::min(a.y(), b.y()) && x.y() <= std::max(a.y(), b.y());
  };
  return (o1 == 0 && onSegment(p, q, r)) || (o2 == 0 && onSegment(p, q, s)) ||
         (o3 == 0 && onSegment(r, s, p)) || (o4 == 0 && onSegment(r, s, q));
}

// Segment pq and triangle abc lying in one plane: tested in the coordinate plane most nearly
// parallel to it.
bool coplanarSegmentTriangle(const Vec& p, const Vec& q, const Vec& a, const Vec& b, const Vec& c) {
  const Vec n = (b - a).cross(c - a);
  int drop = 0;
  n.cwiseAbs().maxCoeff(&drop);
  if (n[drop] == 0) return true;  // degenerate triangle: conservative
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  const Vec2 p2(p[u], p[v]), q2(q[u], q[v]), a2(a[u], a[v]), b2(b[u], b[v]), c2(c[u], c[v]);
  return insideTriangle2(p2, a2, b2, c2) || insideTriangle2(q2, a2, b2, c2) ||
         segmentsMeet2(p2, q2, a2, b2) || segmentsMeet2(p2, q2, b2, c2) ||
         segmentsMeet2(p2, q2, c2, a2);
}

// Closed segment pq meets closed triangle abc.
bool segmentTriangle(const Vec& p, const Vec& q, const Vec& a, const Vec& b, const Vec& c) {
  double s1 = orient(a, b, c, p), s2 = orient(a, b, c, q);
  // An end within 1e-9 of the triangle's size from its plane counts as in the plane: faces that
  // were exactly coplanar in the voxel frame come back a rounding error apart from world
  // coordinates, and the 3D signs of nearly coplanar configurations are noise.
  const Vec n = (b - a).cross(c - a);
  const double tolerance = 1e-9 * n.norm() * ((b - a).norm() + (c - a).norm() + (q - p).norm());
  if (std::abs(s1) <= tolerance) s1 = 0;
  if (std::abs(s2) <= tolerance) s2 = 0;
  if (s1 == 0 && s2 == 0) return coplanarSegmentTriangle(p, q, a, b, c);
  if ((s1 > 0 && s2 > 0) || (s1 < 0 && s2 < 0)) return false;
  const double e1 = orient(p, q, a, b), e2 = orient(p, q, b, c), e3 = orient(p, q, c, a);
  return (e1 >= 0 && e2 >= 0 && e3 >= 0) || (e1 <= 0 && e2 <= 0 && e3 <= 0);
}

bool anyEdgeMeets(const std::array<Vec, 3>& t, const std::array<Vec, 3>& u) {
  for (int k = 0; k < 3; ++k)
    if (segmentTriangle(t[k], t[(k + 1) % 3], u[0], u[1], u[2])) return true;
  return false;
}

// All corners of u strictly on one side of t's plane, beyond rounding (the cheap early out).
bool strictlyOneSide(const std::array<Vec, 3>& t, const std::array<Vec, 3>& u) {
  const Vec n = (t[1] - t[0]).cross(t[2] - t[0]);
  const double size = (t[1] - t[0]).norm() + (t[2] - t[0]).norm();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec& x : u) {
    const double s = n.dot(x - t[0]);
    const double tolerance = 1e-9 * n.norm() * (size + (x - t[0]).norm());
    lo = std::min(lo, s - tolerance);
    hi = std::max(hi, s + tolerance);
  }
  return lo > 0 || hi < 0;
}

}  // namespace

double solidAngle(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const Vec x = a - p, y = b - p, z = c - p;
  const double lx = x.norm(), ly = y.norm(), lz = z.norm();
  const double det = x.dot(y.cross(z));
  const double den = lx * ly * lz + x.dot(y) * lz + y.dot(z) * lx + z.dot(x) * ly;
  return 2.0 * std::atan2(det, den);
}

double pointTriangleDistance(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const auto cp = mesh::closestPointOnTriangle<double>(p, a, b, c);
  return (p - (cp.weights[0] * a + cp.weights[1] * b + cp.weights[2] * c)).norm();
}

bool trianglesIntersect(const std::array<Vec, 3>& t, const Tri& tIds, const std::array<Vec, 3>& u,
                        const Tri& uIds) {
  int shared = 0, ti = -1, uj = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (tIds[i] >= 0 && tIds[i] == uIds[j]) {
        ++shared;
        ti = i;
        uj = j;
      }
  if (shared == 0)
    return !strictlyOneSide(t, u) && !strictlyOneSide(u, t) &&
           (anyEdgeMeets(t, u) || anyEdgeMeets(u, t));
  if (shared == 1) {
    // Non-coplanar triangles meeting in a corner can only cross along a segment from that
    // corner, which leaves one of them through its opposite edge.
    return segmentTriangle(t[(ti + 1) % 3], t[(ti + 2) % 3], u[0], u[1], u[2]) ||
           segmentTriangle(u[(uj + 1) % 3], u[(uj + 2) % 3], t[0], t[1], t[2]);
  }
  if (shared == 2) {
    const Vec nt = (t[1] - t[0]).cross(t[2] - t[0]), nu = (u[1] - u[0]).cross(u[2] - u[0]);
    return nt.dot(nu) < -0.999 * nt.norm() * nu.norm();
  }
  return true;  // the same three corners
}

void GuardSet::bucketsIn(const Vec& lo, const Vec& hi, std::vector<int>& out) const {
  out.clear();
  std::array<int, 3> a{}, b{};
  for (int d = 0; d < 3; ++d) {
    a[d] = std::clamp(static_cast<int>(std::floor(lo[d] / kBucketSize)), 0, dims[d] - 1);
    b[d] = std::clamp(static_cast<int>(std::floor(hi[d] / kBucketSize)), 0, dims[d] - 1);
  }
  for (int k = a[2]; k <= b[2]; ++k)
    for (int j = a[1]; j <= b[1]; ++j)
      for (int i = a[0]; i <= b[0]; ++i) {
        const int id = bucketOfCell[static_cast<std::size_t>(i + dims[0] * (j + dims[1] * k))];
        if (id >= 0) out.push_back(id);
      }
}

GuardSet makeGuards(const std::vector<Vec>& vertices, const std::vector<Tri>& triangles,
                    double spacing, const std::array<int, 3>& cells) {
  auto samplesPerSide = [&](const Tri& t) {
    const Vec &a = vertices[static_cast<std::size_t>(t[0])],
              &b = vertices[static_cast<std::size_t>(t[1])],
              &c = vertices[static_cast<std::size_t>(t[2])];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    return std::max(1, static_cast<int>(std::ceil(longest / spacing)));
  };
  // Counted before anything is allocated: a triangle with k samples per side adds about k²/2.
  double total = double(vertices.size());
  for (const Tri& t : triangles) {
    const double k = samplesPerSide(t);
    total += k == 1 ? 1.0 : 0.5 * (k + 1) * (k + 2);
  }
  if (total > double(kMaxGuardPoints))
    throw std::invalid_argument(
        "mesh: its triangles would need " + std::to_string(static_cast<long long>(total)) +
        " sample points (at most " + std::to_string(kMaxGuardPoints) +
        "): too many triangles much longer than a voxel (a lower tightness makes the voxels "
        "larger)");
  std::vector<Vec> raw(vertices);
  for (const Tri& t : triangles) {
    const Vec &a = vertices[static_cast<std::size_t>(t[0])],
              &b = vertices[static_cast<std::size_t>(t[1])],
              &c = vertices[static_cast<std::size_t>(t[2])];
    const int k = samplesPerSide(t);
    if (k == 1) {
      raw.push_back((a + b + c) / 3.0);
      continue;
    }
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j) {
        if (i == k || j == k || i + j == 0) continue;  // the corners are guards already
        const double u = double(i) / k, v = double(j) / k;
        raw.push_back((1.0 - u - v) * a + u * b + v * c);
      }
  }
  GuardSet g;
  for (int d = 0; d < 3; ++d)
    g.dims[d] = (cells[d] + GuardSet::kBucketSize - 1) / GuardSet::kBucketSize;
  const std::size_t cellCount = static_cast<std::size_t>(g.dims[0]) * g.dims[1] * g.dims[2];
  std::vector<int> cellOf(raw.size()), count(cellCount + 1, 0);
  for (std::size_t i = 0; i < raw.size(); ++i) {
    std::array<int, 3> c{};
    for (int d = 0; d < 3; ++d)
      c[d] = std::clamp(static_cast<int>(std::floor(raw[i][d] / GuardSet::kBucketSize)), 0,
                        g.dims[d] - 1);
    cellOf[i] = c[0] + g.dims[0] * (c[1] + g.dims[1] * c[2]);
    ++count[static_cast<std::size_t>(cellOf[i]) + 1];
  }
  for (std::size_t c = 0; c < cellCount; ++c) count[c + 1] += count[c];
  g.points.resize(raw.size());
  {
    std::vector<int> next(count.begin(), count.end() - 1);
    for (std::size_t i = 0; i < raw.size(); ++i)
      g.points[static_cast<std::size_t>(next[static_cast<std::size_t>(cellOf[i])]++)] = raw[i];
  }
  g.bucketOfCell.assign(cellCount, -1);
  for (std::size_t c = 0; c < cellCount; ++c) {
    if (count[c] == count[c + 1]) continue;
    Vec lo = g.points[static_cast<std::size_t>(count[c])], hi = lo;
    for (int i = count[c]; i < count[c + 1]; ++i) {
      lo = lo.cwiseMin(g.points[static_cast<std::size_t>(i)]);
      hi = hi.cwiseMax(g.points[static_cast<std::size_t>(i)]);
    }
    g.bucketOfCell[c] = static_cast<int>(g.buckets.size());
    g.buckets.push_back({count[c], count[c + 1], lo, hi, 0.5 * (lo + hi), 0.5 * (hi - lo).norm()});
  }
  return g;
}

}  // namespace sb::cage::detail
