// The material parameters that act once per sub-step — α (stiffness), β (how far the goal
// follows the fit) and damping — are stated for a reference sub-step and converted to the
// sub-step a step runs, so a body's material does not change with the time step or the number of
// sub-steps (docs/design.md §5.3).
//
// Applied per sub-step as given, α is a stiffness per unit mass k = α/((1 − α)·h²): four
// sub-steps instead of one made a body sixteen times stiffer (a cantilever's sag 6.7 → 0.42 mm),
// and damping d removed 1 − (1 − d)ⁿ of the deformation's velocity in n sub-steps.
#pragma once

#include "sim/world/body_def.h"

namespace sb {

// The sub-step the parameters are stated for (s): a 1/60 s frame in four sub-steps, as every
// shipped scene runs (they keep their bits).
inline constexpr double kReferenceSubstep = 1.0 / 240.0;

// α for a sub-step of h seconds (h > 0, α in [0, 1]): the same k = α/((1 − α)·h_ref²), i.e.
// α_h = k·h²/(1 + k·h²) = α·r/((1 − α) + α·r) with r = (h/h_ref)². 0 and 1 map to themselves,
// α_h grows with h and stays below 1 for α < 1.
double alphaForSubstep(double alpha, double h);

// β for a sub-step of h seconds. A deformation the fit can represent is pulled back by
// α·(1 − β′) per sub-step (β′ = kBetaMax·β, the blend applied, shape_matching.h) while a rotation
// is pulled back by α; both keep their stiffness per unit mass when
// 1 − β′_h = alphaForSubstep(α(1 − β′), h) / alphaForSubstep(α, h).
// Returns β_h = β′_h / kBetaMax, which exceeds 1 for sub-steps shorter than the reference at
// large α and β (β′_h stays below 1 for β′ < 1). Unchanged for α = 0 (no pull at all).
double betaForSubstep(double beta, double alpha, double h);

// Damping for a sub-step of h seconds (d in [0, 1]): the same share of the deformation's velocity
// left per second, 1 − (1 − d)^(h/h_ref). 0 and 1 map to themselves.
double dampingForSubstep(double damping, double h);

// `params` with α, β and damping for a sub-step of h seconds. At the reference sub-step (to 1e-6
// relative, so a dt written as 0.016666667 in four sub-steps counts) it returns them unchanged,
// bit for bit.
BodyParams paramsForSubstep(const BodyParams& params, double h);

}  // namespace sb
