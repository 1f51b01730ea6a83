// Particle groups: built from real cluster layouts, checked against the clusters they come
// from, and the moments they add up against a direct double-precision sum.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "sim/world/matching/cluster_layout.h"
#include "sim/world/matching/particle_groups.h"
#include "test_util.h"

namespace sb {
namespace {

struct Body {
  int n = 0;
  std::vector<float> r[3], x[3], w;
  std::vector<std::vector<int>> lists;  // cluster member lists
  std::vector<int> particleStart, particleClusters;
};

// A 12×12×12 grid with grid clusters (cells of 3×3×3 points grown by one cell), positions
// rotated, stretched and moved 100 m away from the origin (float sums there lose digits unless
// taken about nearby reference points).
Body gridBody() {
  Body b;
  std::vector<Vec3> rest;
  for (int k = 0; k < 12; ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) rest.push_back(0.1 * Vec3(i, j, k));
  ClusterDef def;
  def.kind = ClusterDef::Kind::Grid;
  def.cellSize = 0.3;
  def.overlap = 0.3;
  b.lists = buildClusterMembers(def, rest);
  b.n = static_cast<int>(rest.size());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Mat3 F = test::randomRotation(rng) * Vec3(1.1, 0.9, 1.0).asDiagonal().toDenseMatrix();
  for (int i = 0; i < b.n; ++i) {
    const Vec3 x = F * rest[size_t(i)] + Vec3(100, -50, 20) +
                   1e-3 * test::drawVector<Vec3>([&] { return u(rng); });
    for (int a = 0; a < 3; ++a) {
      b.r[a].push_back(float(rest[size_t(i)][a]));
      b.x[a].push_back(float(x[a]));
    }
    b.w.push_back(float(0.5 + 0.25 * u(rng)));
  }
  std::vector<std::vector<int>> byParticle(size_t(b.n));
  for (size_t c = 0; c < b.lists.size(); ++c)
    for (int p : b.lists[c]) byParticle[size_t(p)].push_back(static_cast<int>(c));
  b.particleStart.push_back(0);
  for (const auto& l : byParticle) {
    b.particleClusters.insert(b.particleClusters.end(), l.begin(), l.end());
    b.particleStart.push_back(static_cast<int>(b.particleClusters.size()));
  }
  return b;
}

// A float vector in double. Out of line on purpose: GCC 12.2's SLP vectorizer (-O2) drops the
// float rounding of a double → float → double chain it can see whole (it computed this test's
// reference about the unrounded point). The library sets its float reference points in one
// sub-step and reads them in the next.
[[gnu::noinline]] Vec3 widen(const Eigen::Vector3f& v) {
  return v.cast<double>();
}

ParticleGroups groupsOf(const Body& b) {
  const float* rest[3] = {b.r[0].data(), b.r[1].data(), b.r[2].data()};
  return buildParticleGroups(b.n, Csr{b.particleStart, b.particleClusters},
                             static_cast<int>(b.lists.size()), rest, b.w.data());
}

TEST(ParticleGroups, GridCellsBecomeGroupsAndClustersAreUnionsOfGroups) {
  const Body b = gridBody();
  const ParticleGroups g = groupsOf(b);
  ASSERT_FALSE(g.empty());
  EXPECT_EQ(g.count(), 64);  // 4×4×4 cells of 27 points
  for (int k = 0; k < g.count(); ++k) {
    const std::vector<int> clusters(g.clusters.begin(k), g.clusters.end(k));
    for (const int* e = g.particles.begin(k); e != g.particles.end(k); ++e) {
      const int p = *e;
      EXPECT_EQ(g.groupOf[size_t(p)], k);
      const std::vector<int> own(b.particleClusters.begin() + b.particleStart[size_t(p)],
                                 b.particleClusters.begin() + b.particleStart[size_t(p) + 1]);
      EXPECT_EQ(own, clusters) << "particle " << p;
    }
  }
  for (size_t c = 0; c < b.lists.size(); ++c) {
    std::set<int> fromGroups;
    for (const int* e = g.clusterGroups.begin(int(c)); e != g.clusterGroups.end(int(c)); ++e)
      fromGroups.insert(g.particles.begin(*e), g.particles.end(*e));
    EXPECT_EQ(fromGroups, std::set<int>(b.lists[c].begin(), b.lists[c].end())) << "cluster " << c;
  }
}

TEST(ParticleGroups, NoGroupsWhenParticlesDoNotShareTheirClusters) {
  // Tetrahedra of a strip: nearly every particle has its own set of clusters.
  Body b;
  b.n = 40;
  for (int a = 0; a < 3; ++a) b.r[a].assign(40, 0.0f);
  b.w.assign(40, 1.0f);
  std::vector<std::vector<int>> byParticle(40);
  for (int c = 0; c + 3 < 40; ++c)
    for (int p = c; p < c + 4; ++p) byParticle[size_t(p)].push_back(c);
  b.particleStart.push_back(0);
  for (const auto& l : byParticle) {
    b.particleClusters.insert(b.particleClusters.end(), l.begin(), l.end());
    b.particleStart.push_back(static_cast<int>(b.particleClusters.size()));
  }
  b.lists.resize(37);
  EXPECT_TRUE(groupsOf(b).empty());
}

TEST(ParticleGroups, ClusterMomentsFromGroupsEqualTheDirectSum) {
  const Body b = gridBody();
  const ParticleGroups g = groupsOf(b);
  ParticleColumns cols{{b.x[0].data(), b.x[1].data(), b.x[2].data()},
                       {b.r[0].data(), b.r[1].data(), b.r[2].data()},
                       b.w.data()};
  for (int a = 0; a < 3; ++a) cols.memberQ[a] = g.memberRest.col(a).data();
  cols.memberW = g.memberWeight.data();
  std::vector<ClusterMoments> groupMoments(size_t(g.count()));
  std::vector<Eigen::Vector3f> groupRef(size_t(g.count()));
  for (int k = 0; k < g.count(); ++k) {
    const int first = *g.particles.begin(k);
    groupRef[size_t(k)] =
        Eigen::Vector3f(b.x[0][size_t(first)], b.x[1][size_t(first)], b.x[2][size_t(first)]);
    groupMoments[size_t(k)] = accumulateMoments(
        cols, g.particles.items.data(), g.particles.start[size_t(k)],
        g.particles.start[size_t(k) + 1], groupRef[size_t(k)], g.restCentre[size_t(k)], false);
  }
  for (size_t c = 0; c < b.lists.size(); ++c) {
    // Reference point and rest centre of the cluster, as the World would have them.
    Vec3 xc = Vec3::Zero(), rcd = Vec3::Zero();
    double mass = 0;
    for (int p : b.lists[c]) {
      const double w = b.w[size_t(p)];
      xc += w * Vec3(b.x[0][size_t(p)], b.x[1][size_t(p)], b.x[2][size_t(p)]);
      rcd += w * Vec3(b.r[0][size_t(p)], b.r[1][size_t(p)], b.r[2][size_t(p)]);
      mass += b.w[size_t(p)];
    }
    const Eigen::Vector3f ref = (xc / mass + Vec3(0.01, -0.02, 0.005)).cast<float>();
    const Eigen::Vector3f rc = (rcd / mass).cast<float>();
    // Independent: every term in double, about the float reference point as the World has it.
    const Vec3 refD = widen(ref), rcD = widen(rc);
    Vec3 wd = Vec3::Zero();
    Mat3 wdq = Mat3::Zero();
    for (int p : b.lists[c]) {
      const Vec3 d = Vec3(b.x[0][size_t(p)], b.x[1][size_t(p)], b.x[2][size_t(p)]) - refD;
      const Vec3 q = Vec3(b.r[0][size_t(p)], b.r[1][size_t(p)], b.r[2][size_t(p)]) - rcD;
      const double w = b.w[size_t(p)];  // (a float factor would make Eigen sum in float)
      wd += w * d;
      wdq += w * d * q.transpose();
    }
    const ClusterMoments m = clusterMomentsFromGroups(g, static_cast<int>(c), groupMoments.data(),
                                                      groupRef.data(), ref, rc);
    // Float sums of offsets within a cell (~0.3 m) and double shifts: errors ~1e-7 of the size
    // of the terms, although the points are 100 m from the origin.
    const double scale = mass * 0.5 * 0.5;
    EXPECT_LT((m.wdq - wdq).norm(), 1e-6 * scale) << "cluster " << c;
    EXPECT_LT((m.wd - wd).norm(), 1e-6 * mass) << "cluster " << c;
  }
}

}  // namespace
}  // namespace sb
