// colliderDistanceLowerBound: what lets the Contacts phase skip a body's per-particle tests
// against colliders its box is far from. It must never exceed the distance of any point of the
// box (a skipped collider would then miss a contact), and it must be tight enough to skip.
// exposedColliderDistance: contacts only with the parts of a collider not buried in another.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sim/world/collider.h"
#include "tests/sim/test_util.h"

namespace sb {
namespace {

using test::drawVector;

std::vector<Collider> someColliders(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), size(0.05, 1.5);
  auto vec = [&](std::uniform_real_distribution<double>& d) {
    return drawVector<Vec3>([&] { return d(rng); });
  };
  std::vector<Collider> out;
  out.push_back(Collider::plane(vec(u), u(rng)));
  out.push_back(Collider::box(vec(u), vec(size), test::randomRotation(rng)));
  out.push_back(Collider::box(vec(u), Vec3(0.1, 1.5, 3.2), Mat3::Identity()));  // a pen's wall
  out.push_back(Collider::sphere(vec(u), size(rng)));
  out.push_back(Collider::capsule(vec(u), vec(u), size(rng)));
  return out;
}

// Over random boxes (some far, some reaching into the collider) and random colliders of every
// shape: no point of the box — its corners, its centre, random points inside — is closer than
// the bound, and for a plane the bound is the lowest corner's distance.
TEST(ColliderBound, NeverAbovePointsOfTheBox) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
  int positive = 0, cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double spread = trial % 2 ? 1.0 : 4.0;  // half the boxes far out
    const Vec3 a = spread * drawVector<Vec3>([&] { return u(rng); });
    const Vec3 b = a + 0.6 * drawVector<Vec3>([&] { return unit(rng); });
    const Eigen::AlignedBox3d box(a, b);
    for (const Collider& c : someColliders(rng)) {
      const double bound = colliderDistanceLowerBound(c, box);
      ++cases;
      if (bound > 0.0) ++positive;
      double lowest = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 8; ++k) {
        Vec3 n;
        const Vec3 corner = box.corner(Eigen::AlignedBox3d::CornerType(k));
        const double d = colliderDistance(c, corner, &n);
        lowest = std::min(lowest, d);
        ASSERT_GE(d, bound - 1e-12) << colliderShapeName(c.shape) << " corner " << k;
      }
      for (int k = 0; k < 64; ++k) {
        const Vec3 t = drawVector<Vec3>([&] { return unit(rng); });
        const Vec3 p = box.min() + t.cwiseProduct(box.sizes());
        Vec3 n;
        ASSERT_GE(colliderDistance(c, p, &n), bound - 1e-12) << colliderShapeName(c.shape);
      }
      if (c.shape == Collider::Shape::Plane) {
        EXPECT_NEAR(bound, lowest, 1e-12);
      }
    }
  }
  // Tight enough to be of use: far boxes are ruled out for most colliders.
  EXPECT_GT(positive, cases / 4) << positive << " of " << cases;
}

// A thin wall (the pens of the shipped scenes): a box beside it is ruled out by its gap along
// the wall's normal, exactly, though the wall's bounding sphere (radius 3.5 m) holds it.
TEST(ColliderBound, WallBoundIsTheGapAlongItsNormal) {
  const Collider wall = Collider::box(Vec3(3.1, 1.5, 0.0), Vec3(0.1, 1.5, 3.2), Mat3::Identity());
  const Eigen::AlignedBox3d body(Vec3(1.0, 0.0, -0.5), Vec3(1.5, 0.5, 0.5));
  EXPECT_NEAR(colliderDistanceLowerBound(wall, body), 3.0 - 1.5, 1e-12);
  // Turned 90° about y, the wall's thin axis is world z: it spans z 0.9 … 1.1 and overlaps the
  // body in x and y; the body (z ≤ 0.5) is 0.4 m from it.
  const Mat3 turn = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).toRotationMatrix();
  const Collider across = Collider::box(Vec3(1.25, 1.5, 1.0), Vec3(0.1, 1.5, 3.2), turn);
  EXPECT_NEAR(colliderDistanceLowerBound(across, body), 1.0 - 0.1 - 0.5, 1e-12);
  // Touching or overlapping: nothing to rule out.
  const Eigen::AlignedBox3d touching(Vec3(2.9, 0.0, -0.5), Vec3(3.05, 0.5, 0.5));
  EXPECT_LE(colliderDistanceLowerBound(wall, touching), 0.0);
}

