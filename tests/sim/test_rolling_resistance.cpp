// The rolling-resistance kernel (sim/world/contact/rolling_resistance.h): the couple stops the
// relative spin when the bound allows, is bounded otherwise, never adds kinetic energy, never
// reverses the spin, and exchanges angular momentum without making any.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "sim/world/contact/rolling_resistance.h"

namespace sb {
namespace {

// A random inertia tensor (kg·m²): principal moments in [0.1, 2], randomly turned.
Mat3 randomInertia(std::mt19937& rng) {
  std::uniform_real_distribution<double> moment(0.1, 2.0), any(-1.0, 1.0);
  const Eigen::Quaterniond q =
      Eigen::Quaterniond(any(rng), any(rng), any(rng), any(rng)).normalized();
  const Mat3 r = q.toRotationMatrix();
  return r * Vec3(moment(rng), moment(rng), moment(rng)).asDiagonal() * r.transpose();
}

double kinetic(const Mat3& inertia, const Vec3& spin) {
  return 0.5 * spin.dot(inertia * spin);
}

TEST(RollingResistance, StopsTheSpinWhenTheBoundAllows) {
  std::mt19937 rng(3);
  const Mat3 inertia = randomInertia(rng);
  const Vec3 spin(0.3, -1.2, 0.5);
  const Vec3 couple = rollingCouple(inertia.inverse(), Mat3::Zero(), spin, 1e3);
  EXPECT_LT((spin + inertia.inverse() * couple).norm(), 1e-12);  // at rest on the obstacle
  EXPECT_LT((couple + inertia * spin).norm(), 1e-12);            // −Iω: the momentum it had
}

TEST(RollingResistance, BoundedCouplesTakeEnergyAndNeverReverseTheSpin) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> any(-3.0, 3.0), bound(0.0, 2.0);
  for (int trial = 0; trial < 500; ++trial) {
    const Mat3 ia = randomInertia(rng), ib = randomInertia(rng);
    const bool bTurns = trial % 2 == 0;  // a body, or a static collider (no inverse inertia)
    const Mat3 invA = ia.inverse(), invB = bTurns ? Mat3(ib.inverse()) : Mat3::Zero();
    const Vec3 wa(any(rng), any(rng), any(rng));
    const Vec3 wb = bTurns ? Vec3(any(rng), any(rng), any(rng)) : Vec3::Zero();
    const double maxCouple = bound(rng);
    const Vec3 couple = rollingCouple(invA, invB, wa - wb, maxCouple);
    EXPECT_LE(couple.norm(), maxCouple * (1 + 1e-12));
    const Vec3 wa2 = wa + invA * couple, wb2 = wb - invB * couple;
    const double before = kinetic(ia, wa) + (bTurns ? kinetic(ib, wb) : 0.0);
    const double after = kinetic(ia, wa2) + (bTurns ? kinetic(ib, wb2) : 0.0);
    EXPECT_LE(after, before + 1e-12 * before);
    // The relative spin shrinks along itself: (1 − s)·w with s in [0, 1].
    const Vec3 w = wa - wb, w2 = wa2 - wb2;
    const double s = 1.0 - w2.dot(w) / w.squaredNorm();
    EXPECT_GE(s, -1e-12);
    EXPECT_LE(s, 1.0 + 1e-12);
    EXPECT_LT((w2 - (1.0 - s) * w).norm(), 1e-9 * w.norm());
    if (bTurns) {  // exchanged: what a gains, b loses
      EXPECT_LT((ia * wa2 + ib * wb2 - ia * wa - ib * wb).norm(), 1e-9 * (ia * wa).norm());
    }
  }
}

// A body that turns freely about an axis (all its particles on that axis: no inertia there,
// zero in the pseudo-inverse) takes no couple about it, and none at all without a bound.
TEST(RollingResistance, NoCoupleAlongAFreeAxisOrWithoutLoad) {
  const Mat3 invA = Vec3(0.0, 2.0, 2.0).asDiagonal();  // a rod along x
  const Vec3 couple = rollingCouple(invA, Mat3::Zero(), Vec3(5.0, 1.0, 0.0), 1e3);
  EXPECT_EQ(couple.x(), 0.0);
  EXPECT_NEAR(couple.y(), -0.5, 1e-12);
  EXPECT_TRUE(rollingCouple(invA, Mat3::Zero(), Vec3(5.0, 1.0, 0.0), 0.0).isZero());
}

}  // namespace
}  // namespace sb
