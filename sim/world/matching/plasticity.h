// Plastic flow of a cluster's rest shape (docs/design.md §5.2, Müller et al. 2005 §4.4).
#pragma once

#include "sim/base/types.h"
#include "sim/world/body_def.h"

namespace sb {

// Spectral norm ‖M‖₂ (largest singular value).
double spectralNorm(const Mat3& M);

// One plastic update over a step of h seconds, given the cluster's current stretch S (symmetric,
// from A = R·S relative to the current rest shape):
//   if ‖S − I‖₂ > c_yield:  Sᵖ ← sym((I + f·(S − I))·Sᵖ), f = 1 − e^(−h·c_creep) ≤ 1 (never
//                           past the current shape; Müller's h·c_creep for small h·c_creep),
//                           sym = the symmetric polar factor, then Sᵖ ← Sᵖ / ∛det Sᵖ
//   if ‖Sᵖ − I‖₂ > c_max:   Sᵖ ← I + c_max·(Sᵖ − I)/‖Sᵖ − I‖₂, renormalised
// Keeps det Sᵖ = 1 and ‖Sᵖ − I‖₂ ≤ c_max. Returns true when Sᵖ changed. A stretch that is not
// finite or would make det ≤ 0 leaves Sᵖ unchanged.
bool updatePlasticDeformation(const Mat3& stretch, double h, const PlasticityParams& params,
                              Mat3& plastic);

}  // namespace sb
