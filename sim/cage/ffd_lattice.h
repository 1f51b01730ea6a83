// Free-form deformation (FFD) lattices: a box of space bound to a regular lattice of control
// nodes, with Bernstein (Sederberg–Parry, global) or uniform cubic B-spline (local) basis
// functions. bindFfd turns a point set into an Embedding (the same W · nodes deform as the mean
// value cage), ffdEvaluateDeBoor evaluates the map recursively per point, ffdDrag* move nodes so
// that a chosen point moves by a chosen displacement (minimum-norm), and ffdInjectivityBound /
// ffdJacobianCheck look for folds. Formulas and conventions: README.md, "FFD lattices".
//
// Conventions used by every function here:
//  * Node (i, j, k), 0 ≤ i < nodes[0], 0 ≤ j < nodes[1], 0 ≤ k < nodes[2], has the flat index
//    i + nodes[0] · (j + nodes[1] · k) (x fastest). Node positions are an FfdNodes array of
//    #nodes × 3 rows in that order (metres); the Embedding's columns are the same nodes.
//  * Points are given in the rest (undeformed) space and must lie in the closed lattice box
//    [origin, origin + size] (up to 1e-12 · size of rounding, clamped); a point's weights depend
//    only on its rest position, the deformed position is Σ_n w_n(x) · nodes_n.
//  * Bernstein: nodes per axis 2 ≤ N ≤ 32, degree N − 1 on that axis, rest node i at
//    origin + size · i / (N − 1) (nodes on the box, corners included).
//  * BSpline: uniform cubic B-spline with an open (unclamped) uniform knot vector; nodes per
//    axis N ≥ 4 give N − 3 knot spans that cover the box exactly, spacing h = size / (N − 3);
//    rest node i at origin + h · (i − 1), so the first and last node lie one spacing outside the
//    box. This placement (the Greville abscissae of the uniform knots) makes the rest lattice
//    reproduce the identity exactly, and every affine motion of the nodes the same affine map of
//    the points (linear precision). A point touches the 4 × 4 × 4 = 64 nodes of its span.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "sim/cage/embedding.h"

namespace sb::cage {

enum class FfdBasis { Bernstein, BSpline };

// Node positions, one row per node in flat index order (#nodes × 3, metres).
using FfdNodes = Eigen::Matrix<double, Eigen::Dynamic, 3>;

// The FFD box and its lattice. Plain data: validate() (called by every function taking a
// lattice) throws std::invalid_argument naming the problem.
struct FfdLattice {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // min corner of the box (m), finite
  Eigen::Vector3d size = Eigen::Vector3d::Ones();    // box edge lengths (m), finite, > 0
  std::array<int, 3> nodes = {4, 4, 4};  // nodes per axis: ≥ 2 (Bernstein), ≥ 4 (BSpline)
  FfdBasis basis = FfdBasis::BSpline;

