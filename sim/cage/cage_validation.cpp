#include "sim/cage/cage_validation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <vector>

#include <Eigen/Geometry>

namespace sb::cage {

namespace {

using Vec3 = Eigen::Vector3d;

[[noreturn]] void fail(const std::string& name, const std::string& reason) {
  throw CageError("cage " + name + ": " + reason);
}

std::string vstr(const Vec3& v) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

struct EdgeUse {
  int tri;
  bool forward;  // traversed from the smaller to the larger vertex index
};

}  // namespace

void validateCage(const TriangleMesh& cage, const std::string& name) {
  const int nv = static_cast<int>(cage.vertices.size());
  const int nt = static_cast<int>(cage.triangles.size());
  if (nv < 4) fail(name, "a closed cage needs at least 4 vertices, got " + std::to_string(nv));
  if (nt < 4) fail(name, "a closed cage needs at least 4 triangles, got " + std::to_string(nt));

  for (int i = 0; i < nv; ++i) {
    if (!cage.vertices[i].allFinite())
      fail(name, "vertex " + std::to_string(i) + " has a non-finite coordinate " + vstr(cage.vertices[i]));
  }
  Eigen::AlignedBox3d box;
  for (const auto& v : cage.vertices) box.extend(v);
  const double diag = box.diagonal().norm();

  for (int t = 0; t < nt; ++t) {
    const auto& tri = cage.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] < 0 || tri[k] >= nv)
        fail(name, "triangle " + std::to_string(t) + " has vertex index " + std::to_string(tri[k]) +
                       " out of range [0, " + std::to_string(nv - 1) + "]");
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      fail(name, "triangle " + std::to_string(t) + " repeats a vertex (" + std::to_string(tri[0]) + ", " +
                     std::to_string(tri[1]) + ", " + std::to_string(tri[2]) + "): zero area");
  }
  for (int t = 0; t < nt; ++t) {
    const auto& tri = cage.triangles[t];
    const Vec3& a = cage.vertices[tri[0]];
    const Vec3& b = cage.vertices[tri[1]];
    const Vec3& c = cage.vertices[tri[2]];
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
  std::map<std::pair<int, int>, std::vector<EdgeUse>> edges;
  for (int t = 0; t < nt; ++t) {
    const auto& tri = cage.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({t, a < b});
    }
  }
  auto edgeName = [](const std::pair<int, int>& e) {
    return "edge " + std::to_string(e.first) + "-" + std::to_string(e.second);
  };
  for (const auto& [e, uses] : edges) {
    if (uses.size() == 1)
      fail(name, "not closed: " + edgeName(e) + " of triangle " + std::to_string(uses[0].tri) +
                     " has no neighbouring triangle (boundary edge)");
    if (uses.size() > 2) {
      std::string tris;
      for (const auto& u : uses) tris += (tris.empty() ? "" : ", ") + std::to_string(u.tri);
      fail(name, "not 2-manifold: " + edgeName(e) + " is shared by " + std::to_string(uses.size()) +
                     " triangles (" + tris + ")");
    }
  }

  // Connectivity and orientation: propagate a flip flag from triangle 0 over the edges.
  std::vector<std::vector<std::pair<int, bool>>> nbrs(nt);  // (neighbour, same direction)
  for (const auto& [e, uses] : edges) {
    const bool same = uses[0].forward == uses[1].forward;
    nbrs[uses[0].tri].push_back({uses[1].tri, same});
    nbrs[uses[1].tri].push_back({uses[0].tri, same});
  }
  std::vector<int> flip(nt, -1);
  std::vector<int> stack{0};
  flip[0] = 0;
  int visited = 1;
  bool orientable = true;
  int conflictA = -1, conflictB = -1;
  while (!stack.empty()) {
    const int t = stack.back();
    stack.pop_back();
    for (const auto& [n, same] : nbrs[t]) {
      const int want = flip[t] ^ (same ? 1 : 0);
      if (flip[n] < 0) {
        flip[n] = want;
        ++visited;
        stack.push_back(n);
      } else if (flip[n] != want && orientable) {
        orientable = false;
        conflictA = t;
        conflictB = n;
      }
    }
  }
  if (visited < nt) {
    int first = 0;
    while (flip[first] >= 0) ++first;
    int components = 1;
    std::vector<int> comp(flip.size());
    for (int t = 0; t < nt; ++t) comp[t] = flip[t] >= 0 ? 0 : -1;
    for (int t = 0; t < nt; ++t) {
      if (comp[t] >= 0) continue;
      std::vector<int> st{t};
      comp[t] = components;
      while (!st.empty()) {
        const int c = st.back();
        st.pop_back();
        for (const auto& nb : nbrs[c])
          if (comp[nb.first] < 0) {
            comp[nb.first] = components;
            st.push_back(nb.first);
          }
      }
      ++components;
    }
    fail(name, "has " + std::to_string(components) + " connected components (triangle " + std::to_string(first) +
                   " is not connected to triangle 0)");
  }
  // Orientation: each edge must be traversed once in each direction.
  std::vector<int> flipped;
  int flippedCount = 0;
  for (int t = 0; t < nt; ++t) flippedCount += flip[t];
  const int minority = (2 * flippedCount <= nt) ? 1 : 0;
  for (int t = 0; t < nt; ++t)
    if (flip[t] == minority) flipped.push_back(t);
  if (!orientable) {
    fail(name, "not orientable: triangles " + std::to_string(conflictA) + " and " + std::to_string(conflictB) +
                   " cannot be oriented consistently");
  }
  if (!flipped.empty()) {
    // Name the first flipped triangle and one edge it shares in the same direction.
    const int t = flipped.front();
    std::string edgeText;
    for (const auto& [e, uses] : edges) {
      if ((uses[0].tri == t || uses[1].tri == t) && uses[0].forward == uses[1].forward) {
        edgeText = edgeName(e) + " is traversed in the same direction by triangles " + std::to_string(uses[0].tri) +
                   " and " + std::to_string(uses[1].tri);
        break;
      }
    }
    std::string list;
    for (std::size_t i = 0; i < flipped.size() && i < 8; ++i) list += (i ? ", " : "") + std::to_string(flipped[i]);
    if (flipped.size() > 8) list += ", ...";
    fail(name, "inconsistent orientation: triangle " + std::to_string(t) + " is flipped relative to its neighbours (" +
                   edgeText + "); flipped triangles: " + list);
  }

  // Vertices: used, and their triangles form a single fan.
  std::vector<std::vector<int>> incident(nv);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) incident[cage.triangles[t][k]].push_back(t);
  // For a vertex v and triangle t containing it, the "next" triangle around v is the one across
  // the edge (v, next corner of t).
  for (int v = 0; v < nv; ++v) {
    if (incident[v].empty())
      fail(name, "vertex " + std::to_string(v) + " " + vstr(cage.vertices[v]) + " is not used by any triangle");
    const int start = incident[v][0];
    int t = start;
    std::size_t count = 0;
    do {
      const auto& tri = cage.triangles[t];
      int k = 0;
      while (tri[k] != v) ++k;
      const int other = tri[(k + 1) % 3];
      const auto& uses = edges[{std::min(v, other), std::max(v, other)}];
      t = uses[0].tri == t ? uses[1].tri : uses[0].tri;
      ++count;
    } while (t != start && count <= incident[v].size());
    if (count != incident[v].size())
      fail(name, "not 2-manifold: vertex " + std::to_string(v) + " " + vstr(cage.vertices[v]) +
                     " joins separate fans of triangles (" + std::to_string(incident[v].size()) +
                     " incident triangles, " + std::to_string(count) + " in one fan)");
  }

  // Outward orientation: positive signed volume (relative to the centroid for accuracy).
  const Vec3 centre = box.center();
  double volume = 0.0;
  for (const auto& tri : cage.triangles) {
    const Vec3 a = cage.vertices[tri[0]] - centre;
    const Vec3 b = cage.vertices[tri[1]] - centre;
    const Vec3 c = cage.vertices[tri[2]] - centre;
    volume += a.dot(b.cross(c)) / 6.0;
  }
  if (!(volume > 1e-12 * diag * diag * diag)) {
    std::ostringstream s;
    s << (volume < 0 ? "inverted: triangles face inward (signed volume " : "flat: signed volume ") << volume
      << " for a bounding-box diagonal of " << diag << ")";
    fail(name, s.str());
  }
}

}  // namespace sb::cage
