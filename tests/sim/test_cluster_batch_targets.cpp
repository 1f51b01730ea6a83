// The batched kernel is compiled for two targets (AVX2 and the x86-64 baseline) and the loader
// picks one by CPU; cluster_batch.h promises both give the same bits. This file builds a second
// copy of the kernel for the baseline alone, under other names, and compares it with the one the
// library dispatches to on this machine, on inputs that take every branch (saddles, inverted
// clusters, volume clamps, non-finite lanes).
#include "sim/world/matching/cluster_batch.h"

#define SB_CLUSTER_BATCH_BASELINE
#define buildClusterBatches baselineBuildClusterBatches
#define setBatchShapeLane baselineSetBatchShapeLane
#define matchClusterBatch baselineMatchClusterBatch
#include "sim/world/matching/cluster_batch.cpp"
#undef buildClusterBatches
#undef setBatchShapeLane
#undef matchClusterBatch

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include "tests/draws.h"

namespace sb {
namespace {

TEST(ClusterBatchTargets, BaselineAndDispatchedKernelGiveTheSameBits) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const int particles = 64;
  std::vector<float> x[3];
  for (auto& column : x)
    for (int i = 0; i < particles; ++i) column.push_back(u(rng));
  x[1][7] = std::nanf("");
  const float* xs[3] = {x[0].data(), x[1].data(), x[2].data()};
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    ClusterBatch batch;
    batch.count = 1 + trial % kBatchLanes;
    batch.memberSlots = 1 + trial % kBatchMaxMembers;
    ClusterBatchShape shape;
    ClusterBatchLanes lanes;
    for (int l = 0; l < kBatchLanes; ++l) {
      batch.cluster[l] = l;
      float mass = 0;
      for (int m = 0; m < batch.memberSlots; ++m) {
        batch.particle[m][l] = int(std::abs(u(rng)) * (particles - 1));
        for (int a = 0; a < 3; ++a) batch.q0[a][m][l] = u(rng);
        batch.w[m][l] = 0.5f + std::abs(u(rng));
        mass += batch.w[m][l];
      }
      batch.mass[l] = mass;
      for (int a = 0; a < 3; ++a) batch.sumWq0[a][l] = 1e-7f * u(rng);
      for (int e = 0; e < 9; ++e) {
        shape.AqqInv[e][l] = (e % 4 == 0 ? 2.0f : 0.0f) + 0.5f * u(rng);
        shape.S[e][l] = (e % 4 == 0 ? 1.0f : 0.0f) + 0.1f * u(rng);
      }
      for (int a = 0; a < 3; ++a) {
        shape.s0[a][l] = 0.1f * u(rng);
        lanes.ref[a][l] = 0.2f * u(rng);
      }
      Eigen::Vector4f q = test::drawVector<Eigen::Vector4f>([&] { return u(rng); });
      q.normalize();
      for (int k = 0; k < 4; ++k) lanes.rotation[k][l] = q[k];
    }
    BodyParams params;
    params.mode = trial % 3 == 0 ? Mode::Rigid : Mode::Linear;
    params.beta = (trial % 5) / 4.0;
    params.preserveVolume = trial % 2 == 0;
    ClusterBatchLanes dispatchedLanes = lanes, baselineLanes = lanes;
    const ClusterBatchGoals dispatched =
        matchClusterBatch(batch, shape, xs, params, dispatchedLanes);
    const ClusterBatchGoals baseline =
        baselineMatchClusterBatch(batch, shape, xs, params, baselineLanes);
    ASSERT_EQ(dispatched.fallback, baseline.fallback) << trial;
    ASSERT_EQ(dispatched.nonFinite, baseline.nonFinite) << trial;
    const std::uint32_t valid = ~(dispatched.fallback | dispatched.nonFinite);
    for (int l = 0; l < batch.count; ++l) {
      if (!(valid >> l & 1u)) continue;
      for (int e = 0; e < 9; ++e)
        ASSERT_EQ(std::memcmp(&dispatched.L[e][l], &baseline.L[e][l], sizeof(float)), 0) << trial;
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(std::memcmp(&dispatched.t[a][l], &baseline.t[a][l], sizeof(float)), 0) << trial;
        ASSERT_EQ(std::memcmp(&dispatchedLanes.ref[a][l], &baselineLanes.ref[a][l], sizeof(float)),
                  0);
      }
      for (int k = 0; k < 4; ++k)
        ASSERT_EQ(std::memcmp(&dispatchedLanes.rotation[k][l], &baselineLanes.rotation[k][l],
                              sizeof(float)),
                  0);
      ++compared;
    }
  }
  EXPECT_GT(compared, 300);
}

}  // namespace
}  // namespace sb
