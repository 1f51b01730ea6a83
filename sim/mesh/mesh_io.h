// Mesh files <-> TriangleMesh. Reading goes through OpenMesh's readers (OBJ, OFF, PLY, STL),
// faces with more than three corners are fan-triangulated, and STL's per-facet vertices are
// merged (exactly equal positions) so that a closed surface comes back closed. Files with
// vertices only are accepted (triangles empty).
#pragma once

#include <stdexcept>
#include <string>

#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh {

// what() = "PATH: reason" (with "line N" where it is known).
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

TriangleMesh readMesh(const std::string& path);

// Writes "v x y z" (17 significant digits, exact round trip) and "f a b c" (1-based) lines.
// Atomic (sim/base/file_io.h): PATH is replaced whole or not at all.
void writeObj(const std::string& path, const TriangleMesh& mesh);

}  // namespace sb::mesh
