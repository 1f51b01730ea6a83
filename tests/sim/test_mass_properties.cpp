// Rigid motion of weighted points (sim/world/mass_properties.h): the fitted motion against a
// rigid velocity field it must recover, and the threaded variant against the serial one, bit for
// bit; a large body stepped at one and two threads (the per-particle passes split inside a body).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

#include "sim/base/parallel.h"
#include "sim/world/mass_properties.h"
#include "test_util.h"

namespace sb {
namespace {

// Float columns of `count` random points in a box far from the origin, with masses, and the
// velocities of a rigid motion vc + ω × (x − c) about the points' centre c.
struct Cloud {
  std::vector<float> x[3], v[3], mass;
  Vec3 centre = Vec3::Zero(), velocity = Vec3(0.3, -1.2, 0.7), omega = Vec3(2.0, -0.5, 1.5);

  explicit Cloud(int count, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0), m(0.5, 2.0);
    for (auto& c : x) c.resize(size_t(count));
    for (auto& c : v) c.resize(size_t(count));
    mass.resize(size_t(count));
    double total = 0;
    for (int i = 0; i < count; ++i) {
      const Vec3 p = Vec3(100, -50, 20) + test::drawVector<Vec3>([&] { return u(rng); });
      for (int a = 0; a < 3; ++a) x[a][size_t(i)] = float(p[a]);
      mass[size_t(i)] = float(m(rng));
      total += mass[size_t(i)];
      centre += double(mass[size_t(i)]) * Vec3(x[0][size_t(i)], x[1][size_t(i)], x[2][size_t(i)]);
    }
    centre /= total;
    for (int i = 0; i < count; ++i) {
      const Vec3 r = Vec3(x[0][size_t(i)], x[1][size_t(i)], x[2][size_t(i)]) - centre;
      const Vec3 vi = velocity + omega.cross(r);
      for (int a = 0; a < 3; ++a) v[a][size_t(i)] = float(vi[a]);
    }
  }
  PointColumns positions() const { return {{x[0].data(), x[1].data(), x[2].data()}}; }
  PointColumns velocities() const { return {{v[0].data(), v[1].data(), v[2].data()}}; }
};

bool sameBits(const RigidMotion& a, const RigidMotion& b) {
  return std::memcmp(a.centre.data(), b.centre.data(), sizeof(Vec3)) == 0 &&
         std::memcmp(a.velocity.data(), b.velocity.data(), sizeof(Vec3)) == 0 &&
         std::memcmp(a.omega.data(), b.omega.data(), sizeof(Vec3)) == 0 &&
         std::memcmp(a.angularMomentum.data(), b.angularMomentum.data(), sizeof(Vec3)) == 0 &&
         std::memcmp(a.inverseInertia.data(), b.inverseInertia.data(), sizeof(Mat3)) == 0;
}

TEST(RigidMotion, RecoversARigidVelocityField) {
  const Cloud cloud(5000, 7);
  const RigidMotion rm =
      rigidMotion(cloud.positions(), cloud.velocities(), cloud.mass.data(), 5000);
  // The oracle works in double on the same float inputs; the fit sums offsets (≤ 2 m) from the
  // first point in float lanes: a few float roundings (6e-8 relative) of those offsets.
  EXPECT_LT((rm.centre - cloud.centre).norm(), 1e-6);
  EXPECT_LT((rm.velocity - cloud.velocity).norm(), 1e-5);
  EXPECT_LT((rm.omega - cloud.omega).norm(), 1e-4);
}

// Counts around the block size and above the threshold from which the threaded variant forks.
TEST(RigidMotion, OnThreadsHasTheSerialBits) {
  for (int count : {1, 511, 512, 513, 40000, 100003}) {
    const Cloud cloud(count, 11 + unsigned(count));
    const RigidMotion serial =
        rigidMotion(cloud.positions(), cloud.velocities(), cloud.mass.data(), count);
    for (int threads : {1, 2}) {
      setThreadCount(threads);
      const RigidMotion threaded =
          rigidMotionOnThreads(cloud.positions(), cloud.velocities(), cloud.mass.data(), count);
      EXPECT_TRUE(sameBits(serial, threaded)) << count << " points, " << threads << " threads";
    }
    setThreadCount(0);
  }
}

// Summed where a sweep passes (the Project phase): blocks added in any order, in pieces of
// several blocks, the last partial; the same bits as the one pass.
TEST(RigidMotion, SummedByBlocksInAnyOrderHasTheSerialBits) {
  for (int count : {1, 511, 512, 4097, 10000}) {
    const Cloud cloud(count, 31 + unsigned(count));
    const RigidMotion serial =
        rigidMotion(cloud.positions(), cloud.velocities(), cloud.mass.data(), count);
    const float origin[3] = {cloud.x[0][0], cloud.x[1][0], cloud.x[2][0]};
    RigidMotionSums sums;
    startRigidMotionSums(sums, origin, count);
    const int piece = 4 * kRigidMotionBlock;
    for (int begin = (count - 1) / piece * piece; begin >= 0; begin -= piece)
      sumRigidMotionBlocks(cloud.positions(), cloud.velocities(), cloud.mass.data(), begin,
                           std::min(count, begin + piece), sums);
    EXPECT_TRUE(sameBits(serial, rigidMotionOf(sums))) << count << " points";
  }
}

// One body large enough that its per-particle passes and rigid-motion sums split over threads,
// spinning (the turned prediction and the spin correction run), damped, on a floor: the same
// state bits at one and two threads.
TEST(RigidMotion, LargeBodyBitIdenticalAtOneAndTwoThreads) {
  auto run = [](int threads) {
    setThreadCount(threads);
    WorldSettings settings;
    settings.timeStep = 1.0 / 60;
    settings.substeps = 2;
    settings.sleep = false;
    World world(settings);
    world.addCollider(Collider::plane(Vec3::UnitY(), 0.0));
    BodyDef def;
    def.positions = test::jitteredGrid(36, 0.6, Vec3(0, 0.35, 0), 5);  // 36³ = 46,656 particles
    def.params.mode = Mode::Linear;
    def.params.alpha = 0.4;
    def.params.damping = 0.01;
    const BodyHandle b = world.addBody(def);
    Eigen::MatrixX3d x = test::toDouble(world.positions(b));
    const Vec3 c = x.colwise().mean().transpose();
    Eigen::MatrixX3d v(x.rows(), 3);
    for (int i = 0; i < x.rows(); ++i)
      v.row(i) = Vec3(0, 6.0, 0).cross(x.row(i).transpose() - c).transpose();
    world.setState(b, x, v);
    for (int s = 0; s < 40; ++s) world.step();
    setThreadCount(0);
    return world.stateHash();
  };
  EXPECT_EQ(run(1), run(2));
}

}  // namespace
}  // namespace sb
