// Particles inside a cage: a body whose particles are only its cage's vertices is a hollow
// shell for clusters and contact; points on a lattice inside the cage give it volume. The render
// mesh still follows the cage vertices only (the interior points come after them).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

// Most interior points interiorLattice makes (about 1e6 · 12 bytes of positions).
inline constexpr long long kMaxInteriorPoints = 1000000;

// The points of the cubic lattice with edge `spacing` (the cage's units, > 0) that lie inside the
// closed, outward-oriented surface `cage` (generalised winding number > 1/2) and at least
// spacing / 2 from it, so none crowds a cage vertex. The lattice is centred on the cage's
// bounding box, so the result does not depend on where the box starts. Ordered x fastest, then
// y, then z. Throws std::invalid_argument when spacing is not positive and finite or the box
// would hold more than kMaxInteriorPoints lattice points.
std::vector<Eigen::Vector3d> interiorLattice(const mesh::TriangleMesh& cage, double spacing);

}  // namespace sb::cage
