#include "sim/surface_geometry.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace sb {

TrianglePoint closestPointOnTriangle(const Vec3f& p, const Vec3f& a, const Vec3f& b,
                                     const Vec3f& c) {
  const Vec3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return {Vec3f(1, 0, 0), TriangleFeature::Vertex0};
  const Vec3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return {Vec3f(0, 1, 0), TriangleFeature::Vertex1};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float t = d1 / (d1 - d3);  // d1 − d3 > 0 here
    return {Vec3f(1 - t, t, 0), TriangleFeature::Edge0};
  }
  const Vec3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return {Vec3f(0, 0, 1), TriangleFeature::Vertex2};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float t = d2 / (d2 - d6);
    return {Vec3f(1 - t, 0, t), TriangleFeature::Edge2};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f) {
    const float t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {Vec3f(0, 1 - t, t), TriangleFeature::Edge1};
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) return {Vec3f(1, 0, 0), TriangleFeature::Vertex0};  // collapsed triangle
  const float v = vb / sum, w = vc / sum;
  return {Vec3f(1 - v - w, v, w), TriangleFeature::Face};
}

namespace {

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

SurfaceTopology buildSurfaceTopology(const std::vector<Triangle>& triangles, int pointCount) {
  SurfaceTopology topo;
  // Directed edge (from, to) → triangle; the neighbour across (a, b) owns (b, a).
  std::map<std::pair<int, int>, int> owner;
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      owner[{triangles[t][size_t(k)], triangles[t][size_t((k + 1) % 3)]}] = int(t);
  topo.neighbours.assign(triangles.size(), Triangle{-1, -1, -1});
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto it = owner.find({triangles[t][size_t((k + 1) % 3)], triangles[t][size_t(k)]});
      if (it != owner.end()) topo.neighbours[t][size_t(k)] = it->second;
    }
  topo.vertexStart.assign(size_t(pointCount) + 1, 0);
  for (const Triangle& t : triangles)
    for (int i : t) ++topo.vertexStart[size_t(i) + 1];
  for (size_t i = 1; i < topo.vertexStart.size(); ++i)
    topo.vertexStart[i] += topo.vertexStart[i - 1];
  topo.vertexTriangles.resize(size_t(topo.vertexStart.back()));
  std::vector<int> fill(topo.vertexStart.begin(), topo.vertexStart.end() - 1);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int i : triangles[t]) topo.vertexTriangles[size_t(fill[size_t(i)]++)] = int(t);
  return topo;
}

double meanEdgeLength(const std::vector<Triangle>& triangles, const std::vector<Vec3>& points) {
  if (triangles.empty()) return 0.0;
  double sum = 0.0;
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k)
      sum += (points[size_t(t[size_t(k)])] - points[size_t(t[size_t((k + 1) % 3)])]).norm();
  return sum / double(3 * triangles.size());
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
      for (int k = topology.vertexStart[size_t(v)]; k < topology.vertexStart[size_t(v) + 1]; ++k) {
        const Triangle& t = triangles[size_t(topology.vertexTriangles[size_t(k)])];
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

}  // namespace sb
