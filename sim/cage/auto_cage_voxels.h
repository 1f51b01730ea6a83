// The first, fine enclosing surface of the automatic cage (internal to sim/cage): the boundary of
// a voxel solid that contains the input mesh with a margin. See auto_cage.h for the whole path.
#pragma once

#include <array>
#include <vector>

#include "sim/cage/auto_cage_geometry.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage::detail {

// Voxels are the unit cubes [i, i+1] × [j, j+1] × [k, k+1] of a grid of `cells` voxels (voxel
// frame). A voxel is occupied when its centre lies within `radius` voxels of a triangle or a
// vertex of the input; with radius = √3/2 + m every point within m of the input lies in an
// occupied voxel. The solid is everything the exterior (6-connected, flood-filled from the grid
// border, which must stay empty) does not reach, so holes, open borders, soups and thin parts are
// closed, never cut. Separate pieces are joined by bridges of voxels along shortest paths, and
// every grid corner whose 8 voxels would make the surface non-manifold (solid or exterior not
// face-connected there) has its 8 voxels made solid; the solid only grows. Returns the solid's
// boundary: a closed, connected, 2-manifold, outward-oriented surface with integer corners.
mesh::TriangleMesh voxelSurface(const std::vector<Vec>& vertices, const std::vector<Tri>& triangles,
                                const std::array<int, 3>& cells, double radius);

}  // namespace sb::cage::detail
