#pragma once

#include <array>
#include <vector>

#include "sim/base/types.h"

namespace sb::mesh {

// Area-weighted vertex normals (sum of the incident triangles' cross products), unit length.
// Vertices used by no triangle (or whose triangles cancel out) get a zero normal.
// normals is resized to positions.rows().
void computeVertexNormals(const std::vector<std::array<int, 3>>& triangles,
                          const PointsRowMajor& positions, PointsRowMajor& normals);

}  // namespace sb::mesh
