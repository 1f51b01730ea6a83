#include "sim/mesh/closed_surface.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include <Eigen/Geometry>

namespace sb::mesh {

namespace {

// One corner-to-corner edge of a triangle: edge k of triangle `tri`, stored as (a, b) with a < b;
// `forward` when the triangle runs from a to b.
struct HalfEdge {
  int a, b;
  int tri, k;
  bool forward;
};

// Every triangle's three half-edges, grouped by undirected edge: sorted by (a, b), then triangle
// and corner, so each edge's uses are consecutive and in triangle order.
std::vector<HalfEdge> sortedHalfEdges(const std::vector<Triangle>& triangles) {
  std::vector<HalfEdge> half;
  half.reserve(3 * triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int from = triangles[t][size_t(k)], to = triangles[t][size_t((k + 1) % 3)];
      half.push_back({std::min(from, to), std::max(from, to), int(t), k, from < to});
    }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.a, x.b, x.tri, x.k) < std::tie(y.a, y.b, y.tri, y.k);
  });
  return half;
}

// Calls visit(first, last) for each run [first, last) of half-edges of one undirected edge.
template <typename Visit>
void forEachEdge(const std::vector<HalfEdge>& half, const Visit& visit) {
  for (size_t i = 0; i < half.size();) {
    size_t j = i + 1;
    while (j < half.size() && half[j].a == half[i].a && half[j].b == half[i].b) ++j;
    visit(i, j);
    i = j;
  }
}

SurfaceTopology topologyFrom(const std::vector<Triangle>& triangles, int vertexCount,
                             const std::vector<HalfEdge>& half) {
  SurfaceTopology topo;
  topo.triangleEdges.assign(triangles.size(), {-1, -1, -1});
  topo.neighbours.assign(triangles.size(), {-1, -1, -1});
  forEachEdge(half, [&](size_t first, size_t last) {
    const int e = static_cast<int>(topo.edges.size());
    topo.edges.push_back({half[first].a, half[first].b});
    for (size_t u = first; u < last; ++u) {
      topo.triangleEdges[size_t(half[u].tri)][size_t(half[u].k)] = e;
      // The other use of the edge (the next one, cyclically, where there are more than two).
      const size_t other = u + 1 < last ? u + 1 : first;
      if (other != u) topo.neighbours[size_t(half[u].tri)][size_t(half[u].k)] = half[other].tri;
    }
  });
  buildCsr(
      vertexCount,
      [&](const auto& emit) {
        for (size_t t = 0; t < triangles.size(); ++t)
          for (int i : triangles[t]) emit(i, int(t));
      },
      topo.vertexTriangles);
  return topo;
}

[[noreturn]] void fail(const std::string& name, const std::string& reason) {
  throw SurfaceError(name + ": " + reason);
}

std::string vstr(const Vec3& v) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

std::string edgeName(const HalfEdge& h) {
  return "edge " + std::to_string(h.a) + "-" + std::to_string(h.b);
}

Vec3f corner(const float* x, const float* y, const float* z, int i) {
  return Vec3f(x[i], y[i], z[i]);
}

Vec3f unitFaceNormal(const Triangle& t, const float* x, const float* y, const float* z) {
  const Vec3f a = corner(x, y, z, t[0]);
  const Vec3f n = (corner(x, y, z, t[1]) - a).cross(corner(x, y, z, t[2]) - a);
  const float len = n.norm();
  return len > 0.0f ? Vec3f(n / len) : Vec3f::Zero();
}

}  // namespace

SurfaceTopology buildSurfaceTopology(const std::vector<Triangle>& triangles, int vertexCount) {
  return topologyFrom(triangles, vertexCount, sortedHalfEdges(triangles));
}

