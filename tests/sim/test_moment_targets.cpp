// The moment sums are compiled for two targets (AVX2 and the x86-64 baseline) and the loader
// picks one by CPU; shape_matching.cpp promises both give the same bits. This file builds a
// second copy for the baseline alone, under other names, and compares it with the one the
// library dispatches to on this machine, for every variant (gathered or not, linear or
// quadratic, small and multi-block clusters).
#include "sim/world/matching/shape_matching.h"

#define SB_SHAPE_MATCHING_BASELINE
#define accumulateMoments baselineAccumulateMoments
#define fitCluster baselineFitCluster
#define goalTransform baselineGoalTransform
#include "sim/world/matching/shape_matching.cpp"
#undef accumulateMoments
#undef fitCluster
#undef goalTransform

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace sb {
namespace {

bool sameBits(const ClusterMoments& a, const ClusterMoments& b) {
  return std::memcmp(a.wd.data(), b.wd.data(), sizeof(double) * 3) == 0 &&
         std::memcmp(a.wdq.data(), b.wdq.data(), sizeof(double) * 9) == 0 &&
         std::memcmp(a.wdm.data(), b.wdm.data(), sizeof(double) * 18) == 0;
}

TEST(MomentTargets, BaselineAndDispatchedSumsGiveTheSameBits) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const int n = 3000;
  std::vector<float> x[3], r[3], w;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) {
      x[a].push_back(2.0f + u(rng));
      r[a].push_back(u(rng));
    }
  for (int i = 0; i < n; ++i) w.push_back(0.1f + std::abs(u(rng)));
  std::vector<int> members;
  std::vector<float> q[3], mw;
  for (int k = 0; k < n; ++k) {
    const int i = (k * 7919) % n;
    members.push_back(i);
    for (int a = 0; a < 3; ++a) q[a].push_back(r[a][size_t(i)] - 0.01f);
    mw.push_back(w[size_t(i)]);
  }
  ParticleColumns cols{
      {x[0].data(), x[1].data(), x[2].data()}, {r[0].data(), r[1].data(), r[2].data()}, w.data()};
  ParticleColumns gathered = cols;
  for (int a = 0; a < 3; ++a) gathered.memberQ[a] = q[a].data();
  gathered.memberW = mw.data();
  const Eigen::Vector3f ref(2.1f, 1.9f, 2.0f), rc(0.01f, 0.01f, 0.01f);
  int compared = 0;
  for (int end : {5, 16, 17, 100, 513, 1025, 3000})
    for (bool quadratic : {false, true}) {
      const ClusterMoments direct = accumulateMoments(cols, nullptr, 0, end, ref, rc, quadratic);
      const ClusterMoments directBase =
          baselineAccumulateMoments(cols, nullptr, 0, end, ref, rc, quadratic);
      EXPECT_TRUE(sameBits(direct, directBase)) << end << " " << quadratic;
      const ClusterMoments viaMembers =
          accumulateMoments(gathered, members.data(), 0, end, ref, rc, quadratic);
      const ClusterMoments viaMembersBase =
          baselineAccumulateMoments(gathered, members.data(), 0, end, ref, rc, quadratic);
      EXPECT_TRUE(sameBits(viaMembers, viaMembersBase)) << end << " " << quadratic;
      compared += 2;
    }
  EXPECT_EQ(compared, 28);
}

}  // namespace
}  // namespace sb
