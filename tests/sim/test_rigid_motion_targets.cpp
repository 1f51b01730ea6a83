// The rigid motion's block sums are compiled for two targets (AVX2 and the x86-64 baseline) and
// the loader picks one by CPU; mass_properties.cpp promises both give the same bits. This file
// builds a second copy for the baseline alone, under other names, and compares it with the one
// the library dispatches to on this machine: whole blocks, a partial last block, a lone point,
// and a non-finite lane.
#include "sim/world/mass_properties.h"

#define SB_MASS_PROPERTIES_BASELINE
#define massProperties baselineMassProperties
#define rigidMotion baselineRigidMotion
#define rigidMotionOnThreads baselineRigidMotionOnThreads
#define startRigidMotionSums baselineStartRigidMotionSums
#define sumRigidMotionBlocks baselineSumRigidMotionBlocks
#define rigidMotionOf baselineRigidMotionOf
#define centreOfMass baselineCentreOfMass
#define linearMomentum baselineLinearMomentum
// Function-like: RigidMotion has a member of that name, which must keep it.
#define angularMomentum(...) baselineAngularMomentum(__VA_ARGS__)
#include "sim/world/mass_properties.cpp"
#undef massProperties
#undef rigidMotion
#undef rigidMotionOnThreads
#undef startRigidMotionSums
#undef sumRigidMotionBlocks
#undef rigidMotionOf
#undef centreOfMass
#undef linearMomentum
#undef angularMomentum

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace sb {
namespace {

bool sameBits(const RigidMotion& a, const RigidMotion& b) {
  auto same = [](const auto& p, const auto& q) {
    return std::memcmp(p.data(), q.data(), sizeof(double) * size_t(p.size())) == 0;
  };
  return same(a.centre, b.centre) && same(a.velocity, b.velocity) && same(a.omega, b.omega) &&
         same(a.angularMomentum, b.angularMomentum) && same(a.inverseInertia, b.inverseInertia);
}

TEST(RigidMotionTargets, BaselineAndDispatchedSumsGiveTheSameBits) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const int n = 3 * kRigidMotionBlock + 77;
  std::vector<float> x[3], v[3], w;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) {
      x[a].push_back(5.0f + u(rng));  // away from the origin, as bodies are
      v[a].push_back(u(rng));
    }
  for (int i = 0; i < n; ++i) w.push_back(0.1f + std::abs(u(rng)));
  const PointColumns xs{{x[0].data(), x[1].data(), x[2].data()}};
  const PointColumns vs{{v[0].data(), v[1].data(), v[2].data()}};
  int compared = 0;
  for (int count : {1, 7, 8, 9, kRigidMotionBlock, kRigidMotionBlock + 13, n}) {
    EXPECT_TRUE(sameBits(rigidMotion(xs, vs, w.data(), count),
                         baselineRigidMotion(xs, vs, w.data(), count)))
        << count;
    EXPECT_TRUE(sameBits(rigidMotionOnThreads(xs, vs, w.data(), count),
                         baselineRigidMotionOnThreads(xs, vs, w.data(), count)))
        << count;
    compared += 2;
  }
  EXPECT_EQ(compared, 14);
  // A non-finite lane: both give NaN in the same places (compared by bits would also compare
  // NaN payloads, which IEEE leaves open).
  v[1][5] = std::nanf("");
  const RigidMotion a = rigidMotion(xs, vs, w.data(), n);
  const RigidMotion b = baselineRigidMotion(xs, vs, w.data(), n);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(std::isnan(a.velocity[k]), std::isnan(b.velocity[k])) << k;
    EXPECT_EQ(std::isnan(a.omega[k]), std::isnan(b.omega[k])) << k;
  }
}

}  // namespace
}  // namespace sb
