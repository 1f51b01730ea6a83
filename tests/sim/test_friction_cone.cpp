// The friction kernel (sim/world/contact/friction_cone.h) against its definition: the lowest
// kinetic energy within the cone, found independently by sampling the disc, and Coulomb's law
// at the result.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "sim/world/contact/friction_cone.h"

namespace sb {
namespace {

// The visit's energy change for impulse f, starting from `before` with slip s.
double energyChange(const Eigen::Matrix2f& K, const Eigen::Vector2f& s,
                    const Eigen::Vector2f& before, const Eigen::Vector2f& f) {
  const Eigen::Vector2d d = (f - before).cast<double>();
  return s.cast<double>().dot(d) + 0.5 * d.dot(K.cast<double>() * d);
}

// A random symmetric positive definite K with eigenvalues between 1/kg and `anisotropy`/kg
// along random axes.
Eigen::Matrix2f randomMetric(std::mt19937& rng, float anisotropy) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float angle = 6.2831853f * u(rng);
  const Eigen::Matrix2f R = Eigen::Rotation2Df(angle).toRotationMatrix();
  const Eigen::Vector2f eig(1.0f, std::pow(anisotropy, u(rng)));
  return R * eig.asDiagonal() * R.transpose();
}

// The radial clamp most impulse solvers use (and this one did): the closest point of the disc
// in the plain metric. With K = diag(100, 1) and the friction at its limit along x, a slip
// along y makes it trade the stiff direction for the soft one and end above the start; the
// kernel does not.
TEST(FrictionCone, RadialClampCanMakeEnergyTheKernelDoesNot) {
  const Eigen::Matrix2f K = Eigen::Vector2f(100.0f, 1.0f).asDiagonal();
  const float limit = 1.0f;
  const Eigen::Vector2f before(limit, 0.0f), free(limit, 10.0f * limit);
  const Eigen::Vector2f slip = K * (before - free);  // so that f* = before − K⁻¹·slip = free
  const Eigen::Vector2f radial = free * (limit / free.norm());
  EXPECT_GT(energyChange(K, slip, before, radial), 10.0);  // 81/2 − 50 + ... : clearly above
  const Eigen::Vector2f f = frictionImpulse(K, slip, before, limit);
  EXPECT_LE(energyChange(K, slip, before, f), 0.0);
  EXPECT_NEAR(f.norm(), limit, 1e-5f);
}

TEST(FrictionCone, LowestEnergyInTheConeAndCoulombsLaw) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int sticking = 0, slipping = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Matrix2f K = randomMetric(rng, trial % 3 == 0 ? 1.0f : 1000.0f);
    const float limit = 0.5f * (u(rng) + 1.0f);
    Eigen::Vector2f before(u(rng), u(rng));
    if (before.norm() > limit) before *= limit / before.norm();
    const Eigen::Vector2f slip = 3.0f * Eigen::Vector2f(u(rng), u(rng));
    const Eigen::Vector2f f = frictionImpulse(K, slip, before, limit);
    ASSERT_LE(f.norm(), limit * (1 + 1e-5f)) << "trial " << trial;
    const double e = energyChange(K, slip, before, f);
    EXPECT_LE(e, 1e-6) << "trial " << trial;
    // Independently: the lowest energy over a fine polar grid of the disc.
    double lowest = 0;  // `before` itself
    for (int a = 0; a < 720; ++a)
      for (int r = 1; r <= 200; ++r) {
        const float rad = limit * float(r) / 200, ang = 6.2831853f * float(a) / 720;
        const Eigen::Vector2f g(rad * std::cos(ang), rad * std::sin(ang));
        lowest = std::min(lowest, energyChange(K, slip, before, g));
      }
    EXPECT_LE(e, lowest + 1e-4 * (std::abs(lowest) + 1e-3)) << "trial " << trial;
    // Coulomb: inside the cone the contact sticks (no slip left); on its edge the slip left
    // opposes the friction impulse.
    // (In double; f itself is float, so its rounding, amplified by K, bounds how well the
    // slip's direction can be known: the 1e-5·|K|·|f| terms below.)
    const Eigen::Vector2d left =
        slip.cast<double>() + K.cast<double>() * (f - before).cast<double>();
    const Eigen::Vector2d fd = f.cast<double>();
    const double rounding = 1e-5 * K.norm() * fd.norm();
    if (f.norm() < limit * (1 - 1e-4f)) {
      EXPECT_LT(left.norm(), 1e-3 * (slip.norm() + 1.0) + rounding) << "trial " << trial;
      ++sticking;
    } else {
      const double cross = left.x() * fd.y() - left.y() * fd.x();
      EXPECT_LT(std::abs(cross), (1e-3 * left.norm() + rounding) * fd.norm()) << "trial " << trial;
      EXPECT_LE(left.dot(fd), rounding * fd.norm()) << "trial " << trial;
      ++slipping;
    }
  }
  EXPECT_GT(sticking, 20);  // both regimes were exercised
  EXPECT_GT(slipping, 20);
}

// With K a multiple of the identity the two metrics agree: the projection is the radial clamp.
TEST(FrictionCone, IsotropicMetricGivesTheRadialClamp) {
  const Eigen::Matrix2f K = 4.0f * Eigen::Matrix2f::Identity();
  const Eigen::Vector2f before(0.1f, -0.2f), slip(-3.0f, 1.0f);
  const Eigen::Vector2f free = before - K.inverse() * slip;
  const Eigen::Vector2f f = frictionImpulse(K, slip, before, 0.4f);
  EXPECT_LT((f - free * (0.4f / free.norm())).norm(), 1e-6f);
}

// An old impulse beyond a cone that shrank (the normal impulse dropped) ends inside it.
TEST(FrictionCone, ImpulseBeyondAShrunkenConeEndsInside) {
  const Eigen::Matrix2f K{{3.0f, 1.0f}, {1.0f, 2.0f}};
  const Eigen::Vector2f f =
      frictionImpulse(K, Eigen::Vector2f(0.0f, 0.0f), Eigen::Vector2f(2.0f, 1.0f), 0.5f);
  EXPECT_LE(f.norm(), 0.5f * (1 + 1e-5f));
}

}  // namespace
}  // namespace sb
