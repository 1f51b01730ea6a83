// Every scene shipped in assets/scenes runs headless for a few seconds of simulated time without
// NaN, stays above the colliders and out of the other bodies, and comes to rest; the scenes
// that show a feature (plasticity, clusters, a pile, a large scene) show it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "scene_checks.h"
#include "sim/cage/embedding.h"
#include "sim/world/matching/plasticity.h"
#include "sim/scene/scene.h"

// CI also runs the suite under AddressSanitizer (SOFTBODY_SANITIZE adds -fsanitize=address, which
// GCC announces with __SANITIZE_ADDRESS__ and Clang through __has_feature).
#if defined(__SANITIZE_ADDRESS__)
#define SB_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SB_TEST_SANITIZED 1
#endif
#endif
#ifndef SB_TEST_SANITIZED
#define SB_TEST_SANITIZED 0
#endif

namespace sb {
namespace {

namespace fs = std::filesystem;
const std::string kSceneDir = std::string(SOFTBODY_ASSET_DIR) + "/scenes";

// Every scene file shipped, sorted so the test names are stable; a new file is covered without
// touching this test.
std::vector<std::string> shippedSceneNames() {
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(kSceneDir))
    if (e.is_regular_file() && e.path().extension() == ".json")
      names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string scenePath(const std::string& name) {
  return kSceneDir + "/" + name + ".json";
}

// How long a scene runs before the end checks, and whether it must be at rest by then. Shape
// matching bodies on the floor rock and creep for seconds after landing (also with bodyContact
// off, so not a contact effect), so each scene runs until it has measurably settled: about 1.2×
// the last moment (measured, in parentheses) any particle still moved more than 1e-3 of its
// body's diagonal per step. A new scene gets 10 s and must settle.
struct RunLength {
  double seconds = 10.0;
  bool mustRest = true;
};

RunLength runLengthOf(const std::string& name) {
  static const std::map<std::string, RunLength> special = {
      {"default", {12.0, true}},    // (10.7 s)
      {"plasticity", {7.0, true}},  // (5.0 s)
      {"clusters", {10.0, true}},   // (7.7 s)
      // Under AddressSanitizer (about 15× slower here) the 12-body pile runs 3 s without the
      // rest check: the results are bit-identical to the normal build, which checks the physics;
      // the sanitizer build is there for memory and undefined-behaviour errors.
      {"pile", {SB_TEST_SANITIZED ? 3.0 : 13.0, !SB_TEST_SANITIZED}},  // (10.1 s)
      // 54 bodies still move by more than 1e-3 of a diagonal per step after 14 s (13 s of CPU),
      // so the performance scene is checked while it moves: 3 s covers the fall and the first
      // contacts of all three layers. Under AddressSanitizer 1 s (the first layer lands; 15 s).
      {"large", {SB_TEST_SANITIZED ? 1.0 : 3.0, false}},
  };
  const auto it = special.find(name);
  return it == special.end() ? RunLength{} : it->second;
}

int stepsFor(const Scene& scene, double seconds) {
  return int(std::lround(seconds / scene.world.settings().timeStep));
}

double maxPlasticNorm(const Scene& scene, int body) {
  const BodyHandle h = scene.bodies[size_t(body)].handle;
  double worst = 0.0;
  for (int c = 0; c < scene.world.clusterCount(h); ++c)
    worst = std::max(worst, spectralNorm(scene.world.plasticDeformation(h, c) - Mat3::Identity()));
  return worst;
}

double lowestY(const Scene& scene, int body) {
  return scene.world.positions(scene.bodies[size_t(body)].handle).col(1).minCoeff();
}
double highestY(const Scene& scene, int body) {
  return scene.world.positions(scene.bodies[size_t(body)].handle).col(1).maxCoeff();
}

// One step, then: no body was reset for NaN/Inf (the World reports that as an event) and every
// particle is finite.
void stepAndCheckFinite(Scene& scene, int step) {
  scene.world.step();
  const std::vector<WorldEvent> events = scene.world.takeEvents();
  ASSERT_TRUE(events.empty()) << "step " << step << ": " << events.front().message;
  for (const SceneBody& b : scene.bodies)
    ASSERT_TRUE(scene.world.positions(b.handle).allFinite())
        << "step " << step << ": body " << scene.world.name(b.handle);
}

class ShippedScene : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedScene, RunsHeadlessStaysOutOfCollidersAndBodiesAndSettles) {
  Scene scene = loadScene(scenePath(GetParam()));
  const int n = int(scene.bodies.size());
  ASSERT_GT(n, 0);

