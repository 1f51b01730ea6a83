// World API: validation with field names, handles, run-time changes, reset.
#include <gtest/gtest.h>

#include "test_util.h"

namespace sb {
namespace {

using test::jitteredGrid;
using test::noGravity;

void expectInvalid(const std::function<void()>& f, const std::string& field) {
  try {
    f();
    FAIL() << "no error for " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(WorldApi, RejectsBadBodiesNamingTheFieldAndStaysUnchanged) {
  World world;
  BodyDef good;
  good.positions = jitteredGrid(2, 1.0, Vec3::Zero(), 1);
  world.addBody(good);
  const std::uint64_t before = world.stateHash();
  BodyDef bad = good;
  bad.params.alpha = 1.5;
  expectInvalid([&] { world.addBody(bad); }, "alpha");
  bad = good;
  bad.params.beta = std::nan("");
  expectInvalid([&] { world.addBody(bad); }, "beta");
  bad = good;
  bad.positions[3].y() = INFINITY;
  expectInvalid([&] { world.addBody(bad); }, "positions[3]");
  bad = good;
  bad.masses = {1.0, 2.0};
  expectInvalid([&] { world.addBody(bad); }, "masses");
  bad = good;
  bad.pinned = {42};
  expectInvalid([&] { world.addBody(bad); }, "pinned");
  bad = good;
  bad.clusters.kind = ClusterDef::Kind::Grid;
  bad.clusters.cellSize = 0.0;
  expectInvalid([&] { world.addBody(bad); }, "clusters.cellSize");
  bad = good;
  bad.params.plasticity.creep = -1;
  expectInvalid([&] { world.addBody(bad); }, "plasticity.creep");
  EXPECT_EQ(world.bodies().size(), 1u);
  EXPECT_EQ(world.stateHash(), before);
  WorldSettings s;
  s.substeps = 0;
  expectInvalid([&] { world.setSettings(s); }, "substeps");
  s = WorldSettings{};
  s.timeStep = -1;
  expectInvalid([&] { world.setSettings(s); }, "timeStep");
  for (double badStep : {0.0, 5e-5, 11.0, std::nan("")}) {
    s = WorldSettings{};
    s.maxSubstep = badStep;
    expectInvalid([&] { world.setSettings(s); }, "maxSubstep");
  }
  expectInvalid([&] { world.step(std::nan("")); }, "dt");
  EXPECT_EQ(world.stateHash(), before);
}

// A step longer than substeps × maxSubstep runs ceil(dt / maxSubstep) equal sub-steps: the same
// bits as asking for that many sub-steps (a body landing on a floor with friction, so gravity,
// contact and friction all see the sub-step).
TEST(WorldApi, LongStepsRunSubstepsOfAtMostMaxSubstep) {
  WorldSettings split;  // maxSubstep 1/120 s by default
  split.timeStep = 0.1;
  World world(split);
  EXPECT_EQ(world.substepsFor(0.1), 12);
  EXPECT_EQ(world.substepsFor(1.0 / 60), 2);
  EXPECT_EQ(world.substepsFor(0.016666667), 2);  // as scene files write 1/60
  EXPECT_EQ(world.substepsFor(1.0 / 120), 1);
  EXPECT_EQ(world.substepsFor(0.0083333334), 1);
  EXPECT_EQ(world.substepsFor(0.009), 2);
  EXPECT_EQ(world.substepsFor(10.0), 1200);
  split.substeps = 16;
  world.setSettings(split);
  EXPECT_EQ(world.substepsFor(0.1), 16);  // more sub-steps than needed are kept
  split.substeps = 1;
  world.setSettings(split);

  WorldSettings exact = split;
  exact.substeps = 12;
  exact.maxSubstep = limits::maxSubstep.hi;
  World reference(exact);
  BodyDef def;
  def.positions = jitteredGrid(3, 0.5, Vec3(0, 0.6, 0), 3);
  def.params.mode = Mode::Linear;
  def.params.alpha = 0.7;
  for (World* w : {&world, &reference}) {
    w->addCollider(Collider::plane(Vec3::UnitY(), 0.0, 0.6));
    w->addBody(def);
  }
  for (int step = 0; step < 30; ++step) {
    world.step();
    reference.step();
  }
  EXPECT_EQ(world.stateHash(), reference.stateHash());
  EXPECT_DOUBLE_EQ(world.time(), reference.time());
  EXPECT_GT(world.positions(world.bodies()[0]).col(1).minCoeff(), -0.01);  // it landed
  EXPECT_LT(world.positions(world.bodies()[0]).col(1).minCoeff(), 0.1);
}

TEST(WorldApi, HandlesBecomeInvalidWhenBodiesAreRemoved) {
  World world;
  BodyDef def;
  def.positions = jitteredGrid(2, 1.0, Vec3::Zero(), 1);
  const BodyHandle a = world.addBody(def);
  const BodyHandle b = world.addBody(def);
  world.removeBody(a);
  EXPECT_FALSE(world.contains(a));
  EXPECT_TRUE(world.contains(b));
  const BodyHandle c = world.addBody(def);  // reuses the slot with a new generation
  EXPECT_EQ(c.index, a.index);
  EXPECT_NE(c, a);
  EXPECT_THROW(world.positions(a), std::invalid_argument);
  // A force or drag queued for a body that is then removed is dropped with it.
  world.addForce(b, 0, Vec3(1, 0, 0));
  DragDef drag;
  drag.body = b;
  drag.particles = {0};
  drag.weights = {1.0};
  world.addDrag(drag);
  world.removeBody(b);
  EXPECT_NO_THROW(world.step());
  const BodyHandle d = world.addBody(def);
  EXPECT_EQ(world.bodies().size(), 2u);
  EXPECT_TRUE(world.contains(c) && world.contains(d));
}

TEST(WorldApi, ModeParamsAndClustersChangeAtRunTime) {
  World world(noGravity(0.01));
  BodyDef def;
  def.positions = jitteredGrid(5, 1.0, Vec3::Zero(), 2);
  const BodyHandle b = world.addBody(def);
  Eigen::MatrixX3d x = test::toMatrix(def.positions);
  x.col(0) *= 1.3;
  world.setState(b, x, Eigen::MatrixX3d::Zero(x.rows(), 3));
  for (int s = 0; s < 10; ++s) world.step();
  BodyParams p = world.params(b);
  p.mode = Mode::Quadratic;
  p.alpha = 0.9;
  world.setParams(b, p);
  ClusterDef clusters;
  clusters.kind = ClusterDef::Kind::Grid;
  clusters.cellSize = 0.4;
  clusters.overlap = 0.2;
  const Eigen::MatrixX3d before = world.positions(b).cast<double>();
  world.setClusters(b, clusters);
  EXPECT_GT(world.clusterCount(b), 4);
  EXPECT_EQ(Eigen::MatrixX3d(world.positions(b).cast<double>()), before);  // positions kept
  for (int s = 0; s < 10; ++s) world.step();
  EXPECT_TRUE(world.positions(b).allFinite());
  clusters.cellSize = -2;
  EXPECT_THROW(world.setClusters(b, clusters), std::invalid_argument);
  EXPECT_GT(world.clusterCount(b), 4);  // unchanged after the failed rebuild
  p.alpha = -0.1;
  EXPECT_THROW(world.setParams(b, p), std::invalid_argument);
  EXPECT_EQ(world.params(b).alpha, 0.9);
}

TEST(WorldApi, ResetRestoresTheStartExactly) {
  WorldSettings settings;
  World world(settings);
  world.addCollider(Collider::plane(Vec3::UnitY(), -1.0));
  BodyDef def;
  def.positions = jitteredGrid(3, 1.0, Vec3::Zero(), 2);
  def.params.plasticity = {0.01, 5.0, 0.5};
  const BodyHandle b = world.addBody(def);
  const std::uint64_t start = world.stateHash();
  for (int s = 0; s < 100; ++s) world.step();
  EXPECT_NE(world.stateHash(), start);
  world.reset();
  EXPECT_EQ(world.stateHash(), start);
  EXPECT_EQ(world.time(), 0.0);
  for (int s = 0; s < 100; ++s) world.step();
  const std::uint64_t after = world.stateHash();
  world.reset();
  for (int s = 0; s < 100; ++s) world.step();
  EXPECT_EQ(world.stateHash(), after);  // replay is exact
  (void)b;
}

TEST(WorldApi, DragPullsTheGrabbedPointTowardTheTarget) {
  World world(noGravity(1.0 / 60));
  BodyDef def;
  def.positions = jitteredGrid(3, 1.0, Vec3::Zero(), 2);
  def.params.alpha = 0.3;
  const BodyHandle b = world.addBody(def);
  DragDef drag;
  drag.body = b;
  drag.particles = {0, 1};
  drag.weights = {0.5, 0.5};
  drag.target = Vec3(0, 3, 0);
  drag.stiffness = 0.2;
  const int id = world.addDrag(drag);
  for (int s = 0; s < 120; ++s) world.step();
  const Eigen::MatrixX3d x = world.positions(b).cast<double>();
  const Vec3 point = 0.5 * (x.row(0) + x.row(1)).transpose();
  EXPECT_LT((point - drag.target).norm(), 0.5);
  EXPECT_GT(world.centreOfMass(b).y(), 1.0);  // the body came along
  world.removeDrag(id);
  drag.weights = {0.0, 0.0};
  EXPECT_THROW(world.addDrag(drag), std::invalid_argument);
}

}  // namespace
}  // namespace sb

namespace sb {
namespace {

// A rigid cube resting on the floor: each sub-step predicts every particle g·h² further down
// (from rest), and the floor's contacts catch it, so the deepest contact as detected is g·h²
// (± the contact gap, a small share of the spacing); in the air there is none.
TEST(WorldApi, DeepestContactIsWhatGravityPredictsIntoTheFloorPerSubstep) {
  for (double h : {1.0 / 240, 1.0 / 60}) {
    WorldSettings settings = test::exactSubsteps(h);
    settings.sleep = false;
    World world(settings);
    world.addCollider(Collider::plane(Vec3::UnitY(), 0.0));
    BodyDef def;
    def.positions = test::jitteredGrid(4, 0.4, Vec3(0, 0.5, 0), 1);
    def.params.mode = Mode::Rigid;
    def.params.alpha = 1.0;
    const BodyHandle b = world.addBody(def);
    world.step();
    EXPECT_EQ(world.lastDeepestContact(), 0.0) << "in the air";
    for (int s = 0; s < int(3.0 / h); ++s) world.step();
    ASSERT_LT(world.positions(b).col(1).minCoeff(), 0.01);  // landed
    const double expected = 9.81 * h * h;
    EXPECT_GT(world.lastDeepestContact(), 0.5 * expected) << h;
    EXPECT_LT(world.lastDeepestContact(), 2.0 * expected) << h;
    std::printf("[ world    ] h %.4f s: deepest contact %.3g mm, g h^2 %.3g mm\n", h,
                1e3 * world.lastDeepestContact(), 1e3 * expected);
  }
}

}  // namespace
}  // namespace sb
