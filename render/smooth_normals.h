// Per-vertex normals for smooth shading: the area-weighted sum of the incident triangles'
// normals, normalised. Plain arrays: positions #V×3 row-major floats, triangles #T×3 ints.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sb::render {

// Writes #V×3 floats to normals. Vertices without a (non-degenerate) triangle get (0, 1, 0).
void computeSmoothNormals(const float* positions, std::size_t vertexCount,
                          const std::int32_t* triangles, std::size_t triangleCount,
                          float* normals);

}  // namespace sb::render
