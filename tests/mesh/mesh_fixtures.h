// Generated cages for the cage tests and benchmarks.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh::testing {

using Vec3 = Eigen::Vector3d;

// Surface of the box [0,sx]×[0,sy]×[0,sz] with a×b×c segments: 2(ab+bc+ca)+2 vertices,
// each grid quad split along the diagonal (i,j)-(i+1,j+1). Outward oriented.
inline TriangleMesh makeBox(int a, int b, int c, Vec3 size = Vec3(1, 1, 1),
                            Vec3 origin = Vec3::Zero()) {
  TriangleMesh m;
  const int n[3] = {a, b, c};
  std::vector<int> index((a + 1) * (b + 1) * (c + 1), -1);
  auto id = [&](int i, int j, int k) -> int {
    int& slot = index[(i * (b + 1) + j) * (c + 1) + k];
    if (slot < 0) {
      slot = static_cast<int>(m.vertices.size());
      m.vertices.push_back(origin + Vec3(size.x() * i / a, size.y() * j / b, size.z() * k / c));
    }
    return slot;
  };
  // For each axis and side: a grid over the two other axes.
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      for (int i = 0; i < n[u]; ++i) {
        for (int j = 0; j < n[v]; ++j) {
          int q[4];
          const int corners[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int k = 0; k < 4; ++k) {
            int coord[3];
            coord[axis] = side ? n[axis] : 0;
            coord[u] = corners[k][0];
            coord[v] = corners[k][1];
            q[k] = id(coord[0], coord[1], coord[2]);
          }
          // (u, v, axis) is right-handed: u×v = +axis. Side 1 faces +axis: counter-clockwise in (u,
          // v).
          if (side == 1) {
            m.triangles.push_back({q[0], q[1], q[2]});
            m.triangles.push_back({q[0], q[2], q[3]});
          } else {
            m.triangles.push_back({q[0], q[2], q[1]});
            m.triangles.push_back({q[0], q[3], q[2]});
          }
        }
      }
    }
  }
  return m;
}

inline TriangleMesh makeIcosphere(int subdivisions, double radius = 1.0,
                                  Vec3 centre = Vec3::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::vector<std::array<int, 3>> nf;
    std::vector<std::pair<std::pair<int, int>, int>> cache;
    auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      for (const auto& c : cache)
        if (c.first == key) return c.second;
      v.push_back((v[a] + v[b]).normalized());
      cache.push_back({key, static_cast<int>(v.size()) - 1});
      return static_cast<int>(v.size()) - 1;
    };
    for (const auto& tr : f) {
      const int a = mid(tr[0], tr[1]), b = mid(tr[1], tr[2]), c = mid(tr[2], tr[0]);
      nf.push_back({tr[0], a, c});
      nf.push_back({tr[1], b, a});
      nf.push_back({tr[2], c, b});
      nf.push_back({a, b, c});
    }
    f = nf;
  }
  TriangleMesh m;
  for (const auto& p : v) m.vertices.push_back(centre + radius * p);
  m.triangles = f;
  return m;
}

// A prism over a simple polygon (counter-clockwise in xy) that is star-shaped with respect to
// `centre`, z in [0, height]; caps are fans around a centre vertex.
inline TriangleMesh makePrism(const std::vector<Eigen::Vector2d>& poly, Eigen::Vector2d centre,
                              double height) {
  TriangleMesh m;
  const int n = static_cast<int>(poly.size());
  for (int i = 0; i < n; ++i) m.vertices.emplace_back(poly[i].x(), poly[i].y(), 0.0);
  for (int i = 0; i < n; ++i) m.vertices.emplace_back(poly[i].x(), poly[i].y(), height);
  const int cb = 2 * n, ct = 2 * n + 1;
  m.vertices.emplace_back(centre.x(), centre.y(), 0.0);
  m.vertices.emplace_back(centre.x(), centre.y(), height);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    m.triangles.push_back({ct, n + i, n + j});
    m.triangles.push_back({cb, j, i});
    m.triangles.push_back({i, j, n + j});
    m.triangles.push_back({i, n + j, n + i});
  }
  return m;
}

// The L: [0,2]×[0,1] ∪ [0,1]×[0,2], height 1.
inline TriangleMesh makeLShape() {
  return makePrism({{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}, {0.5, 0.5}, 1.0);
}
inline bool insideLShape(const Vec3& p) {
  if (p.z() <= 0 || p.z() >= 1 || p.x() <= 0 || p.y() <= 0) return false;
  return (p.x() < 2 && p.y() < 1) || (p.x() < 1 && p.y() < 2);
}

// A 5-pointed star prism: radii 1 and 0.4, height 0.5.
inline TriangleMesh makeStar(int points = 5, double outer = 1.0, double inner = 0.4) {
  std::vector<Eigen::Vector2d> poly;
  for (int i = 0; i < 2 * points; ++i) {
    const double ang = M_PI * i / points + M_PI / 2;
    const double r = (i % 2) ? inner : outer;
    poly.emplace_back(r * std::cos(ang), r * std::sin(ang));
  }
  return makePrism(poly, {0, 0}, 0.5);
}

// Torus around z: major radius R, minor r, n × k quads.
inline TriangleMesh makeTorus(int n = 24, int k = 12, double R = 1.0, double r = 0.35) {
  TriangleMesh m;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    for (int j = 0; j < k; ++j) {
      const double b = 2 * M_PI * j / k;
      m.vertices.emplace_back((R + r * std::cos(b)) * std::cos(a),
                              (R + r * std::cos(b)) * std::sin(a), r * std::sin(b));
    }
  }
  auto id = [&](int i, int j) { return (i % n) * k + (j % k); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      const int p = id(i, j), q = id(i + 1, j), s = id(i + 1, j + 1), t = id(i, j + 1);
      // d/da × d/db points outward for this parametrisation when traversed
      // (i,j)->(i+1,j)->(i+1,j+1).
      m.triangles.push_back({p, q, s});
      m.triangles.push_back({p, s, t});
    }
  }
  return m;
}

inline double diagonal(const TriangleMesh& m) {
  Eigen::Vector3d lo = m.vertices[0], hi = m.vertices[0];
  for (const auto& v : m.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return (hi - lo).norm();
}

}  // namespace sb::mesh::testing
