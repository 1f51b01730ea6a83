// Automatic cages: a coarse, closed, 2-manifold, outward-oriented, self-intersection-free cage
// that strictly encloses any input mesh (several components, open borders, triangle soups,
// self-intersecting or thin input alike), for binding with mean value coordinates.
//
// How (one concept per file):
//   auto_cage_voxels.cpp   the mesh is voxelised with a small offset; the exterior is flood-filled
//                          from the grid border, everything it does not reach is solid (so holes,
//                          soups and thin parts are closed and enclosed, never cut); components
//                          are bridged, non-manifold voxel configurations closed, and the
//                          solid's boundary extracted as triangles;
//   auto_cage_decimate.cpp constrained quadric edge-collapse decimation down to the budget, each
//                          collapse vetoed unless every guard point (input vertices and samples on
//                          the input triangles) stays inside at a positive distance, no triangles
//                          intersect, the surface stays manifold and no triangle flips;
//   auto_cage.cpp          input checks, the final independent checks (closed surface, no
//                          self-intersection, enclosure of every guard point by winding number)
//                          and the report.
// Deterministic: the same input and options give the same cage bit for bit, for any thread count.
#pragma once

#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

struct CageOptions {
  // Most cage vertices (≥ 4). When the budget cannot be reached even from the coarsest voxels
  // (8 along the longest side) — a budget of a few vertices (suzanne stops at 11 for a budget of
  // 4), or a shape of higher genus — the cage has more: compare CageReport::vertices.
  int vertexBudget = 250;
  // In [0, 1]: the voxel resolution of the first, fine enclosing surface, from 24 voxels along the
  // longest side of the bounding box (0: fast, loose) to 128 (1: tight, slower); 0.2 gives 45.
  // The cage's offset from the mesh scales with the voxel size, but at a few hundred vertices
  // the decimation dominates the distance: the bunny at 250 vertices, 235k triangles, is 3.09 %
  // of the diagonal in 1.8 s at 0.2 and 3.15 % in 5.2 s at 0.5. Finer voxels pay for larger
  // budgets.
  double tightness = 0.2;
  // Threads for the final checks (0 = threadCount(), sim/base/parallel.h; never more).
  int threads = 0;
};

struct CageReport {
  int vertices = 0, triangles = 0;  // of the cage
  int voxelResolution = 0;          // voxels along the longest side of the bounding box
  int fineVertices = 0;             // vertices of the voxel surface before decimation
  double diagonal = 0.0;            // bounding-box diagonal of the input (its units)
  double hausdorff = 0.0;           // one-sided Hausdorff distance cage → mesh (input units)
  double hausdorffRelative = 0.0;   // hausdorff / diagonal
  double minClearance = 0.0;        // smallest distance from a guard point to the cage (> 0)
  int guardPoints = 0;              // input vertices + samples on the input triangles
  double seconds = 0.0;             // wall time of makeCage
};

struct CageResult {
  mesh::TriangleMesh cage;
  CageReport report;
};

// Builds the cage of `mesh` (vertices in any unit; triangles may be empty: then the vertices are
// enclosed). Throws std::invalid_argument naming the field and the reason for: no vertices,
// non-finite coordinates, a triangle index out of range, vertexBudget < 4, tightness outside
// [0, 1] or not finite, threads < 0, a mesh whose guard samples would exceed 5·10⁷ points (many
// triangles much larger than the voxels). Throws std::runtime_error if a final check fails (a bug,
// never expected).
CageResult makeCage(const mesh::TriangleMesh& mesh, const CageOptions& options = {});

}  // namespace sb::cage