SurfaceTopology validateClosedSurface(const TriangleMesh& surface, const std::string& name,
                                      const SurfaceRules& rules) {
  const int nv = static_cast<int>(surface.vertices.size());
  const int nt = static_cast<int>(surface.triangles.size());
  if (nv < 4) fail(name, "a closed surface needs at least 4 vertices, got " + std::to_string(nv));
  if (nt < 4) fail(name, "a closed surface needs at least 4 triangles, got " + std::to_string(nt));

  for (int i = 0; i < nv; ++i)
    if (!surface.vertices[size_t(i)].allFinite())
      fail(name, "vertex " + std::to_string(i) + " has a non-finite coordinate " +
                     vstr(surface.vertices[size_t(i)]));
  Eigen::AlignedBox3d box;
  for (const auto& t : surface.triangles)
    for (int i : t)
      if (i >= 0 && i < nv) box.extend(surface.vertices[size_t(i)]);
  if (!rules.allowUnusedVertices)
    for (const auto& v : surface.vertices) box.extend(v);
  const double diag = box.diagonal().norm();

  for (int t = 0; t < nt; ++t) {
    const auto& tri = surface.triangles[size_t(t)];
    for (int k = 0; k < 3; ++k)
      if (tri[size_t(k)] < 0 || tri[size_t(k)] >= nv)
        fail(name, "triangle " + std::to_string(t) + " has vertex index " +
                       std::to_string(tri[size_t(k)]) + " out of range [0, " +
                       std::to_string(nv - 1) + "]");
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      fail(name, "triangle " + std::to_string(t) + " repeats a vertex (" + std::to_string(tri[0]) +
                     ", " + std::to_string(tri[1]) + ", " + std::to_string(tri[2]) +
                     "): zero area");
  }
  for (int t = 0; t < nt; ++t) {
    const auto& tri = surface.triangles[size_t(t)];
    const Vec3& a = surface.vertices[size_t(tri[0])];
    const Vec3& b = surface.vertices[size_t(tri[1])];
    const Vec3& c = surface.vertices[size_t(tri[2])];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const double twiceArea = (b - a).cross(c - a).norm();
    if (longest <= 1e-12 * diag || twiceArea <= 1e-12 * longest * longest) {
      std::ostringstream s;
      s << "triangle " << t << " (vertices " << tri[0] << ", " << tri[1] << ", " << tri[2]
        << ") has zero area (area " << 0.5 * twiceArea << ", longest edge " << longest << ")";
      fail(name, s.str());
    }
  }

  // Edges: exactly two uses, in opposite directions.
  const std::vector<HalfEdge> half = sortedHalfEdges(surface.triangles);
  forEachEdge(half, [&](size_t first, size_t last) {
    if (last - first == 1)
      fail(name, "not closed: " + edgeName(half[first]) + " of triangle " +
                     std::to_string(half[first].tri) +
                     " has no neighbouring triangle (boundary edge)");
    if (last - first > 2) {
      std::string tris;
      for (size_t u = first; u < last; ++u)
        tris += (tris.empty() ? "" : ", ") + std::to_string(half[u].tri);
      fail(name, "not 2-manifold: " + edgeName(half[first]) + " is shared by " +
                     std::to_string(last - first) + " triangles (" + tris + ")");
    }
  });
  SurfaceTopology topo = topologyFrom(surface.triangles, nv, half);

  // Connectivity and orientation: propagate a flip flag from triangle 0 over the edges; two
  // neighbours agree when they traverse their shared edge in opposite directions.
  auto sameDirection = [&](size_t first) { return half[first].forward == half[first + 1].forward; };
  std::vector<std::vector<std::pair<int, bool>>> nbrs(static_cast<size_t>(nt));
  forEachEdge(half, [&](size_t first, size_t) {
    const bool same = sameDirection(first);
    nbrs[size_t(half[first].tri)].push_back({half[first + 1].tri, same});
    nbrs[size_t(half[first + 1].tri)].push_back({half[first].tri, same});
  });
  std::vector<int> flip(size_t(nt), -1);
  std::vector<int> stack{0};
  flip[0] = 0;
  int visited = 1;
  bool orientable = true;
  int conflictA = -1, conflictB = -1;
  while (!stack.empty()) {
    const int t = stack.back();
    stack.pop_back();
    for (const auto& [n, same] : nbrs[size_t(t)]) {
      const int want = flip[size_t(t)] ^ (same ? 1 : 0);
      if (flip[size_t(n)] < 0) {
        flip[size_t(n)] = want;
        ++visited;
        stack.push_back(n);
      } else if (flip[size_t(n)] != want && orientable) {
        orientable = false;
        conflictA = t;
        conflictB = n;
      }
    }
  }
  if (visited < nt) {
    int first = 0;
    while (flip[size_t(first)] >= 0) ++first;
    int components = 1;
    std::vector<int> comp(flip.size());
    for (int t = 0; t < nt; ++t) comp[size_t(t)] = flip[size_t(t)] >= 0 ? 0 : -1;
    for (int t = 0; t < nt; ++t) {
      if (comp[size_t(t)] >= 0) continue;
      std::vector<int> st{t};
      comp[size_t(t)] = components;
      while (!st.empty()) {
        const int c = st.back();
        st.pop_back();
        for (const auto& nb : nbrs[size_t(c)])
          if (comp[size_t(nb.first)] < 0) {
            comp[size_t(nb.first)] = components;
            st.push_back(nb.first);
          }
      }
      ++components;
    }
    fail(name, "has " + std::to_string(components) + " connected components (triangle " +
                   std::to_string(first) + " is not connected to triangle 0)");
  }
  if (!orientable)
    fail(name, "not orientable: triangles " + std::to_string(conflictA) + " and " +
                   std::to_string(conflictB) + " cannot be oriented consistently");
  // Orientation: each edge must be traversed once in each direction. The minority orientation
  // is the flipped one.
  int flippedCount = 0;
  for (int t = 0; t < nt; ++t) flippedCount += flip[size_t(t)];
  const int minority = (2 * flippedCount <= nt) ? 1 : 0;
  std::vector<int> flipped;
  for (int t = 0; t < nt; ++t)
    if (flip[size_t(t)] == minority) flipped.push_back(t);
  if (!flipped.empty()) {
    // Name the first flipped triangle and one edge it shares in the same direction.
    const int t = flipped.front();
    std::string edgeText;
    forEachEdge(half, [&](size_t first, size_t) {
      if (edgeText.empty() && (half[first].tri == t || half[first + 1].tri == t) &&
          sameDirection(first))
        edgeText = edgeName(half[first]) + " is traversed in the same direction by triangles " +
                   std::to_string(half[first].tri) + " and " + std::to_string(half[first + 1].tri);
    });
    std::string list;
    for (size_t i = 0; i < flipped.size() && i < 8; ++i)
      list += (i ? ", " : "") + std::to_string(flipped[i]);
    if (flipped.size() > 8) list += ", ...";
    fail(name, "inconsistent orientation: triangle " + std::to_string(t) +
                   " is flipped relative to its neighbours (" + edgeText +
                   "); flipped triangles: " + list);
  }

  // Vertices: used (unless allowed), and their triangles form a single fan. Walking around v,
  // the next triangle after t is the one across t's edge that leaves v.
  for (int v = 0; v < nv; ++v) {
    const int incident = topo.vertexTriangles.size(v);
    if (incident == 0) {
      if (rules.allowUnusedVertices) continue;
      fail(name, "vertex " + std::to_string(v) + " " + vstr(surface.vertices[size_t(v)]) +
                     " is not used by any triangle");
    }
    const int start = *topo.vertexTriangles.begin(v);
    int t = start;
    int count = 0;
    do {
      const auto& tri = surface.triangles[size_t(t)];
      int k = 0;
      while (tri[size_t(k)] != v) ++k;
      t = topo.neighbours[size_t(t)][size_t(k)];  // across edge (v, next corner)
      ++count;
    } while (t != start && count <= incident);
    if (count != incident)
      fail(name, "not 2-manifold: vertex " + std::to_string(v) + " " +
                     vstr(surface.vertices[size_t(v)]) + " joins separate fans of triangles (" +
                     std::to_string(incident) + " incident triangles, " + std::to_string(count) +
                     " in one fan)");
  }

  // Outward orientation: positive signed volume (relative to the box centre for accuracy).
  const Vec3 centre = box.center();
  double volume = 0.0;
  for (const auto& tri : surface.triangles) {
    const Vec3 a = surface.vertices[size_t(tri[0])] - centre;
    const Vec3 b = surface.vertices[size_t(tri[1])] - centre;
    const Vec3 c = surface.vertices[size_t(tri[2])] - centre;
    volume += a.dot(b.cross(c)) / 6.0;
  }
  if (!(volume > 1e-12 * diag * diag * diag)) {
    std::ostringstream s;
    s << (volume < 0 ? "inverted: triangles face inward (signed volume " : "flat: signed volume ")
      << volume << " for a bounding-box diagonal of " << diag << ")";
    fail(name, s.str());
  }
  return topo;
}

