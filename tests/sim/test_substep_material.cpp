// The per-sub-step material parameters stated at the reference sub-step and converted to any
// other (sim/world/substep_material.h): each conversion keeps the quantity it claims to keep,
// recomputed here from its closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/world/matching/shape_matching.h"
#include "sim/world/substep_material.h"

namespace sb {
namespace {

// Stiffness per unit mass (1/s²) of a pull `a` per sub-step of h seconds: the spring whose
// implicit-Euler step moves a point that share of the way to its rest position.
double stiffness(double a, double h) {
  return a / ((1.0 - a) * h * h);
}

// Relative error stiffness() may carry for a pull `a` rounded to double: 1 − a loses digits as
// a nears 1.
double stiffnessTolerance(double a) {
  return 1e-13 / (1.0 - a) + 1e-12;
}

const double kSteps[] = {1e-4, 1.0 / 960, 1.0 / 480, 1.0 / 120, 1.0 / 60, 0.1, 1.0, 10.0};

TEST(SubstepMaterial, AlphaKeepsTheStiffnessPerUnitMass) {
  for (double alpha : {0.001, 0.05, 0.3, 0.5, 0.9, 0.999})
    for (double h : kSteps) {
      const double a = alphaForSubstep(alpha, h);
      EXPECT_GT(a, 0.0);
      EXPECT_LT(a, 1.0);
      EXPECT_NEAR(stiffness(a, h) / stiffness(alpha, kReferenceSubstep), 1.0, stiffnessTolerance(a))
          << "alpha " << alpha << " h " << h;
    }
  // Longer sub-steps need a larger share of the way for the same stiffness.
  EXPECT_LT(alphaForSubstep(0.5, 1.0 / 480), 0.5);
  EXPECT_GT(alphaForSubstep(0.5, 1.0 / 120), 0.5);
  // No pull stays none, a projection onto the goal stays one (rigid at any step).
  for (double h : kSteps) {
    EXPECT_EQ(alphaForSubstep(0.0, h), 0.0);
    EXPECT_EQ(alphaForSubstep(1.0, h), 1.0);
  }
}

TEST(SubstepMaterial, BetaKeepsTheStiffnessOfWhatTheFitFollows) {
  // A deformation the fit represents is pulled back by α(1 − β′) per sub-step (β′ the applied
  // blend): its stiffness is the same at every sub-step, as is the rotation's (α).
  for (double alpha : {0.05, 0.5, 0.9, 1.0})
    for (double beta : {0.0, 0.3, 0.7, 1.0})
      for (double h : kSteps) {
        const double a = alphaForSubstep(alpha, h);
        const double b = appliedBeta(betaForSubstep(beta, alpha, h));
        EXPECT_GE(b, 0.0);
        EXPECT_LT(b, 1.0);  // the goal never follows the fit entirely
        const double pull = a * (1.0 - b), pullRef = alpha * (1.0 - appliedBeta(beta));
        if (pullRef >= 1.0) {
          EXPECT_NEAR(pull, 1.0, 1e-12);
          continue;
        }
        EXPECT_NEAR(stiffness(pull, h) / stiffness(pullRef, kReferenceSubstep), 1.0,
                    stiffnessTolerance(pull) + stiffnessTolerance(a))
            << "alpha " << alpha << " beta " << beta << " h " << h;
      }
}

TEST(SubstepMaterial, DampingKeepsTheDecayPerSecond) {
  for (double d : {0.01, 0.1, 0.5, 0.99})
    for (double h : kSteps) {
      const double dh = dampingForSubstep(d, h);
      EXPECT_GT(dh, 0.0);
      EXPECT_LT(dh, 1.0 + 1e-15);
      // The share of the deformation's velocity a sub-step leaves is what h / h_ref reference
      // sub-steps leave.
      const double left = std::exp(h / kReferenceSubstep * std::log1p(-d));
      EXPECT_NEAR(1.0 - dh, left, 1e-15 + 1e-12 * left) << "damping " << d << " h " << h;
    }
  for (double h : kSteps) {
    EXPECT_EQ(dampingForSubstep(0.0, h), 0.0);
    EXPECT_EQ(dampingForSubstep(1.0, h), 1.0);
  }
}

TEST(SubstepMaterial, ParametersAtTheReferenceSubstepApplyAsGiven) {
  BodyParams p;
  p.alpha = 0.3;
  p.beta = 0.7;
  p.damping = 0.1;
  p.restitution = 0.4;
  // The shipped scenes' 0.016666667 s in four sub-steps is the reference to 1e-6.
  for (double h : {kReferenceSubstep, 0.016666667 / 4}) {
    const BodyParams q = paramsForSubstep(p, h);
    EXPECT_EQ(q.alpha, p.alpha);
    EXPECT_EQ(q.beta, p.beta);
    EXPECT_EQ(q.damping, p.damping);
  }
  // Elsewhere α, β and damping change and nothing else does.
  const BodyParams q = paramsForSubstep(p, 1.0 / 60);
  EXPECT_NE(q.alpha, p.alpha);
  EXPECT_NE(q.beta, p.beta);
  EXPECT_NE(q.damping, p.damping);
  EXPECT_EQ(q.restitution, p.restitution);
  EXPECT_EQ(q.mode, p.mode);
}

}  // namespace
}  // namespace sb
