// Harmonic coordinates (Joshi et al. 2007, "Harmonic coordinates for character articulation"; the
// weights of Blender's Mesh Deform): for each cage vertex j the function w_j that is harmonic
// (Δw_j = 0) inside the cage and equals the piecewise-linear hat function of vertex j on the
// cage's surface. Unlike mean value coordinates they are non-negative and follow the interior of
// a non-convex cage: a vertex has (almost) no influence across a gap of the cage.
//
// Solved numerically on a regular grid (method, boundary handling and accuracy in README.md):
// the result converges to the true coordinates like O(cell size).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "sim/cage/embedding.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

// Order in which the sparse LDLᵀ factorisation eliminates the grid's unknowns.
// Measured on the bunny cage (README.md): AMD was as fast or faster in 5 of 6 configurations.
enum class HarmonicOrdering {
  Amd,               // Eigen's approximate minimum degree (default)
  NestedDissection,  // geometric nested dissection of the grid (mid-planes of the box)
};

// How the Laplace system is solved (README.md, "Harmonic coordinates": cost table).
enum class HarmonicSolver {
  // Direct up to resolution 32 (faster there: 0.3 s against 0.6 s for the bunny cage),
  // MultigridCg above (4.6 s against 36–48 s at resolution 64).
  Auto,
  // Eigen's SimplicialLDLT of the whole system, one solve per cage vertex. Cost ~ resolution⁶.
  Direct,
  // Conjugate gradients per cage vertex, preconditioned by a multigrid V-cycle: symmetric
  // Gauss-Seidel on each grid, trilinear interpolation between grids of doubling spacing,
  // Galerkin coarse systems, an exact solve (SimplicialLDLT) on the coarsest (≤ 2000 unknowns).
  // Stops at a relative residual of cgTolerance; its weights differ from Direct's by about that
  // much. Cost ~ resolution³.
  MultigridCg,
};

// How the cage's boundary values enter the grid (README.md, "Harmonic coordinates").
enum class HarmonicBoundary {
  // Every inside node is an unknown; a stencil arm that leaves the cage ends at the crossing
  // point, with the exact hat values there (linear ghost value, Gibou et al. 2002). Linear
  // precision exact at the nodes, weights converge like O(h²).
  CutCell,
  // Nodes within one cell of the cage are fixed to the hat values of their closest cage point
  // (Joshi et al.'s voxelised boundary). Weights and linear precision converge like O(h).
  ClosestPoint,
};

struct HarmonicOptions {
  // Grid cells along the longest axis of the cage's bounding box (cubic cells), ≥ 4. The bind's
  // error (linear precision, distance to the exact coordinates) is about one cell (CutCell: far
  // less inside, README.md). 32 by default: a 164-vertex cage binds in ~0.5 s there; above 32
  // HarmonicSolver::Auto switches to multigrid CG, ~5 s at 64 (the direct solve: ~40 s).
  int resolution = 32;
  // Threads for the solve and the lookup, at most threadCount() (0 = threadCount();
  // sim/base/parallel.h). The weights do not depend on it.
  int threads = 0;
  // Memory the bind may take at most (bytes, estimated before anything is allocated: the grid,
  // the right-hand sides and solutions of the interior nodes for every cage vertex, the
  // factor, and the dense weights). A bind that would exceed it is refused with the figure
  // (std::runtime_error).
  std::uint64_t maxBytes = std::uint64_t(4) << 30;
  HarmonicBoundary boundary = HarmonicBoundary::CutCell;
  HarmonicOrdering ordering = HarmonicOrdering::Amd;
  HarmonicSolver solver = HarmonicSolver::Auto;
  // MultigridCg: stop at |r| ≤ cgTolerance·|b| per cage vertex. 1e-12 kept the bunny cage's
  // weights within 4e-11 of Direct's at resolutions 24 and 32, 1.2e-10 at 64 (README.md).
  double cgTolerance = 1e-12;
  bool keepDoublePrecision = true;  // keep the double weights in the Embedding (deformDouble)
};

// Figures of a harmonic bind (the common ones are also in the Embedding's BindStats).
struct HarmonicReport {
  std::array<int, 3> gridNodes{};  // nodes along x, y, z (cells + 1 + 2 margin cells)
  double cellSize = 0.0;           // grid spacing h (the cage's units)
  // Unknowns of the Laplace system: the inside nodes (ClosestPoint: farther than h from the cage).
  std::int64_t interiorNodes = 0;
  std::int64_t boundaryNodes = 0;  // other nodes given boundary values (within √3·h of the cage)
  std::int64_t cutArms = 0;        // CutCell: stencil arms ending at a cage crossing
  std::int64_t factorNonZeros = 0;  // non-zeros of the LDLᵀ factor L (MultigridCg: coarse grid's)
  int maxCgIterations = 0;          // MultigridCg: most iterations any cage vertex took
  double classifySeconds = 0.0;     // distances and inside/outside of the nodes
  double factorSeconds = 0.0;  // assembly + sparse LDLᵀ factorisation (MultigridCg: the levels)
  double solveSeconds = 0.0;   // the solves for all cage vertices
  double lookupSeconds = 0.0;  // trilinear lookup of the points
  double totalSeconds = 0.0;
  // Points whose grid cell lacks values at some corner (outside the cage, more than a cell
  // away, or beyond the grid): given the hat functions of their closest cage point.
  std::int64_t closestPointPoints = 0;
  double maxSumError = 0.0;     // max_i |Σ_j w_ij − 1|
  double minWeight = 0.0;       // min_ij w_ij (≥ 0 up to solver round-off)
  double maxLinearError = 0.0;  // max_i |Σ_j w_ij v_j − x_i| / cage diagonal
};

// Validates the cage (closed, 2-manifold, outward: throws mesh::SurfaceError naming the
// problem), the points (finite: std::invalid_argument naming the point) and the options
// (resolution: std::invalid_argument; memory: std::runtime_error with the estimate), then
// returns the dense embedding W (#points × #cage vertices, rows summing to 1) of harmonic
// coordinates. Points inside the cage get the trilinear interpolation of the grid solution;
// points outside it are described in README.md ("Harmonic coordinates"). Nothing is returned
// half-built: every check happens before the work.
Embedding bindHarmonic(const std::vector<Eigen::Vector3d>& points, const mesh::TriangleMesh& cage,
                       const HarmonicOptions& options = {}, HarmonicReport* report = nullptr);

}  // namespace sb::cage
