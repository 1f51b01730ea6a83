#include "sim/world/substep_material.h"

#include <cmath>

#include "sim/world/matching/shape_matching.h"

namespace sb {
namespace {

// (h / h_ref)²: how much stiffer a stated α would be if applied as it is.
double stepRatio(double h) {
  const double q = h / kReferenceSubstep;
  return q * q;
}

}  // namespace

double alphaForSubstep(double alpha, double h) {
  if (alpha <= 0.0 || alpha >= 1.0) return alpha;
  const double r = stepRatio(h);
  return alpha * r / ((1.0 - alpha) + alpha * r);
}

double betaForSubstep(double beta, double alpha, double h) {
  if (alpha <= 0.0) return beta;
  const double applied = appliedBeta(beta);
  const double follows =
      1.0 - alphaForSubstep(alpha * (1.0 - applied), h) / alphaForSubstep(alpha, h);
  return follows / kBetaMax;
}

double dampingForSubstep(double damping, double h) {
  if (damping <= 0.0 || damping >= 1.0) return damping;
  return 1.0 - std::pow(1.0 - damping, h / kReferenceSubstep);
}

BodyParams paramsForSubstep(const BodyParams& params, double h) {
  if (std::abs(h / kReferenceSubstep - 1.0) <= 1e-6) return params;
  BodyParams p = params;
  p.alpha = alphaForSubstep(params.alpha, h);
  p.beta = betaForSubstep(params.beta, params.alpha, h);
  p.damping = dampingForSubstep(params.damping, h);
  return p;
}

}  // namespace sb
