// The restitution kernel of impacts with a soft body (sim/world/contact/soft_impact.h), against
// its closed forms: the phases of an impact and the relaxation time.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/world/contact/soft_impact.h"

namespace sb {
namespace {

// The pair's contacts pushed hard enough that holding back is not limited by them.
constexpr float kFree = 100.0f;

SoftImpact impactAt(float approach, float e, int relaxing) {
  SoftImpact impact;
  impact.approach = approach;
  impact.restitution = e;
  impact.relaxing = relaxing;
  return impact;
}

TEST(SoftImpact, NearMissEndsWithoutAnyCorrection) {
  SoftImpact impact = impactAt(3.0f, 0.5f, 5);
  bool alive = false;
  EXPECT_EQ(advanceSoftImpact(impact, -2.0f, false, kFree, alive), 0.0f);
  EXPECT_TRUE(alive);  // still coming
  EXPECT_EQ(advanceSoftImpact(impact, 0.5f, false, kFree, alive), 0.0f);
  EXPECT_FALSE(alive);  // left again before the surfaces met: no bounce
}

TEST(SoftImpact, CompressesThenPartsWithEAndHoldsThatSpeed) {
  const float u0 = 4.0f, e = 0.5f;
  SoftImpact impact = impactAt(u0, e, 4);
  bool alive = false;
  // Meeting and compressing: no correction while the centres approach.
  for (float v : {-3.0f, -1.0f, -0.2f}) {
    EXPECT_EQ(advanceSoftImpact(impact, v, true, kFree, alive), 0.0f);
    EXPECT_TRUE(alive);
  }
  EXPECT_EQ(impact.compressing, 3);
  // Compression over: the relative velocity is set to e·u₀.
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 0.1f, true, kFree, alive), e * u0 - 0.1f);
  // Release: faster is held back to e·u₀, slower is left alone, for max(compressing + 1,
  // relaxing) = 4 sub-steps.
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 2.7f, true, kFree, alive), e * u0 - 2.7f);
  EXPECT_EQ(advanceSoftImpact(impact, 1.5f, true, kFree, alive), 0.0f);
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 2.1f, false, kFree, alive), e * u0 - 2.1f);
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 2.2f, false, kFree, alive), e * u0 - 2.2f);
  EXPECT_TRUE(alive);
  EXPECT_EQ(advanceSoftImpact(impact, 5.0f, false, kFree, alive), 0.0f);
  EXPECT_FALSE(alive);
}

// Holding back takes at most what the pair's own contacts gave in the sub-step: a drag or a
// third body that parts the pair is not fought.
TEST(SoftImpact, HoldTakesBackOnlyWhatThePairsContactsGave) {
  SoftImpact impact = impactAt(3.0f, 0.0f, 10);
  bool alive = false;
  EXPECT_EQ(advanceSoftImpact(impact, -1.0f, true, kFree, alive), 0.0f);
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 0.5f, true, 0.2f, alive), -0.2f);
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 0.5f, true, 0.7f, alive), -0.5f);
  EXPECT_EQ(advanceSoftImpact(impact, 0.5f, false, 0.0f, alive), 0.0f);
  EXPECT_EQ(advanceSoftImpact(impact, 0.5f, false, -1.0f, alive), 0.0f);  // they pulled: nothing
  EXPECT_TRUE(alive);
}

TEST(SoftImpact, InelasticImpactStopsAtOnceWhenTheSolveAlreadyStoppedIt) {
  SoftImpact impact = impactAt(2.0f, 0.0f, 1);
  bool alive = false;
  // The solve stopped the pair in the sub-step the surfaces met: released at once, to 0.
  EXPECT_FLOAT_EQ(advanceSoftImpact(impact, 0.3f, true, kFree, alive), -0.3f);
  EXPECT_TRUE(alive);
  EXPECT_EQ(impact.compressing, 0);
}

TEST(SoftImpact, RelaxationTimeIsTheClosedForm) {
  for (double alpha : {0.05, 0.1, 0.3, 0.5, 0.9, 0.99}) {
    const int n = relaxSubsteps(alpha);
    // (1 − α)ⁿ ≤ 0.01 < (1 − α)ⁿ⁻¹, or the cap.
    if (n < kMaxRelaxSubsteps) {
      EXPECT_LE(std::pow(1.0 - alpha, n), 0.01 * (1 + 1e-12)) << alpha;
      EXPECT_GT(std::pow(1.0 - alpha, n - 1), 0.01) << alpha;
    } else {
      EXPECT_GT(std::pow(1.0 - alpha, kMaxRelaxSubsteps - 1), 0.01) << alpha;
    }
  }
  EXPECT_EQ(relaxSubsteps(0.1), 44);
  EXPECT_EQ(relaxSubsteps(0.3), 13);
  EXPECT_EQ(relaxSubsteps(1.0), 1);
  EXPECT_EQ(relaxSubsteps(0.0), kMaxRelaxSubsteps);
  EXPECT_EQ(relaxSubsteps(std::nan("")), kMaxRelaxSubsteps);
}

}  // namespace
}  // namespace sb
