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
#include <tuple>
#include <vector>

#include "scene_checks.h"
#include "sim/cage/embedding.h"
#include "sim/scene/scene.h"
#include "sim/world/matching/plasticity.h"
#include "tests/support/sanitizers.h"
#include "tests/support/temp_dir_test.h"

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
  // Deepest particle in another body at the end, in spacings; the shipped scenes keep 5 %.
  double deepestAllowed = 0.05;
};

RunLength runLengthOf(const std::string& name) {
  static const std::map<std::string, RunLength> special = {
      {"default", {12.0, true}},      // (10.7 s)
      {"plasticity", {8.0, true}},    // (asleep at 7.8 s)
      {"clusters", {10.0, true}},     // (7.7 s)
      {"restitution", {10.0, true}},  // (8.3 s: the e = 0.9 box bounces until then)
      {"slope", {10.0, true}},        // (1.9 s: the 40° box has slid onto the floor)
      {"stack", {10.0, true}},        // (0.6 s)
      {"pile", {13.0, true}},         // (10.1 s)
      // 54 bodies still move by more than 1e-3 of a diagonal per step after 14 s (13 s of CPU),
      // so the performance scene is checked while it moves: 3 s covers the fall and the first
      // contacts of all three layers.
      {"large", {3.0, false}},
      // The source's scale (issue 13): 384 bodies, 55k particles, ~0.4 s of CPU per step on
      // two threads today, so 1.5 s (the lower layers land and the upper ones fall onto them;
      // 0.25 s, the first layer landing, under the sanitizers). It does not keep the 5 %: from
      // 0.5 s on one particle is lodged 0.5–0.73 spacings inside another body (measured at
      // 1.5 s: particle 37 of bunny 135 in bunny 007, 0.507); an open defect of issue 13, held
      // here at its measured size so it cannot grow unseen.
      {"seed-scale", {test_support::kSanitized ? 0.25 : 1.5, false, 0.75}},
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
  EXPECT_LE(deepest.relativeDepth, length.deepestAllowed)
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

// Every shipped scene run at one sub-step of 1 s per step (maxSubstep 1 s, the longest
// accepted), with sleep as the scene has it (on in all of them) and off: nothing gains energy
// and no body leaves its shape. Kinetic energy never exceeds what the scene had at the start
// plus the potential energy of every particle falling 1 m below the lowest start point (no
// collider is lower); every body keeps within 30 % of its diagonal of its best rigid fit
// (measured at most 26 %, a soft pile body under the others) and no particle ends deeper than 5
// spacings in a collider (measured at most 3.05, the pile without sleep: at such sub-steps the
// floor's contacts resolve only approximately). Before the sub-step conversion
// (substep_material.h) the pile, large and restitution scenes blew up at this step
// (10¹³ – 10²⁹ J); the restitution scene also needed resting contact kept inelastic at long
// sub-steps (contact_phase.cpp: approaches below 2|g|h). With sleep, the restitution scene sank
// 1.5 m into the floor in 20 steps (~30 spacings) until sleeping bodies were seen in the
// detection's frame (ContactScratch::Body::frameShift). Under the sanitizers only the runs with
// sleep (the scenes' own setting) are made: the other half adds minutes and no code path.
class ShippedSceneAtOneSecondSubsteps
    : public ::testing::TestWithParam<std::tuple<std::string, bool>> {};

TEST_P(ShippedSceneAtOneSecondSubsteps, GainsNoEnergyAndKeepsItsBodies) {
  const auto& [name, sleep] = GetParam();
  if (!sleep && test_support::kSanitized) GTEST_SKIP() << "the GCC build runs this one";
  // The seed-scale pile (issue 13): one 1-s sub-step there costs ~2.5 s of CPU (every body
  // looks 9.8 m around), so it runs 6 steps with sleep, in the GCC build only; its lowest
  // bodies, under five layers, end up to 0.41 diagonals from a rigid fit (0.47 after 20 steps;
  // the 12-body pile: 0.26), which is allowed here as measured, not claimed as good.
  const bool seedScale = name == "seed-scale";
  if (seedScale && (!sleep || test_support::kSanitized))
    GTEST_SKIP() << "the seed-scale pile runs once, with sleep, in the GCC build";
  const int steps = seedScale ? 6 : 20;
  const double shapeAllowed = seedScale ? 0.6 : 0.3;
  Scene scene = loadScene(scenePath(name));
  WorldSettings settings = scene.world.settings();
  ASSERT_TRUE(settings.sleep) << "a shipped scene without sleep: run it once, not twice";
  settings.timeStep = 1.0;
  settings.substeps = 1;
  settings.maxSubstep = 1.0;
  settings.sleep = sleep;
  scene.world.setSettings(settings);
  ASSERT_EQ(scene.world.substepsFor(1.0), 1);
  const double g = settings.gravity.norm();
  const int n = int(scene.bodies.size());
  double lowest = 1e30, budget = 0.0;
  for (int i = 0; i < n; ++i) lowest = std::min(lowest, lowestY(scene, i));
  auto kinetic = [&] {
    double e = 0.0;
    for (const SceneBody& b : scene.bodies) {
      const Eigen::VectorXf m = scene.world.masses(b.handle);
      const auto v = scene.world.velocities(b.handle);
      for (int k = 0; k < m.size(); ++k) e += 0.5 * m[k] * v.row(k).squaredNorm();
    }
    return e;
  };
  budget = kinetic();
  for (const SceneBody& b : scene.bodies) {
    const Eigen::VectorXf m = scene.world.masses(b.handle);
    const auto x = scene.world.positions(b.handle);
    for (int k = 0; k < m.size(); ++k) budget += m[k] * g * (x(k, 1) - (lowest - 1.0));
  }
  double peak = 0.0;
  for (int s = 0; s < steps; ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
    peak = std::max(peak, kinetic());
    ASSERT_LE(kinetic(), budget) << "step " << s;
  }
  double worstShape = 0.0;
  for (int i = 0; i < n; ++i) {
    const double off =
        test::maxDeviationFromRigidFit(scene, i) / test::boundingBoxDiagonal(scene, i);
    EXPECT_LT(off, shapeAllowed) << "body " << i;
    worstShape = std::max(worstShape, off);
  }
  const test::ColliderClearance floor = test::lowestColliderClearance(scene);
  EXPECT_GE(floor.relativeDistance, -5.0);
  std::printf(
      "[ scene    ] %s at 1-s sub-steps, sleep %s: peak kinetic energy %.3g J of %.3g J "
      "allowed; largest departure from a rigid fit %.3g diagonals; lowest particle %.3g "
      "spacings from a collider\n",
      name.c_str(), sleep ? "on" : "off", peak, budget, worstShape, floor.relativeDistance);
}

INSTANTIATE_TEST_SUITE_P(Shipped, ShippedSceneAtOneSecondSubsteps,
                         ::testing::Combine(::testing::ValuesIn(shippedSceneNames()),
                                            ::testing::Bool()),
                         [](const ::testing::TestParamInfo<std::tuple<std::string, bool>>& run) {
                           return testName({std::get<0>(run.param), run.index}) +
                                  (std::get<1>(run.param) ? "_sleep" : "_no_sleep");
                         });

// Every shipped scene saved and loaded again is the same world: the same state, and the same
// steps after it (settings, parameters, pins, initial velocities, colliders and clusters all
// came back); saving the loaded copy gives the same bytes (a stable key order, numbers that
// round-trip). Pins and initial velocities were once dropped by saving (cantilever.json's bars
// fell, plasticity.json's bodies lost their throw).
class SavedShippedScene : public test_support::TempDirTest,
                          public ::testing::WithParamInterface<std::string> {};

TEST_P(SavedShippedScene, LoadsAsTheSameWorldAndSavesTheSameBytesAgain) {
  Scene original = loadScene(scenePath(GetParam()));
  const std::string saved = path("saved.json"), again = path("again.json");
  saveScene(original, saved);
  Scene back = loadScene(saved);
  ASSERT_EQ(back.bodies.size(), original.bodies.size());
  EXPECT_EQ(back.world.stateHash(), original.world.stateHash());
  // The seed-scale scene (issue 13) costs ~0.3 s per step once it piles: 10 steps there (its
  // bodies still fall then).
  const int steps = GetParam() == "seed-scale" ? 10 : 60;
  for (int k = 1; k <= steps; ++k) {
    original.world.step();
    back.world.step();
    if (k % 10 == 0) {
      ASSERT_EQ(back.world.stateHash(), original.world.stateHash()) << "step " << k;
    }
  }
  saveScene(back, again);
  EXPECT_EQ(contents(again), contents(saved));
}

INSTANTIATE_TEST_SUITE_P(Shipped, SavedShippedScene, ::testing::ValuesIn(shippedSceneNames()),
                         testName);

TEST(ShippedScenes, IncludeTheDocumentedScenes) {
  const std::vector<std::string> names = shippedSceneNames();
  for (const char* expected : {"default", "plasticity", "clusters", "pile", "large", "stack",
                               "restitution", "slope", "hands", "seed-scale"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
}

// The pile at one-second steps (the scene's other settings as shipped): each step runs 120
// sub-steps of 1/120 s (WorldSettings::maxSubstep), so the pile lands and rests as at short
// steps. With one sub-step per second it blew up (fastest particle 1.8·10⁸ m/s within 60 s).
// Checked: no NaN, nothing in the floor or deep in another body, no body far from its rest
// shape, every body asleep by 8 s (measured: asleep from 5 s).
TEST(ShippedScenes, PileAtOneSecondStepsRestsAsAtShortSteps) {
  Scene scene = loadScene(scenePath("pile"));
  WorldSettings settings = scene.world.settings();
  settings.timeStep = 1.0;
  scene.world.setSettings(settings);
  ASSERT_EQ(scene.world.substepsFor(1.0), 120);
  for (int s = 0; s < 8; ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
  }
  EXPECT_GE(test::lowestColliderClearance(scene).relativeDistance, -0.01);
  EXPECT_LE(test::deepestPenetration(scene).relativeDepth, 0.05);
  for (int i = 0; i < int(scene.bodies.size()); ++i) {
    // The pile's bodies are 0.5–0.8 m; soft ones squash under the others by centimetres.
    EXPECT_LT(test::maxDeviationFromRigidFit(scene, i), 0.15 * test::boundingBoxDiagonal(scene, i))
        << "body " << i;
    EXPECT_TRUE(scene.world.isSleeping(scene.bodies[size_t(i)].handle)) << "body " << i;
  }
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
  // At rest both keep their shape to well under 1 % of their size: what is left is a particle of
  // the floor contact held a millimetre or three off its body's fit (1.2 and 3.0 mm on bodies
  // 1.03 m tall), too small for a ratio to say anything; the ratio is checked while landing.
  const double size = test::boundingBoxDiagonal(scene, stiff);
  EXPECT_LT(stiffRest, 0.005 * size);
  EXPECT_LT(floppyRest, 0.005 * size);
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

// ---- contact scenes (issue 11): a stack, restitution, slopes -----------------------------------
// Their tests switch sleep off: a sleeping body skips the step, so the solver's own drift, bounce
// and friction are measured only while every body is awake (the generic test above runs the
// scenes as shipped, sleep on).

void wakeForever(Scene& scene) {
  WorldSettings s = scene.world.settings();
  s.sleep = false;
  scene.world.setSettings(s);
}

// Edge of a box-shaped body placed axis-aligned: the largest extent of its rest positions (more
// than the edge for a tilted box; the slope test uses it only as a loose bound).
double restEdge(const Scene& scene, int body) {
  const Eigen::MatrixX3d x =
      scene.world.restPositions(scene.bodies[size_t(body)].handle).cast<double>();
  return (x.colwise().maxCoeff() - x.colwise().minCoeff()).maxCoeff();
}

Vec3 centreOf(const Scene& scene, int body) {
  return scene.world.centreOfMass(scene.bodies[size_t(body)].handle);
}
Vec3 velocityOf(const Scene& scene, int body) {
  const BodyHandle h = scene.bodies[size_t(body)].handle;
  return scene.world.linearMomentum(h) / scene.world.mass(h);
}
double substepOf(const Scene& scene) {
  return scene.world.settings().timeStep / scene.world.settings().substeps;
}

// A stack of rigid boxes stands: over 20 s, sleep off, the top box of the stack drifts sideways
// less than 1 % of its edge, and every box ends where it sits on the one below. Under the
// sanitizers 5 s (the GCC build checks the 20 s; these took 112 s under AddressSanitizer).
TEST(ShippedScenes, StackOfRigidBoxesStandsWithoutDrift) {
  const double seconds = test_support::kSanitized ? 5.0 : 20.0;
  Scene scene = loadScene(scenePath("stack"));
  wakeForever(scene);
  const int n = int(scene.bodies.size());
  ASSERT_GE(n, 4);
  std::vector<int> order(static_cast<size_t>(n));
  std::vector<Vec3> start(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    order[size_t(i)] = i;
    start[size_t(i)] = centreOf(scene, i);
    EXPECT_EQ(scene.world.params(scene.bodies[size_t(i)].handle).mode, Mode::Rigid);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return start[a].y() < start[b].y(); });
  const int top = order.back();
  const double edge = restEdge(scene, top);
  for (int i = 0; i < n; ++i)  // one column
    EXPECT_LT(std::hypot(start[i].x() - start[top].x(), start[i].z() - start[top].z()),
              0.01 * edge);

  double worstDrift = 0.0;
  for (int s = 0; s < stepsFor(scene, seconds); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
    const Vec3 d = centreOf(scene, top) - start[size_t(top)];
    worstDrift = std::max(worstDrift, std::hypot(d.x(), d.z()));
  }
  EXPECT_LT(worstDrift, 0.01 * edge) << "top box drift, m";

  // Nothing fell: the k-th box from the floor (y = 0) has its centre at (k + ½)·edge, within the
  // contact tolerance of the generic test (5 % of the particle spacing) per interface below it.
  double worstHeight = 0.0;
  for (int k = 0; k < n; ++k) {
    const int i = order[size_t(k)];
    const double tolerance = (k + 1) * 0.05 * test::particleSpacing(scene, i);
    const double off = centreOf(scene, i).y() - (k + 0.5) * restEdge(scene, i);
    EXPECT_LE(std::abs(off), tolerance) << "box " << k << " from the floor";
    worstHeight = std::max(worstHeight, std::abs(off));
  }
  std::printf(
      "[ scene    ] stack: %d rigid boxes, edge %.3f m: top box drift over %.0f s at most %.3g m "
      "(%.3g %% of the edge); centres at most %.3g m from the stacked heights\n",
      n, edge, seconds, worstDrift, 100.0 * worstDrift / edge, worstHeight);
}

// Boxes dropped from the same height with e = 0, 0.5, 0.9 (the floor's e is 0, a contact takes
// the larger), a row of rigid ones and a row of soft ones (linear α 0.5), rise after the first
// impact to e² of their fall H, in order of e within each row. Soft boxes: the bracket,
// e² ± 0.05 (their impact is an event of the pair as a whole, soft_impact.h; the rebound starts
// from the compressed body and its spring-back is held, so no finer closed form). Rigid boxes:
//
// The bracket is the time discretisation's, derived from the integrator and the contact rule.
// Sub-step h: v −= g·h, then x += h·v (symplectic Euler); the bounce fires in the sub-step whose
// predicted position is below the floor, restarting from that sub-step's start height
// x₀ ∈ [0, V·h) (V the impact speed) with speed e·V. Falling from rest at H to x₀ gives
// V²/2g = H − x₀ + V·h/2, rising from x₀ + h·e·V with e·V peaks at most g·h²/8 above the
// continuous x₀ + h·e·V + (eV)²/2g − e·V·h/2. So apex − e²·H = x₀·(1 − e²) + e·(1 + e)·V·h/2
// (+ g·h²/8): between e(1 + e)/2·V·h and (1 + e)(1 − e/2)·V·h + g·h²/8. The apex is sampled once
// per frame Δt, which can miss up to g·Δt²/8 of it; V is at most √(2gH) + g·h.
TEST(ShippedScenes, BoxesReboundESquaredOfTheirFall) {
  Scene scene = loadScene(scenePath("restitution"));
  wakeForever(scene);
  const int n = int(scene.bodies.size());
  ASSERT_GE(n, 3);
  const double g = scene.world.settings().gravity.norm();
  const double dt = scene.world.settings().timeStep;
  struct Drop {
    bool rigid;
    double e, fall, restY, apex = 0.0, vyBefore = 0.0;
    int impact = -1;
    bool done = false;
  };
  std::vector<Drop> drops;
  for (int i = 0; i < n; ++i) {
    const BodyHandle h = scene.bodies[size_t(i)].handle;
    const BodyParams& params = scene.world.params(h);
    const double fall = lowestY(scene, i);  // the floor is y = 0
    drops.push_back({params.mode == Mode::Rigid && params.alpha == 1.0, params.restitution, fall,
                     centreOf(scene, i).y() - fall});
  }
  for (int s = 0; s < stepsFor(scene, 4.0); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
    for (int i = 0; i < n; ++i) {
      Drop& d = drops[size_t(i)];
      const double vy = velocityOf(scene, i).y(), y = centreOf(scene, i).y() - d.restY;
      if (d.impact < 0) {
        if (vy > d.vyBefore) d.impact = s;  // free fall only ever speeds the body up downward
        d.vyBefore = vy;
        continue;
      }
      if (d.done) continue;
      d.apex = std::max(d.apex, y);
      // Past the apex and on the way down again, or 1.5 s after the impact (the e = 0.9 box
      // flies 2·0.9·v/g ≈ 0.8 s).
      if ((vy < 0.0 && y < 0.5 * d.apex) || (s - d.impact) * dt > 1.5) d.done = true;
    }
  }
  // Rigid row first, each row in order of e.
  std::sort(drops.begin(), drops.end(),
            [](const Drop& a, const Drop& b) { return a.rigid != b.rigid ? a.rigid : a.e < b.e; });
  EXPECT_EQ(std::count_if(drops.begin(), drops.end(), [](const Drop& d) { return d.rigid; }), 3);
  for (size_t k = 0; k < drops.size(); ++k) {
    const Drop& d = drops[k];
    EXPECT_GE(d.impact, 0) << "e " << d.e << " never landed";
    EXPECT_TRUE(d.done) << "e " << d.e;
    const double h = substepOf(scene), e = d.e;
    const double v = std::sqrt(2.0 * g * d.fall);
    const double low =
        d.rigid ? e * e + (e * (1.0 + e) / 2.0 * v * h - g * dt * dt / 8.0) / d.fall : e * e - 0.05;
    const double high =
        d.rigid ? e * e + ((1.0 + e) * (1.0 - e / 2.0) * (v + g * h) * h + g * h * h / 8.0) / d.fall
                : e * e + 0.05;
    EXPECT_GE(d.apex / d.fall, low) << "e " << e;
    EXPECT_LE(d.apex / d.fall, high) << "e " << e;
    if (k > 0 && drops[k].rigid == drops[k - 1].rigid) {
      EXPECT_GT(drops[k].e, drops[k - 1].e) << "restitutions must differ";
      EXPECT_GT(d.apex, drops[k - 1].apex) << "e " << d.e << " vs " << drops[k - 1].e;
    }
    std::printf(
        "[ scene    ] restitution: %s e %.2f, fall %.3f m (impact %.2f m/s): apex %.4f m, "
        "ratio %.4f (e^2 %.4f, allowed %.4f to %.4f)\n",
        d.rigid ? "rigid" : "soft", e, d.fall, v, d.apex, d.apex / d.fall, e * e, low, high);
  }
}

// The slope (a box collider) a body starts on: the collider its centre is nearest to, and the
// downhill direction along that collider's top face.
struct SlopeOf {
  int collider = -1;
  double angle = 0.0;  // radians from horizontal
  double friction = 0.0;
  Vec3 normal, downhill;
};
SlopeOf slopeUnder(const Scene& scene, int body) {
  SlopeOf best;
  double nearest = std::numeric_limits<double>::infinity();
  const Vec3 c = centreOf(scene, body);
  const std::vector<Collider>& colliders = scene.world.colliders();
  for (int k = 0; k < int(colliders.size()); ++k) {
    if (colliders[size_t(k)].shape != Collider::Shape::Box) continue;
    Vec3 normal;
    const double d = colliderDistance(colliders[size_t(k)], c, &normal);
    if (d < nearest) {
      nearest = d;
      best.collider = k;
    }
  }
  if (best.collider < 0) return best;
  const Collider& slope = colliders[size_t(best.collider)];
  best.normal = slope.rotation.col(1);  // the box's top face (+y of the box)
  best.angle = std::acos(std::clamp(best.normal.y(), -1.0, 1.0));
  best.friction = slope.friction;
  const Vec3 down = -Vec3::UnitY();
  best.downhill = (down - down.dot(best.normal) * best.normal).normalized();
  return best;
}

// A box on a slope shallower than its friction angle (tan θ < μ) stays where it was put: its
// centre moves less than 1 mm along the slope over 10 s (sleep off).
TEST(ShippedScenes, BoxOnAShallowSlopeStays) {
  Scene scene = loadScene(scenePath("slope"));
  wakeForever(scene);
  std::vector<int> holding;
  std::vector<SlopeOf> slopes;
  for (int i = 0; i < int(scene.bodies.size()); ++i) {
    const SlopeOf s = slopeUnder(scene, i);
    ASSERT_GE(s.collider, 0) << "body " << i << " is on no box collider";
    slopes.push_back(s);
    if (std::tan(s.angle) < s.friction) holding.push_back(i);
  }
  ASSERT_FALSE(holding.empty()) << "no slope shallower than its friction angle";
  std::vector<Vec3> start;
  for (int i = 0; i < int(scene.bodies.size()); ++i) start.push_back(centreOf(scene, i));
  for (int s = 0; s < stepsFor(scene, 10.0); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
  }
  for (int i : holding) {
    const Vec3 d = centreOf(scene, i) - start[size_t(i)];
    const double drift = (d - d.dot(slopes[size_t(i)].normal) * slopes[size_t(i)].normal).norm();
    EXPECT_LT(drift, 1e-3) << "body " << i;
    std::printf(
        "[ scene    ] slope: %.1f deg, mu %.2f (friction angle %.1f deg): drift along the "
        "slope over 10 s %.3g m\n",
        slopes[size_t(i)].angle * 180.0 / M_PI, slopes[size_t(i)].friction,
        std::atan(slopes[size_t(i)].friction) * 180.0 / M_PI, drift);
  }
}

// A box on a slope steeper than its friction angle slides down with Coulomb's acceleration
// g·(sin θ − μ·cos θ), measured from its velocity along the slope between t1 (after the 1 mm drop
// onto it) and t2 (still on the slope). Tolerance: 1 % of the friction term μ·g·cos θ, i.e. the
// slide matches Coulomb's law to a coefficient within ±0.01·μ. Sliding is steady (constant force,
// so symplectic Euler's velocities are exact) and the solve clamps a rigid body's accumulated
// friction to the round cone μ·λ, so nothing but round-off should be left; the failures this
// catches are far outside it (held by static friction: a = 0; frictionless: g·sin θ; friction
// from the wrong normal load or a faceted cone: errors of 10 % and more of μ).
TEST(ShippedScenes, BoxOnASteepSlopeSlidesWithCoulombAcceleration) {
  Scene scene = loadScene(scenePath("slope"));
  wakeForever(scene);
  const double g = scene.world.settings().gravity.norm();
  std::vector<int> sliding;
  std::vector<SlopeOf> slopes;
  for (int i = 0; i < int(scene.bodies.size()); ++i) {
    const SlopeOf s = slopeUnder(scene, i);
    ASSERT_GE(s.collider, 0) << "body " << i << " is on no box collider";
    slopes.push_back(s);
    if (std::tan(s.angle) > s.friction) sliding.push_back(i);
  }
  ASSERT_FALSE(sliding.empty()) << "no slope steeper than its friction angle";
  // Velocity along the slope at t1 (after the 1 mm drop onto it) and t2 (still on it).
  const double t1 = 0.25, t2 = 1.0;
  std::vector<double> v1(scene.bodies.size()), v2(scene.bodies.size());
  for (int s = 0; s < stepsFor(scene, t2); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
    for (int i : sliding) {
      const double v = velocityOf(scene, i).dot(slopes[size_t(i)].downhill);
      if (s + 1 == stepsFor(scene, t1)) v1[size_t(i)] = v;
      v2[size_t(i)] = v;
    }
  }
  for (int i : sliding) {
    const SlopeOf& sl = slopes[size_t(i)];
    // Still on its slope at t2, not on the floor.
    Vec3 normal;
    const double onSlope =
        colliderDistance(scene.world.colliders()[size_t(sl.collider)], centreOf(scene, i), &normal);
    EXPECT_LT(onSlope, restEdge(scene, i)) << "body " << i << " left its slope";
    const double a = (v2[size_t(i)] - v1[size_t(i)]) / (t2 - t1);
    const double expected = g * (std::sin(sl.angle) - sl.friction * std::cos(sl.angle));
    const double tolerance = 0.01 * sl.friction * g * std::cos(sl.angle);
    EXPECT_NEAR(a, expected, tolerance) << "body " << i;
    std::printf(
        "[ scene    ] slope: %.1f deg, mu %.2f: acceleration %.4f m/s^2 between %.2f and %.2f s "
        "(g(sin - mu cos) %.4f, tolerance %.4f)\n",
        sl.angle * 180.0 / M_PI, sl.friction, a, t1, t2, expected, tolerance);
  }
}

// The box that slides off the 40° ramp ends flat on the floor, at rest. Both ramps of slope.json
// dip into the floor, and a particle of the box at the ramp's foot used to be pushed out of the
// ramp through its sunk end face, down and away from the ramp: against the floor, every
// sub-step. The box stood on one edge with its centre 12 cm beyond it, crept away from the ramp
// at 2.6-3.4 cm/s, tilted 20° (held by rolling resistance, whose cap grows with the fighting
// normal impulses), and lay down only at 4.7 s; with sleep on it froze there tilted (buried
// faces, docs/design.md §5.5). From 3 s on (sleep off) it must lie on a face (its centre at half
// its edge, 0.2 m, within 1 mm) and not move (its centre within 0.1 mm until 6 s).
TEST(ShippedScenes, BoxSlidOffTheSteepRampLiesFlatAtItsFoot) {
  Scene scene = loadScene(scenePath("slope"));
  wakeForever(scene);
  int sliding = -1;
  for (int i = 0; i < int(scene.bodies.size()); ++i)
    if (std::tan(slopeUnder(scene, i).angle) > slopeUnder(scene, i).friction) sliding = i;
  ASSERT_GE(sliding, 0) << "no slope steeper than its friction angle";
  Vec3 at3 = Vec3::Zero();
  for (int s = 0; s < stepsFor(scene, 6.0); ++s) {
    stepAndCheckFinite(scene, s);
    if (HasFatalFailure()) return;
    if (s + 1 == stepsFor(scene, 3.0)) at3 = centreOf(scene, sliding);
  }
  EXPECT_NEAR(at3.y(), 0.2, 1e-3);
  EXPECT_LT((centreOf(scene, sliding) - at3).norm(), 1e-4);
}

}  // namespace
}  // namespace sb
