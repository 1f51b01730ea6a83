// Multiquadric radial basis function (RBF) deformation: a smooth map of space that carries a set
// of control points (handles: cage vertices or any points) to where they are moved, written as a
// weight matrix W like every other embedding (embedding.h), so it deforms with the same kernels.
//
// The map is interpolation of the handles' displacement field, per coordinate:
//   f(x) = Σ_i λ_i φ(|x − c_i|) + a₀ + aᵀx,   φ(r) = √(r² + s²)  (Hardy's multiquadric),
// with f(c_j) = the moved handle j and the side conditions Σ λ_i = 0, Σ λ_i c_i = 0 that make the
// system square and tie the affine part to the data. Everything is linear in the moved handles,
// so f(x) = Σ_j W(x)_j q_j with W(x) = [φ(|x − c_1|) … φ(|x − c_n|), 1, xᵀ] · M⁻¹[:, :n] and
//   M = | Φ   P |,  Φ_ij = φ(|c_i − c_j|),  P = [1, c_iᵀ] (n × 4).
//       | Pᵀ  0 |
// Properties (tested): the handles are interpolated (W(c_j) = e_j), Σ_j W_j(x) = 1 and affine
// motions of the handles move every point by that same affine map (the affine part reproduces
// them exactly). Weights are global (every handle moves every point) and may be negative.
//
// The shape parameter s: s = shape × h, with h the mean distance from each handle to its
// nearest other handle. Small s (→ 0: φ = r, the polyharmonic "linear" kernel) gives a stiffer,
// more local-looking but less smooth map (creases at the handles); large s gives a smoother map
// but M's condition number grows fast (roughly like s⁴ for evenly spaced handles), so the
// accepted range is shape ∈ [0, 10]; 1 (the default) is Hardy's usual choice of about a spacing.
#pragma once

#include <vector>

#include "sim/base/types.h"
#include "sim/cage/embedding.h"

namespace sb::cage {

struct RbfOptions {
  double shape = 1.0;  // s / mean nearest-handle distance, in [0, 10]
  int threads = 0;     // threads for the weights (0 = threadCount(); sim/base/parallel.h)
};

// Largest handle count accepted: M is factorised densely, O(n³) (4,096 handles: ~0.1 TFLOP).
inline constexpr int kMaxRbfHandles = 4096;

// W (#points × #handles, dense, double kept) for handles at rest positions `handles` (metres).
// Refuses (std::invalid_argument, naming the index or the reason): fewer than 4 handles, more
// than kMaxRbfHandles, a non-finite point or handle, two handles at the same place, handles all
// in one plane (the affine part is then undetermined), a shape outside [0, 10]; and
// (std::runtime_error) a system too ill-conditioned to solve to 1e-6 (shape too large for
// these handles). The stats: seconds, threads, weight range, max |Σw − 1| and linear error
// (relative to the handles' bounding-box diagonal).
Embedding bindRbf(const std::vector<Vec3>& points, const std::vector<Vec3>& handles,
                  const RbfOptions& options = {});

}  // namespace sb::cage
