// The order in which a mesh's triangles are sent to the GPU. A renderer shades a vertex again
// once it has dropped out of a small cache of recently shaded vertices (llvmpipe: per batch of
// indices, a small table of recent ones). Meshes from files often come back to a vertex long
// after its first triangle: the Stanford bunny in its file's order shades each vertex about three
// times. Sending neighbouring triangles one after another brings that near the ideal of once.
// Only the order of whole triangles changes: the vertices, their numbering and each triangle's
// winding stay, so nothing but the drawing speed can tell the difference.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sb::render {

// `indices`: #T×3 vertex indices, row-major, each ≥ 0. Returns the same #T triangles (each with
// its three indices in the same cyclic order, so facing is kept) in an order that reuses recent
// vertices: Forsyth's "linear-speed vertex cache optimisation" (2006), a greedy choice of the next
// triangle by the cache positions and remaining triangle counts of its vertices, with a 32-entry
// least-recently-used cache as the model. Time O(#T) (a bounded amount of work per triangle).
std::vector<std::int32_t> cacheFriendlyTriangleOrder(const std::int32_t* indices,
                                                     std::size_t triangleCount);

}  // namespace sb::render
