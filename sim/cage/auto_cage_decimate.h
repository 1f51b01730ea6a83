// Constrained decimation of the automatic cage (internal to sim/cage). See auto_cage.h.
#pragma once

#include "sim/cage/auto_cage_geometry.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage::detail {

// Collapses edges of `cage` (closed, 2-manifold, outward-oriented, free of self-intersections,
// enclosing every guard point at ≥ clearance; voxel frame) in order of quadric error (Garland &
// Heckbert; ties on flat parts go to the shorter edge) until it has at most `budget` vertices or no
// collapse passes. A collapse to the quadric-optimal position, else the midpoint, else an endpoint,
// is made only when
//  (a) every guard point stays inside, at ≥ clearance from the new triangles: only the collapsed
//      one-ring changes, so a point's winding number changes by (Σ solid angles of the new fan −
//      Σ of the old fan) / 4π, which must be 0 for each guard point near the one-ring;
//  (b) no new triangle intersects another cage triangle;
//  (c) the link condition holds (the surface stays 2-manifold);
//  (d) no new triangle flips against its old self or is a sliver;
//  (e) samples on the new triangles lie within maxDeviation of a guard point (a bound on the
//      Hausdorff distance cage → mesh; relaxed ×1.5 whenever a whole pass makes no collapse,
//      dropped after 12 relaxations).
// So the result keeps the invariants (a)–(d). Deterministic.
void decimateCage(mesh::TriangleMesh& cage, const GuardSet& guards, int budget, double clearance,
                  double maxDeviation);

}  // namespace sb::cage::detail
