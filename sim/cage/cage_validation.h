// Cage validation: a cage must be a closed, 2-manifold, connected, consistently and outward
// oriented triangle surface with no zero-area triangles before anything is bound to it.
#pragma once

#include <stdexcept>
#include <string>

#include "sim/cage/triangle_mesh.h"

namespace sb::cage {

// what() = "cage NAME: REASON" naming the offending triangle / edge / vertex.
class CageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Checks, in this order: at least 4 vertices and 4 triangles; finite coordinates; indices in
// range; no repeated index in a triangle; no zero-area triangle (2·area ≤ 1e-12 · longest
// edge², or longest edge ≤ 1e-12 · cage diagonal); every edge shared by exactly two triangles
// (open / non-manifold edge); traversed in opposite directions by them (a flipped triangle is
// named: the minority orientation); every vertex used and its triangles forming one fan
// (non-manifold vertex); one connected component; positive signed volume (outward).
// Throws CageError on the first failure.
void validateCage(const TriangleMesh& cage, const std::string& name);

}  // namespace sb::cage
