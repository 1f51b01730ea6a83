// Interior lattice points (sim/cage/interior_points.h): the counts a box gives in closed form,
// every point inside a non-convex shape and clear of its surface (checked against the shape's
// own inside test and distances), and bad spacings refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "sim/cage/interior_points.h"
#include "tests/mesh/mesh_fixtures.h"

namespace sb::cage {
namespace {

using mesh::testing::Vec3;

TEST(InteriorLattice, BoxCountsInClosedForm) {
  // Unit box at the origin: the lattice is centred on (0.5, 0.5, 0.5).
  const mesh::TriangleMesh box = mesh::testing::makeBox(3, 3, 3);
  // Spacing 0.3: offsets −0.3, 0, 0.3 per axis, each 0.2 ≥ 0.15 from the faces: 27 points.
  const auto p = interiorLattice(box, 0.3);
  ASSERT_EQ(p.size(), 27u);
  EXPECT_LT((p.front() - Vec3(0.2, 0.2, 0.2)).norm(), 1e-12);  // x fastest, then y, then z
  EXPECT_LT((p[1] - Vec3(0.5, 0.2, 0.2)).norm(), 1e-12);
  EXPECT_LT((p.back() - Vec3(0.8, 0.8, 0.8)).norm(), 1e-12);
  // Spacing 0.45: offsets ±0.45 are 0.05 from the faces (< 0.225): only the centre is kept.
  const auto one = interiorLattice(box, 0.45);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_LT((one[0] - Vec3(0.5, 0.5, 0.5)).norm(), 1e-12);
  // Spacing above the box: no point but the centre, which is 0.5 from the faces (< 0.6).
  EXPECT_TRUE(interiorLattice(box, 1.2).empty());
}

TEST(InteriorLattice, PointsAreInsideANonConvexShapeAndClearOfIt) {
  const mesh::TriangleMesh l = mesh::testing::makeLShape();  // [0,2]×[0,1] ∪ [0,1]×[0,2], z [0,1]
  const double s = 0.125;
  const auto points = interiorLattice(l, s);
  ASSERT_GT(points.size(), 100u);
  for (const Vec3& p : points) {
    EXPECT_TRUE(mesh::testing::insideLShape(p)) << p.transpose();
    // Clear of every face by s/2: the L's faces are the planes z = 0, 1 and the outline.
    EXPECT_GE(std::min(p.z(), 1.0 - p.z()), 0.5 * s - 1e-12);
    EXPECT_GE(std::min(p.x(), p.y()), 0.5 * s - 1e-12);
    EXPECT_FALSE(p.x() > 1.0 - 0.5 * s + 1e-12 && p.y() > 1.0 - 0.5 * s + 1e-12) << p.transpose();
  }
  // And every lattice point that is inside and clear is there: count them from the L's outline
  // (lattice offsets are multiples of s from the box centre (1, 1, 0.5), so no distance ties).
  const std::array<Eigen::Vector2d, 6> outline = {Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 0),
                                                  Eigen::Vector2d(2, 1), Eigen::Vector2d(1, 1),
                                                  Eigen::Vector2d(1, 2), Eigen::Vector2d(0, 2)};
  size_t expected = 0;
  for (int k = -4; k <= 4; ++k)
    for (int j = -8; j <= 8; ++j)
      for (int i = -8; i <= 8; ++i) {
        const Vec3 p(1 + i * s, 1 + j * s, 0.5 + k * s);
        if (!mesh::testing::insideLShape(p)) continue;
        double clear = std::min(p.z(), 1.0 - p.z());
        for (size_t e = 0; e < outline.size(); ++e) {
          const Eigen::Vector2d a = outline[e], b = outline[(e + 1) % outline.size()];
          const Eigen::Vector2d q(p.x(), p.y());
          const double t = std::clamp((q - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
          clear = std::min(clear, (q - (a + t * (b - a))).norm());
        }
        expected += clear >= 0.5 * s;
      }
  EXPECT_EQ(points.size(), expected);
}

TEST(InteriorLattice, BadSpacingIsRefused) {
  const mesh::TriangleMesh box = mesh::testing::makeBox(1, 1, 1);
  for (double bad : {0.0, -1.0, std::nan(""), double(INFINITY)}) {
    EXPECT_THROW(interiorLattice(box, bad), std::invalid_argument) << bad;
  }
  try {
    interiorLattice(box, 1e-3);  // 1001³ lattice points
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("spacing"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sb::cage