Vec3f pseudoNormal(const std::vector<Triangle>& triangles, const SurfaceTopology& topology,
                   const float* x, const float* y, const float* z, int triangle,
                   TriangleFeature feature) {
  const Triangle& tri = triangles[size_t(triangle)];
  switch (feature) {
    case TriangleFeature::Face:
      return unitFaceNormal(tri, x, y, z);
    case TriangleFeature::Edge0:
    case TriangleFeature::Edge1:
    case TriangleFeature::Edge2: {
      const int k = int(feature) - int(TriangleFeature::Edge0);
      const int other = topology.neighbours[size_t(triangle)][size_t(k)];
      return unitFaceNormal(tri, x, y, z) + unitFaceNormal(triangles[size_t(other)], x, y, z);
    }
    default: {
      const int v = tri[size_t(int(feature) - int(TriangleFeature::Vertex0))];
      const Vec3f p = corner(x, y, z, v);
      Vec3f sum = Vec3f::Zero();
      for (const int* it = topology.vertexTriangles.begin(v); it != topology.vertexTriangles.end(v);
           ++it) {
        const Triangle& t = triangles[size_t(*it)];
        const int at = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        const Vec3f e1 = corner(x, y, z, t[size_t((at + 1) % 3)]) - p;
        const Vec3f e2 = corner(x, y, z, t[size_t((at + 2) % 3)]) - p;
        // Angle at the vertex, from atan2 so it stays accurate for needle triangles.
        const float angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
        sum += angle * unitFaceNormal(t, x, y, z);
      }
      return sum;
    }
  }
}

double meanEdgeLength(const std::vector<Triangle>& triangles, const std::vector<Vec3>& points) {
  if (triangles.empty()) return 0.0;
  double sum = 0.0;
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k)
      sum += (points[size_t(t[size_t(k)])] - points[size_t(t[size_t((k + 1) % 3)])]).norm();
  return sum / double(3 * triangles.size());
}

}  // namespace sb::mesh