  void validate() const;
  int nodeCount() const { return nodes[0] * nodes[1] * nodes[2]; }
  int nodeIndex(int i, int j, int k) const { return i + nodes[0] * (j + nodes[1] * k); }
  // Distance between neighbouring rest nodes per axis (m): size / (N − 1) for Bernstein,
  // size / (N − 3) for BSpline.
  Eigen::Vector3d spacing() const;
  // Rest position of node (i, j, k) (m); see the conventions above.
  Eigen::Vector3d restNode(int i, int j, int k) const;
  // All rest node positions (#nodes × 3): the lattice that maps every point to itself.
  FfdNodes restNodes() const;
  // The outer layer of nodes as a closed surface, outward-oriented: two triangles per boundary
  // cell face, indices into the nodes (a lattice body's surface for contact).
  std::vector<std::array<int, 3>> boundaryTriangles() const;
  // Lattice shape-matching regions (FastLSM, Rivers & James 2007): one region per node, the
  // nodes within halfWidth index steps of it on every axis (a (2w+1)³ block, cut at the
  // lattice's faces), as sorted node indices. Neighbouring regions overlap by all but one layer,
  // which is what holds a clustered body together. halfWidth ≥ 1 (std::invalid_argument).
  std::vector<std::vector<int>> regions(int halfWidth) const;
};

// A lattice whose box is the bounding box of the points grown by margin · (bounding box
// diagonal) on every side (margin ≥ 0, finite; a flat point set still gets a box of positive
// size when margin > 0). Throws std::invalid_argument for no points, a non-finite point, a
// negative or NaN margin, or a box of zero size on some axis (all points equal, or flat with
// margin 0); nodes and basis are checked as in FfdLattice::validate.
FfdLattice ffdLatticeAround(const std::vector<Eigen::Vector3d>& points, std::array<int, 3> nodes,
                            FfdBasis basis, double margin = 0.05);

// One-dimensional bases (exposed for tests and tools).
// Bernstein polynomials of degree n ≥ 0 at t ∈ [0, 1]: values[i] = C(n, i) tⁱ (1 − t)ⁿ⁻ⁱ,
// i = 0..n (n + 1 entries), by the stable triangle recurrence; derivatives[i] = d/dt of it when
// derivatives is not null.
void ffdBernsteinBasis(int degree, double t, double* values, double* derivatives = nullptr);
// The four nonzero uniform cubic B-splines on a knot span, t ∈ [0, 1]:
// (1 − t)³/6, (3t³ − 6t² + 4)/6, (−3t³ + 3t² + 3t + 1)/6, t³/6, and their derivatives d/dt.
void ffdCubicBSplineBasis(double t, double values[4], double derivatives[4] = nullptr);

// The nonzero weights of one point (node index, weight), ascending node index: 64 entries for a
// BSpline lattice (exact zeros at span borders are kept), every node for Bernstein. Computed
// from the precomputed per-axis bases (tensor products). Throws std::invalid_argument when the
// point is not finite or outside the box (the message gives the point and the box).
void ffdWeights(const FfdLattice& lattice, const Eigen::Vector3d& point,
                std::vector<std::pair<int, double>>& out);

struct FfdBindOptions {
  // Keep the double weights in the Embedding (rowWeights, deformDouble); float always.
  bool keepDoublePrecision = true;
  // Memory the weights may take at most (bytes, estimated before binding: 12 bytes per point ×
  // node for Bernstein, 16 bytes per point × 64 for BSpline); a larger bind is refused
  // (std::invalid_argument with the figure) instead of exhausting memory.
  std::uint64_t maxWeightBytes = std::uint64_t(4) << 30;
};

// The weights of every point as an Embedding (#points × #nodes): sparse for BSpline (≤ 64
// nonzeros per row; exact zeros dropped), dense for Bernstein. Embedding::deform(nodes) then
// gives the deformed points. stats(): seconds, nonZeros, min/max weight, maxSumError and
// maxLinearError (rest lattice, relative to the box diagonal). Throws std::invalid_argument
// for a bad lattice or a point outside the box ("point 17 (x, y, z) is outside ...").
Embedding bindFfd(const std::vector<Eigen::Vector3d>& points, const FfdLattice& lattice,
                  const FfdBindOptions& options = {});

// The deformed position of one rest-space point by the recursive algorithm: de Boor's
// algorithm for BSpline (on the 4 nodes of the span, along x for each of the 16 (y, z) rows,
// then along y, then z), de Casteljau's (its Bézier case) for Bernstein. Validates the lattice,
// the node array (#nodes × 3, finite) and the point on every call.
Eigen::Vector3d ffdEvaluateDeBoor(const FfdLattice& lattice, const FfdNodes& nodes,
                                  const Eigen::Vector3d& point);
// The same for many points (checks once): out[i] = ffdEvaluateDeBoor(points[i]) (#points × 3).
void ffdDeformDeBoor(const FfdLattice& lattice, const FfdNodes& nodes,
                     const std::vector<Eigen::Vector3d>& points,
                     Eigen::Matrix<double, Eigen::Dynamic, 3>& out);

// ∂(deformed position)/∂(rest position) at a rest-space point, from the analytic derivatives
// of the basis (row r = component r of the image, column c = ∂/∂x_c). Identity on the rest
// lattice.
Eigen::Matrix3d ffdJacobian(const FfdLattice& lattice, const FfdNodes& nodes,
                            const Eigen::Vector3d& point);

// Direct manipulation. Moves the nodes so that the rest-space point moves by displacement (m):
// ΔP_n = w_n ΔQ / Σ_k w_k², the minimum-norm (in Σ_n |ΔP_n|²) node change with
// Σ_n w_n ΔP_n = ΔQ. Only the point's nonzero-weight nodes move. Returns ΔP (#nodes × 3).
FfdNodes ffdDragPoint(const FfdLattice& lattice, FfdNodes& nodes, const Eigen::Vector3d& point,
                      const Eigen::Vector3d& displacement);

struct FfdDragReport {
  FfdNodes delta;            // ΔP applied to the nodes (#nodes × 3)
  int rank = 0;              // rank of the points' weight matrix (≤ #points)
  double maxResidual = 0.0;  // max_p |Σ_n w_pn ΔP_n − ΔQ_p| (m); ~1e-16 unless rank-deficient
};
// Several points at once: ΔP = B⁺ ΔQ, the minimum-norm solution of B ΔP = ΔQ (B = the points'
// weight rows, #points × #touched nodes; complete orthogonal decomposition, so coincident or
// dependent points give the least-squares, minimum-norm answer and a residual). points and
// displacements have the same length.
FfdDragReport ffdDragPoints(const FfdLattice& lattice, FfdNodes& nodes,
                            const std::vector<Eigen::Vector3d>& points,
                            const std::vector<Eigen::Vector3d>& displacements);

// Sufficient condition for injectivity of a uniform cubic B-spline map (Choi & Lee 2000, after
// Goodman & Unsworth): with each axis scaled to unit spacing, every control-point displacement
// component below 1/K: K₂ ≈ 2.046 (0.48) for a 2D map, K₃ ≈ 2.48 (0.40) for a 3D one. The
// thesis quotes the 2D figure, 0.48; the lattice here is 3D, so the default is 0.40 (and 0.48
// is not enough in 3D: test_ffd builds a lattice displaced by 0.47 spacings with det J < 0).
inline constexpr double kFfdInjectivityBound2D = 0.48;
inline constexpr double kFfdInjectivityBound3D = 0.40;

struct FfdInjectivityReport {
  bool applicable = false;  // BSpline only (no such bound is used for Bernstein lattices)
  Eigen::Vector3d maxDisplacementRatio = Eigen::Vector3d::Zero();  // max_n |ΔP_n,a| / h_a
  double bound = kFfdInjectivityBound3D;
  bool guaranteedInjective = false;  // applicable and every ratio < bound
};
FfdInjectivityReport ffdInjectivityBound(const FfdLattice& lattice, const FfdNodes& nodes,
                                         double bound = kFfdInjectivityBound3D);

struct FfdJacobianReport {
  double minDeterminant = 0.0;
  Eigen::Vector3d argMin = Eigen::Vector3d::Zero();  // sample with the smallest determinant
  std::int64_t nonPositiveCount = 0;                 // samples with det J ≤ 0 (folded)
  std::int64_t samples = 0;
};
// det J at each rest-space sample point (each in the box). A fold shows as det ≤ 0; det > 0 at
// the samples proves nothing between them. No samples: minDeterminant 0, counts 0.
FfdJacobianReport ffdJacobianCheck(const FfdLattice& lattice, const FfdNodes& nodes,
                                   const std::vector<Eigen::Vector3d>& samples);

}  // namespace sb::cage
