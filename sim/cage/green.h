// Green coordinates (Lipman, Levin, Cohen-Or, "Green Coordinates", SIGGRAPH 2008) of points
// inside a closed, outward-oriented triangle cage, as an Embedding over extended controls.
//
// For a point η inside the cage (V vertices v_i, F triangles t_j with unit outward normals n_j),
// Green's third identity applied to the linear function x ↦ x gives
//   η = Σ_i φ_i(η) v_i + Σ_j ψ_j(η) n_j,
//   φ_i(η) = ∫_{star of v_i} Γ_i(ξ) ∂G/∂n(ξ, η) dσ = (1/4π) Σ_{t ∋ v_i} ∫_t Γ_i (ξ−η)·n / |ξ−η|³,
//   ψ_j(η) = −∫_{t_j} G(ξ, η) dσ = (1/4π) ∫_{t_j} 1 / |ξ−η| dσ,
// with G(ξ, η) = −1/(4π|ξ−η|) and Γ_i the piecewise-linear hat function of vertex i. The
// deformed point of the paper is
//   η' = Σ_i φ_i v'_i + Σ_j ψ_j s_j n(t'_j),
// n(t'_j) the deformed triangle's unit outward normal and s_j its stretch factor (paper, 3-D):
//   s_j = sqrt(|u'|²|v|² − 2(u'·v')(u·v) + |v'|²|u|²) / (sqrt(8) · area(t_j)),
// u = v_b − v_a, v = v_c − v_a the triangle's edge vectors at rest, u', v' deformed (s_j = 1 at
// rest, s_j = k under a uniform scale by k). Under any similarity of the cage (rotation, uniform
// scale, translation) every point moves by that similarity; under other deformations the map is
// close to conformal (shape preserving). Σ_i φ_i = 1. Affine maps that are not similarities are
// NOT reproduced (by design of the coordinates).
//
// The per-triangle integrals are evaluated in closed form (see README.md, "Green coordinates"):
// the signed solid angle of the triangle, the integrals of 1/|ξ−η| along its edges and the
// divergence theorem in the triangle's plane; these are the integrals of the paper's GCTriInt,
// written in a form without arccos and without the paper's ε test. Accuracy (rest reproduction,
// Σφ − 1): ~1e-15 of the cage size for points ≥ 1e-5 of the size from the cage, degrading near
// edges of non-axis-aligned cages to ~1e-10 at 1e-8 and ~1e-7 at 1e-11 (README.md).
//
// Only interior points are accepted (generalised winding number > 1/2 and not on the cage): the
// paper's exterior extension (a correction across the face through which a point leaves) is not
// implemented; bindGreen refuses outside points, naming the first one.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "sim/base/types.h"
#include "sim/cage/embedding.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

struct GreenOptions {
  int threads = 0;  // threads for the weights (0 = threadCount(); sim/base/parallel.h)
  // Keep the double weights (rowWeights, deformDouble); the float copy is always made.
  bool keepDoublePrecision = true;
};

// W (#points × (V + F), dense, kind EmbeddingKind::Green) with W = [φ | ψ]: columns 0 … V−1
// the vertex coordinates φ_i, columns V … V+F−1 the face coordinates ψ_j (face order of
// cage.triangles; units: metres — W · greenControls(...) is in the cage's units). The cage is
// attached (Embedding::attachGreenCage): deform(deformed cage vertices, V × 3) extends them
// with greenControls and gives the deformed points. Points in the
// cage's units. Validates the cage with mesh::validateClosedSurface (throws mesh::SurfaceError:
// open, non-manifold, inverted, degenerate). Refuses (std::invalid_argument, naming the point's
// index and position) a non-finite point, a point outside the cage and a point on it (within
// 1e-12 cage diagonals of a triangle). Rows are computed independently in a fixed order:
// bit-identical for any thread count. Stats: seconds, threads, weight range, max |Σ_i φ_i − 1|
// (maxSumError; over the vertex columns only) and the rest-pose reproduction error
// max |W · greenControls(cage, rest) − η| / cage diagonal (maxLinearError).
Embedding bindGreen(const std::vector<Vec3>& points, const mesh::TriangleMesh& cage,
                    const GreenOptions& options = {});

// The extended controls ((V + F) × 3, metres) for the cage `restCage` (connectivity and rest
// positions) moved to `deformed` (V × 3, one row per cage vertex): rows 0 … V−1 the deformed
// vertices, row V + j = s_j · n(t'_j) (stretch factor times deformed unit outward normal of
// triangle j): W · greenControls(restCage, deformed) is the deformed points (what deform does
// with the attached cage). A deformed triangle of zero area has no normal: its row is zero (the
// face term is left out; the map stays finite). Throws std::invalid_argument on a size
// mismatch.
Eigen::Matrix<double, Eigen::Dynamic, 3> greenControls(
    const mesh::TriangleMesh& restCage, const Eigen::Matrix<double, Eigen::Dynamic, 3>& deformed);

// The Green coordinates of one point η (relative to nothing: world positions), without checks:
// phi (V) and psi (F), for tests and tools. The point must be inside the cage and off it;
// returns the generalised winding number Σ Ω_j / 4π (≈ 1 inside, ≈ 0 outside).
double greenCoordinates(const Vec3& eta, const mesh::TriangleMesh& cage, Eigen::VectorXd& phi,
                        Eigen::VectorXd& psi);

}  // namespace sb::cage
