// Geometry of closed triangle surfaces for body–body contact: closest points on triangles and
// which side of a surface a point is on. Stateless kernels (tested in tests/sim/test_contact.cpp).
#pragma once

#include <array>
#include <vector>

#include "sim/types.h"

namespace sb {

using Triangle = std::array<int, 3>;  // particle indices, counter-clockwise seen from outside

// Where on a triangle (a, b, c) the closest point lies. Edge k joins corners k and (k+1) mod 3.
enum class TriangleFeature : unsigned char { Face, Edge0, Edge1, Edge2, Vertex0, Vertex1, Vertex2 };

struct TrianglePoint {
  Vec3f weights;  // barycentric weights of a, b, c (each in [0, 1], summing to 1)
  TriangleFeature feature;
};

// Closest point of the triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
// A degenerate triangle (zero area) yields one of its vertices or edges, never NaN.
TrianglePoint closestPointOnTriangle(const Vec3f& p, const Vec3f& a, const Vec3f& b,
                                     const Vec3f& c);

// Mean edge length of the surface (metres): the "particle spacing" of a cage.
double meanEdgeLength(const std::vector<Triangle>& triangles, const std::vector<Vec3>& points);

// Adjacency of a closed surface that the side test needs; built once per body.
struct SurfaceTopology {
  // For each triangle, the triangle across each of its edges (edge k joins corners k and k+1).
  std::vector<Triangle> neighbours;
  // CSR: the triangles around point i are vertexTriangles[vertexStart[i] .. vertexStart[i+1]).
  std::vector<int> vertexStart, vertexTriangles;
};

// Requires a closed 2-manifold surface (every edge shared by exactly two triangles); the World
// validates that first. pointCount: number of points the indices refer to.
SurfaceTopology buildSurfaceTopology(const std::vector<Triangle>& triangles, int pointCount);

// The pseudo-normal at a closest point (Bærentzen & Aanæs 2005), from the current positions
// (#P×3 columns x, y, z): the face normal inside a face, the sum of the two unit face normals on
// an edge, the angle-weighted sum of the unit face normals around a vertex. For a closed
// surface, (p − closest point) · pseudo-normal < 0 exactly when p is inside. Computed only for
// the closest feature, so no per-step pass over the whole surface is needed.
Vec3f pseudoNormal(const std::vector<Triangle>& triangles, const SurfaceTopology& topology,
                   const float* x, const float* y, const float* z, int triangle,
                   TriangleFeature feature);

}  // namespace sb
