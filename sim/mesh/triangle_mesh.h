// A plain indexed triangle mesh in double precision: the exchange type of the cage module.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

namespace sb::mesh {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
  // Which file polygon each triangle came from: empty (every triangle is its own face, the
  // usual case) or one id per triangle. The readers fan-triangulate a polygon with corners
  // c0 … c(k−1) into the consecutive triangles (c0, cj, cj+1), j = 1 … k−2, all with the same
  // id, so the polygon can be rebuilt (polygonFaces). Everything that works on triangles
  // ignores it; polygon mean value coordinates (sim/cage/polygon_mvc.h) use it. Code that
  // edits `triangles` must clear or update it.
  std::vector<int> polygonOf{};
};

// The faces of a mesh as corner lists (counter-clockwise from outside): the polygons recorded
// in polygonOf, or one triangle per face when polygonOf is empty. Throws std::invalid_argument
// if polygonOf does not match the triangles (wrong size, or a polygon's triangles not a
// consecutive fan from its first corner).
std::vector<std::vector<int>> polygonFaces(const TriangleMesh& mesh);

// True if some face of the mesh has more than three corners.
bool hasPolygonFaces(const TriangleMesh& mesh);

}  // namespace sb::mesh
