// Closed triangle surfaces: the adjacency (topology) every user of a cage or body surface needs,
// built once, and the validation that a surface is closed, 2-manifold and outward-oriented.
// Users: cage binding (mean value coordinates, sim/cage), body–body contact (inside/outside by
// pseudo-normals, sim/world/contact), the viewer (cage edges).
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/base/csr.h"
#include "sim/base/types.h"
#include "sim/mesh/closest_point.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh {

using Triangle = std::array<int, 3>;  // vertex indices, counter-clockwise seen from outside

// Adjacency of a triangle surface with V vertices and T triangles. Edge k of a triangle joins
// its corners k and (k+1) mod 3.
struct SurfaceTopology {
  std::vector<std::array<int, 2>> edges;  // #E undirected edges (a, b), a < b, in first-use order
  std::vector<std::array<int, 3>> triangleEdges;  // #T: index into `edges` of edge k
  // #T: the triangle across edge k, -1 on a border; where more than two triangles share an edge
  // (not a closed surface) one of them.
  std::vector<std::array<int, 3>> neighbours;
  Csr vertexTriangles;  // #V rows: the triangles around each vertex, ascending
};

// Builds the adjacency of any triangle list whose indices are in [0, vertexCount). No checks
// beyond that; validateClosedSurface is the checked way in.
SurfaceTopology buildSurfaceTopology(const std::vector<Triangle>& triangles, int vertexCount);

// what() = "NAME: REASON", naming the offending triangle / edge / vertex.
class SurfaceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SurfaceRules {
  // Vertices that no triangle uses are accepted (interior particles of a body); otherwise each
  // one is an error.
  bool allowUnusedVertices = false;
};

// Checks, in this order: at least 4 vertices and 4 triangles; finite coordinates; indices in
// range; no repeated index in a triangle; no zero-area triangle (2·area ≤ 1e-12 · longest
// edge², or longest edge ≤ 1e-12 · surface diagonal); every edge shared by exactly two triangles
// (open / non-manifold edge); traversed in opposite directions by them (a flipped triangle is
// named: the minority orientation); every vertex used (unless allowed) and its triangles forming
// one fan (non-manifold vertex); one connected component; positive signed volume (outward).
// Throws SurfaceError on the first failure; returns the topology it built on success.
SurfaceTopology validateClosedSurface(const TriangleMesh& surface, const std::string& name,
                                      const SurfaceRules& rules = {});

// The pseudo-normal at a closest point (Bærentzen & Aanæs 2005), from the current positions
// (#V×3 columns x, y, z): the face normal inside a face, the sum of the two unit face normals on
// an edge, the angle-weighted sum of the unit face normals around a vertex. For a closed
// surface, (p − closest point) · pseudo-normal < 0 exactly when p is inside. Computed only for
// the closest feature, so no per-step pass over the whole surface is needed.
Vec3f pseudoNormal(const std::vector<Triangle>& triangles, const SurfaceTopology& topology,
                   const float* x, const float* y, const float* z, int triangle,
                   TriangleFeature feature);

// Mean edge length of the triangles (metres; each shared edge counted once per triangle): the
// "particle spacing" of a cage. 0 for no triangles.
double meanEdgeLength(const std::vector<Triangle>& triangles, const std::vector<Vec3>& points);

}  // namespace sb::mesh