// A ramp whose lower end is sunk into the floor (slope.json's 40° ramp). A particle at its foot,
// a little inside it and nearer its sunk end face than its top, is pushed out through the top:
// up and away from the ramp, not down into the floor. Alone (no floor), the end face is its way
// out, as colliderDistance says.
TEST(ExposedColliderDistance, LeavesARampSunkIntoTheFloorThroughItsTop) {
  const Mat3 tilt = Eigen::AngleAxisd(40 * M_PI / 180, Vec3::UnitZ()).toRotationMatrix();
  const Collider ramp = Collider::box(Vec3(0, 0.887577, 0), Vec3(1.5, 0.1, 0.4), tilt);
  const std::vector<Collider> scene = {Collider::plane(Vec3::UnitY(), 0.0), ramp};
  const Vec3 top = tilt.col(1), end = -tilt.col(0);
  const Vec3 foot = ramp.centre + 0.1 * top + 1.5 * end;  // where the top meets the end face
  ASSERT_NEAR(foot.y(), 0.0, 1e-3);
  const Vec3 p = foot - 0.0003 * top - 0.0002 * end;  // 0.3 mm below the top, 0.2 mm in the end
  Vec3 n;
  ASSERT_NEAR(colliderDistance(ramp, p, &n), -0.0002, 1e-9);
  ASSERT_NEAR(n.dot(end), 1.0, 1e-12);  // alone: out through the end face, down (n.y −0.64)
  double d;
  ASSERT_TRUE(exposedColliderDistance(scene, 1, p, &d, &n));
  EXPECT_NEAR(d, -0.0003, 1e-9);
  EXPECT_NEAR(n.dot(top), 1.0, 1e-12);
  EXPECT_GT(n.y(), 0.0);
  ASSERT_TRUE(exposedColliderDistance({ramp}, 0, p, &d, &n));
  EXPECT_NEAR(n.dot(end), 1.0, 1e-12);
}

// A wall standing in the floor: a particle pressed 0.1 mm into the floor and 0.1 mm into the
// wall's side still meets the side (its exit is no deeper in the floor than the particle), and
// the floor's contact is untouched.
TEST(ExposedColliderDistance, KeepsAWallsSideForAParticlePressedIntoTheFloor) {
  const Collider wall = Collider::box(Vec3(1.1, 1.0, 0), Vec3(0.1, 1.2, 2.0), Mat3::Identity());
  const std::vector<Collider> scene = {Collider::plane(Vec3::UnitY(), 0.0), wall};
  const Vec3 p(1.0001, -0.0001, 0.3);
  double d;
  Vec3 n;
  ASSERT_TRUE(exposedColliderDistance(scene, 1, p, &d, &n));
  EXPECT_NEAR(d, -0.0001, 1e-9);
  EXPECT_NEAR(n.x(), -1.0, 1e-12);
  ASSERT_TRUE(exposedColliderDistance(scene, 0, p, &d, &n));
  EXPECT_NEAR(d, -0.0001, 1e-12);
  EXPECT_NEAR(n.y(), 1.0, 1e-12);
}

// A box sunk wholly under the floor has no surface a particle above the floor can meet; a
// sphere half sunk keeps its upper half, down to the floor.
TEST(ExposedColliderDistance, BuriedPartsMakeNoContact) {
  const Collider plank = Collider::box(Vec3(0, -0.3, 0), Vec3(1, 0.1, 1), Mat3::Identity());
  const Collider ball = Collider::sphere(Vec3(3, 0, 0), 0.5);
  const std::vector<Collider> scene = {Collider::plane(Vec3::UnitY(), 0.0), plank, ball};
  double d;
  Vec3 n;
  EXPECT_FALSE(exposedColliderDistance(scene, 1, Vec3(0.2, 0.001, 0.1), &d, &n));
  ASSERT_TRUE(exposedColliderDistance(scene, 2, Vec3(3.6, 0.1, 0), &d, &n));
  EXPECT_GT(n.y(), 0.0);
  ASSERT_TRUE(exposedColliderDistance(scene, 2, Vec3(3.52, 0.001, 0), &d, &n));  // at its foot
  EXPECT_NEAR(d, 0.02, 1e-4);
}

}  // namespace
}  // namespace sb
