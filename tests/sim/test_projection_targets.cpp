// The projection onto one goal transform is compiled for two targets (AVX2 and the x86-64
// baseline) and the loader picks one by CPU; goal_projection.cpp promises both give the same
// bits. This file builds a second copy for the baseline alone, under another name, and compares
// it with the one the library dispatches to on this machine: linear and quadratic goals, with
// and without the velocities formed in the same sweep, ranges of every remainder length, particles
// within and beyond the reach, and a non-finite one.
#include "sim/world/matching/goal_projection.h"

#define SB_GOAL_PROJECTION_BASELINE
#define projectOntoTransform baselineProjectOntoTransform
#include "sim/world/matching/goal_projection.cpp"
#undef projectOntoTransform

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace sb {
namespace {

TEST(ProjectionTargets, BaselineAndDispatchedKernelsGiveTheSameBits) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const int n = 301;
  std::vector<float> r[3], start[3];
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) {
      r[a].push_back(u(rng));
      // Every third particle far from its goal: beyond a reach of 0.5.
      start[a].push_back(u(rng) * (i % 3 == 0 ? 4.0f : 0.2f));
    }
  start[1][17] = std::nanf("");
  GoalTransform T;
  for (int k = 0; k < 9; ++k) T.L.data()[k] += 0.1f * u(rng);
  for (int k = 0; k < 18; ++k) T.Q.data()[k] = 0.05f * u(rng);
  T.t = Eigen::Vector3f(0.3f, -0.2f, 0.1f);
  const RestColumns rest{r[0].data(), r[1].data(), r[2].data()};
  std::vector<float> vStart[3];
  for (auto& column : vStart)
    for (int i = 0; i < n; ++i) column.push_back(u(rng));
  int compared = 0;
  for (bool quadratic : {false, true})
    for (bool withVelocities : {false, true})
      for (int begin : {0, 3})
        for (int end : {begin + 1, begin + 7, begin + 8, begin + 9, n - 5, n}) {
          std::vector<float> a[3] = {start[0], start[1], start[2]};
          std::vector<float> b[3] = {start[0], start[1], start[2]};
          std::vector<float> va[3], vb[3];
          for (int c = 0; c < 3; ++c) va[c] = vb[c] = vStart[c];
          auto velocities = [&](std::vector<float>* v) {
            return ProjectedVelocities{
                {v[0].data(), v[1].data(), v[2].data()},
                {{-0.02f, -0.3f, 0.1f}, {0.3f, -0.05f, -0.2f}, {-0.1f, 0.2f, -0.01f}},
                {0.5f, -1.0f, 0.25f},
                60.0f,
                {0.0f, -0.16f, 0.0f}};
          };
          const ProjectedVelocities velA = velocities(va), velB = velocities(vb);
          const int badA = projectOntoTransform(
              PositionColumns{a[0].data(), a[1].data(), a[2].data()}, rest, begin, end, T,
              quadratic, 0.4f, 0.5f, withVelocities ? &velA : nullptr);
          const int badB = baselineProjectOntoTransform(
              PositionColumns{b[0].data(), b[1].data(), b[2].data()}, rest, begin, end, T,
              quadratic, 0.4f, 0.5f, withVelocities ? &velB : nullptr);
          EXPECT_EQ(badA != 0, badB != 0) << quadratic << " " << begin << " " << end;
          for (int c = 0; c < 3; ++c)
            for (int i = 0; i < n; ++i) {
              const size_t k = size_t(i);
              if (!(std::isnan(a[c][k]) && std::isnan(b[c][k]))) {
                EXPECT_EQ(std::memcmp(&a[c][k], &b[c][k], sizeof(float)), 0)
                    << quadratic << " " << begin << " " << end << " " << c << " " << i;
              }
              if (!(std::isnan(va[c][k]) && std::isnan(vb[c][k]))) {
                EXPECT_EQ(std::memcmp(&va[c][k], &vb[c][k], sizeof(float)), 0)
                    << quadratic << " " << begin << " " << end << " v" << c << " " << i;
              }
            }
          ++compared;
        }
  EXPECT_EQ(compared, 48);
}

}  // namespace
}  // namespace sb