  // The scene file must place every body out of every other body and above the colliders.
  const test::Penetration initial = test::deepestPenetration(scene);
  EXPECT_EQ(initial.depth, 0.0) << "body " << initial.body << " starts inside body "
                                << initial.into;
  EXPECT_GT(test::lowestColliderClearance(scene).distance, 0.0);

  const RunLength length = runLengthOf(GetParam());
  const int steps = stepsFor(scene, length.seconds);
  for (int s = 0; s < steps; ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
  }

  // Static colliders: nothing deeper than 1 % of its particle spacing.
  const test::ColliderClearance floor = test::lowestColliderClearance(scene);
  EXPECT_GE(floor.relativeDistance, -0.01)
      << floor.distance << " m inside collider " << floor.collider << " (body " << floor.body
      << ", particle " << floor.particle << ")";

  // Other bodies: no particle deeper than 5 % of the smaller particle spacing of the two.
  const test::Penetration deepest = test::deepestPenetration(scene);
  EXPECT_LE(deepest.relativeDepth, 0.05)
      << "particle " << deepest.particle << " of body " << deepest.body << " is " << deepest.depth
      << " m inside body " << deepest.into;

  // At rest: the largest move over one more step, relative to the body's bounding-box diagonal.
  std::vector<Eigen::MatrixX3d> before(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    before[size_t(i)] = scene.world.positions(scene.bodies[size_t(i)].handle).cast<double>();
  stepAndCheckFinite(scene, steps);
  if (HasFatalFailure()) return;
  double jitter = 0.0;
  int jitterBody = -1;
  for (int i = 0; i < n; ++i) {
    const Eigen::MatrixX3d after =
        scene.world.positions(scene.bodies[size_t(i)].handle).cast<double>();
    const double move = (after - before[size_t(i)]).rowwise().norm().maxCoeff() /
                        test::boundingBoxDiagonal(scene, i);
    if (move > jitter) {
      jitter = move;
      jitterBody = i;
    }
  }
  if (length.mustRest) {
    EXPECT_LE(jitter, 1e-3) << "body " << jitterBody << " still moves after " << length.seconds
                            << " s";
  }

  std::printf(
      "[ scene    ] %s: %d bodies, %.1f s: lowest collider distance %.3g spacings, "
      "deepest penetration %.3g spacings (%.3g m), max move per step %.3g diagonals\n",
      GetParam().c_str(), n, length.seconds, floor.relativeDistance, deepest.relativeDepth,
      deepest.depth, jitter);
}

std::string testName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Shipped, ShippedScene, ::testing::ValuesIn(shippedSceneNames()), testName);

TEST(ShippedScenes, IncludeTheFiveDocumentedScenes) {
  const std::vector<std::string> names = shippedSceneNames();
  for (const char* expected : {"default", "plasticity", "clusters", "pile", "large"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
}

// Runs the plasticity scene for `seconds`; returns the plastic body's index (the one body with
// plasticity) and, through beforeImpact, its largest ‖Sᵖ − I‖ while no other body had yet come
// down to its top.
int runPlasticityScene(Scene& scene, double seconds, bool plasticityOn, double* beforeImpact) {
  int plastic = -1;
  for (int i = 0; i < int(scene.bodies.size()); ++i)
    if (scene.world.params(scene.bodies[size_t(i)].handle).plasticity.enabled()) {
      EXPECT_EQ(plastic, -1) << "one plastic body expected";
      plastic = i;
    }
  if (plastic < 0) {
    ADD_FAILURE() << "no plastic body";
    return -1;
  }
  if (!plasticityOn) {
    BodyParams p = scene.world.params(scene.bodies[size_t(plastic)].handle);
    p.plasticity.creep = 0.0;
    scene.world.setParams(scene.bodies[size_t(plastic)].handle, p);
  }
  bool hit = false;
  *beforeImpact = 0.0;
  for (int s = 0; s < stepsFor(scene, seconds); ++s) {
    stepAndCheckFinite(scene, s);
    if (::testing::Test::HasFatalFailure()) return -1;
    for (int i = 0; i < int(scene.bodies.size()); ++i)
      if (i != plastic && lowestY(scene, i) < highestY(scene, plastic)) hit = true;
    if (!hit) *beforeImpact = maxPlasticNorm(scene, plastic);
  }
  EXPECT_TRUE(hit) << "nothing came down onto the plastic body";
  return plastic;
}

// A plastic body hit by a heavier rigid one keeps a dent: after the impact a cluster's permanent
// deformation is well above zero (and above what the body's own landing caused), the settled
// body is visibly further from its rest shape than the same body without plasticity, and neither
// relaxes over another second.
TEST(ShippedScenes, PlasticityKeepsADentAfterTheImpact) {
  const double settled = runLengthOf("plasticity").seconds;
  Scene elastic = loadScene(scenePath("plasticity"));
  double unused = 0.0;
  const int elasticBody = runPlasticityScene(elastic, settled, false, &unused);
  if (HasFatalFailure() || elasticBody < 0) return;
  const double elasticDent = test::maxDeviationFromRigidFit(elastic, elasticBody);

  Scene scene = loadScene(scenePath("plasticity"));
  double beforeImpact = 0.0;
  const int plastic = runPlasticityScene(scene, settled, true, &beforeImpact);
  if (HasFatalFailure() || plastic < 0) return;
  const double atEnd = maxPlasticNorm(scene, plastic);
  const double dentAtEnd = test::maxDeviationFromRigidFit(scene, plastic);
  EXPECT_GT(atEnd, 0.1) << "largest ‖Sp − I‖ over the clusters";
  EXPECT_GT(atEnd, beforeImpact + 0.05) << "the dent must come from the impact";
  EXPECT_GT(dentAtEnd, 2.0 * elasticDent) << "no more visible than an elastic sag";

  for (int s = 0; s < stepsFor(scene, 1.0); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
  }
  const double later = maxPlasticNorm(scene, plastic);
  const double dentLater = test::maxDeviationFromRigidFit(scene, plastic);
  EXPECT_GT(later, 0.9 * atEnd);
  EXPECT_GT(dentLater, 0.9 * dentAtEnd);
  std::printf(
      "[ scene    ] plasticity: max |Sp - I| %.3f before impact, %.3f at %.0f s, %.3f a "
      "second later; deviation from rest shape %.3f m, %.3f m a second later, %.3f m "
      "without plasticity\n",
      beforeImpact, atEnd, settled, later, dentAtEnd, dentLater, elasticDent);
}

// The same mesh with the same parameters, one cluster vs many: the material is the same, so the
// body deforms about as much either way (the whole-body level carries the large-scale stiffness;
// the clusters add local detail), at rest and while landing.
TEST(ShippedScenes, ClusterCountDoesNotChangeTheStiffness) {
  Scene scene = loadScene(scenePath("clusters"));
  ASSERT_EQ(scene.bodies.size(), 2u);
  int stiff = 0, floppy = 1;
  if (scene.world.clusterCount(scene.bodies[0].handle) > 1) std::swap(stiff, floppy);
  const BodyHandle hs = scene.bodies[size_t(stiff)].handle;
  const BodyHandle hf = scene.bodies[size_t(floppy)].handle;
  ASSERT_EQ(scene.world.clusterCount(hs), 1);
  ASSERT_GE(scene.world.clusterCount(hf), 8);
  // Identical bodies apart from the clusters, so the difference is theirs.
  EXPECT_EQ(scene.bodies[0].meshPath, scene.bodies[1].meshPath);
  EXPECT_EQ(scene.bodies[0].scale, scene.bodies[1].scale);
  EXPECT_EQ(scene.bodies[0].rotationDegrees, scene.bodies[1].rotationDegrees);
  EXPECT_EQ(scene.world.mass(hs), scene.world.mass(hf));
  const BodyParams ps = scene.world.params(hs), pf = scene.world.params(hf);
  EXPECT_EQ(ps.mode, pf.mode);
  EXPECT_EQ(ps.alpha, pf.alpha);
  EXPECT_EQ(ps.beta, pf.beta);
  EXPECT_EQ(ps.damping, pf.damping);

  double stiffMax = 0.0, floppyMax = 0.0;
  for (int s = 0; s < stepsFor(scene, runLengthOf("clusters").seconds); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
    stiffMax = std::max(stiffMax, test::maxDeviationFromRigidFit(scene, stiff));
    floppyMax = std::max(floppyMax, test::maxDeviationFromRigidFit(scene, floppy));
  }
  const double stiffRest = test::maxDeviationFromRigidFit(scene, stiff);
  const double floppyRest = test::maxDeviationFromRigidFit(scene, floppy);
  EXPECT_LT(floppyRest, 1.5 * stiffRest);
  EXPECT_GT(floppyRest, stiffRest / 1.5);
  EXPECT_LT(floppyMax, 1.3 * stiffMax);
  EXPECT_GT(floppyMax, stiffMax / 1.3);
  std::printf(
      "[ scene    ] clusters: deviation from a rigid fit at rest %.4f m (1 cluster) vs "
      "%.4f m (%d clusters); largest while landing %.4f m vs %.4f m\n",
      stiffRest, floppyRest, scene.world.clusterCount(hf), stiffMax, floppyMax);
}

// A pile: at least ten bodies dropped onto each other; once settled, some rest on others rather
// than on the floor (their lowest particle is well above every plane collider).
TEST(ShippedScenes, PileRestsBodiesOnEachOther) {
  if (SB_TEST_SANITIZED) GTEST_SKIP() << "a minute under the sanitizer; see runLengthOf";
  Scene scene = loadScene(scenePath("pile"));
  ASSERT_GE(scene.bodies.size(), 10u);
  for (int s = 0; s < stepsFor(scene, runLengthOf("pile").seconds); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
  }
  int onOthers = 0;
  double highestClearance = 0.0;
  for (int i = 0; i < int(scene.bodies.size()); ++i) {
    const Eigen::MatrixX3d x = scene.world.positions(scene.bodies[size_t(i)].handle).cast<double>();
    double aboveFloor = std::numeric_limits<double>::infinity();
    for (const Collider& c : scene.world.colliders())
      if (c.shape == Collider::Shape::Plane)
        for (int k = 0; k < x.rows(); ++k) {
          Vec3 normal;
          aboveFloor = std::min(aboveFloor, colliderDistance(c, x.row(k).transpose(), &normal));
        }
    const double clearance = aboveFloor / test::particleSpacing(scene, i);
    highestClearance = std::max(highestClearance, clearance);
    if (clearance > 1.5) ++onOthers;
  }
  EXPECT_GE(onOthers, 1);
  std::printf(
      "[ scene    ] pile: %d of %zu bodies rest clear of the floor, the highest %.2f "
      "spacings above it\n",
      onOthers, scene.bodies.size(), highestClearance);
}

// The performance scene: at least 50 bodies and 50,000 render-mesh vertices.
TEST(ShippedScenes, LargeSceneIsLarge) {
  const Scene scene = loadScene(scenePath("large"));
  long renderVertices = 0, particles = 0;
  for (const SceneBody& b : scene.bodies) {
    ASSERT_TRUE(b.render) << "every body of the large scene draws a render mesh";
    renderVertices += b.render->embedding->meshVertexCount();
    particles += scene.world.particleCount(b.handle);
  }
  EXPECT_GE(scene.bodies.size(), 50u);
  EXPECT_GE(renderVertices, 50000);
  std::printf("[ scene    ] large: %zu bodies, %ld particles, %ld render vertices\n",
              scene.bodies.size(), particles, renderVertices);
}

}  // namespace
}  // namespace sb
