// Scene files: the shipped scenes load, errors name file/field/reason, saving round-trips.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <future>

#include "sim/mesh/mesh_io.h"
#include "sim/scene/body_embedding.h"
#include "sim/scene/fold_watch.h"
#include "sim/scene/frame_export.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"

namespace sb {
namespace {

namespace fs = std::filesystem;
const std::string kAssets = SOFTBODY_ASSET_DIR;

std::string body(const std::string& extra) {
  return R"({"bodies": [{"name": "b", "mesh": ")" + kAssets + R"(/meshes/suzanne_cage.obj")" +
         extra + "}]}";
}

void expectSceneError(const std::string& json, const std::string& needle) {
  try {
    parseScene(json, "test.json", "");
    FAIL() << "no error, expected " << needle;
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("test.json: ", 0), 0u) << what;  // names the file first
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

TEST(Scene, DefaultSceneLoadsWithBoundRenderMeshes) {
  const Scene scene = loadScene(defaultScenePath());
  ASSERT_GE(scene.bodies.size(), 3u);
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const SceneBody& b = scene.bodies[i];
    ASSERT_TRUE(b.render) << i;
    PointsRowMajor v;
    scene.renderVertices(int(i), v);
    // At the start the particles are the placed cage, so by linear precision of mean value
    // coordinates the render vertices are the placed render mesh.
    const mesh::TriangleMesh mesh = mesh::readMesh(kAssets + "/scenes/" + b.render->path);
    ASSERT_EQ(v.rows(), int(mesh.vertices.size()));
    const Vec3 r = b.rotationDegrees * (M_PI / 180.0);
    const Mat3 R =
        (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3::UnitY()) *
         Eigen::AngleAxisd(r.x(), Vec3::UnitX()))
            .toRotationMatrix();
    double worst = 0;
    for (size_t k = 0; k < mesh.vertices.size(); ++k) {
      const Vec3 expected = R * (b.scale * mesh.vertices[k]) + b.translation;
      worst = std::max(worst, (v.row(int(k)).transpose().cast<double>() - expected).norm());
    }
    EXPECT_LT(worst, 1e-4) << i;
    EXPECT_FALSE(scene.renderTriangles(int(i)).empty());
  }
  // The two bunnies (same cage and render files, different placements) share one binding, and
  // the check above shows it serves both placements.
  EXPECT_EQ(scene.bodies[0].meshPath, scene.bodies[2].meshPath);
  EXPECT_EQ(scene.bodies[0].render, scene.bodies[2].render);
  EXPECT_NE(scene.bodies[0].render, scene.bodies[1].render);
}

// The default scene after 2 s (its bodies landed and rolling): the rigid bunny's render mesh
// follows its cage as a whole (cage::RigidFollow), within the stated tolerance of W·x; the soft
// bodies' take the weights, bit for bit; and the render meshes of all bodies at once are those
// of one body at a time, bit for bit.
TEST(Scene, RigidBodiesFollowTheirCagesAndSoftOnesTakeTheWeights) {
  Scene scene = loadScene(defaultScenePath());
  for (int s = 0; s < 120; ++s) scene.world.step();
  std::vector<int> which;
  std::vector<PointsRowMajor> together(scene.bodies.size());
  std::vector<PointsRowMajor*> outs;
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    which.push_back(int(i));
    outs.push_back(&together[i]);
  }
  scene.renderVertices(which, outs);
  int followed = 0;
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const SceneBody& b = scene.bodies[i];
    ASSERT_TRUE(b.render && b.render->rigidFollow) << i;
    const ConstPointsRef cage = scene.world.positions(b.handle).topRows(b.cageVertexCount);
    PointsRowMajor alone, weighted, probe;
    scene.renderVertices(int(i), alone);
    b.render->embedding->deform(cage, weighted);
    EXPECT_EQ(alone, together[i]) << i;
    const bool rigid = scene.world.params(b.handle).mode == Mode::Rigid;
    EXPECT_EQ(b.render->rigidFollow->follow(cage, probe), rigid) << i;
    if (!rigid) {
      EXPECT_EQ(alone, weighted) << i;
      continue;
    }
    ++followed;
    const double diagonal = (cage.colwise().maxCoeff() - cage.colwise().minCoeff()).norm();
    const double rounding = 16.0 * std::numeric_limits<float>::epsilon() *
                            b.render->rigidFollow->lebesgue() * cage.cwiseAbs().maxCoeff();
    EXPECT_LE((alone - weighted).rowwise().norm().maxCoeff(),
              cage::RigidFollow::kTolerance * diagonal + rounding)
        << i;
  }
  EXPECT_EQ(followed, 1);
}

TEST(Scene, ErrorsNameFileFieldAndReason) {
  expectSceneError("{\n \"bodies\": [\n  {,}\n]}", "line 3");
  expectSceneError("{}", "bodies: is required");
  expectSceneError(R"({"bodies": [], "wrld": {}})", "wrld: unknown field");
  expectSceneError(body(R"(, "alpha": 3)"), "bodies[0].alpha: must be in [0, 1], got 3");
  expectSceneError(body(R"(, "mode": "jelly")"),
                   "bodies[0].mode: must be rigid, linear or quadratic");
  expectSceneError(body(R"(, "translation": [1, 2])"),
                   "bodies[0].translation: must be an array of 3 numbers");
  expectSceneError(body(R"(, "clusters": {"kind": "grid", "cellSize": -1})"),
                   "bodies[0].clusters.cellSize");
  expectSceneError(body(R"(, "clusters": {"kind": "explicit", "clusters": [[0, 1, 999]]})"),
                   "bodies[0]: clusters.clusters[0]: particle index out of range");
  expectSceneError(body(R"(, "plasticity": {"yeild": 1})"),
                   "bodies[0].plasticity.yeild: unknown field");
  expectSceneError(R"({"world": {"substeps": 0}, "bodies": []})",
                   "world.substeps: must be in [1, 1000]");
  expectSceneError(R"({"colliders": [{"type": "cone"}], "bodies": []})", "colliders[0].type");
  expectSceneError(R"({"colliders": [{"type": "plane", "restitution": 1.5}], "bodies": []})",
                   "colliders[0].restitution: must be in [0, 1], got 1.5");
  expectSceneError(body(R"(, "restitution": -0.1)"), "bodies[0].restitution: must be in [0, 1]");
  expectSceneError(R"({"world": {"sleep": 1}, "bodies": []})", "world.sleep");
  expectSceneError(R"({"world": {"rollingResistance": 2}, "bodies": []})",
                   "world.rollingResistance: must be in [0, 1], got 2");
  expectSceneError(R"({"world": {"maxSubstep": 0}, "bodies": []})",
                   "world.maxSubstep: must be in [0.0001, 1], got 0");
  expectSceneError(R"({"bodies": [{"mesh": "/no/such/mesh.obj"}]})",
                   "bodies[0].mesh: /no/such/mesh.obj");
  // A render mesh needs a valid closed cage; a mesh with no faces cannot be one.
  const fs::path dir = fs::temp_directory_path() / "softbody_scene_test";
  fs::create_directories(dir);
  { std::ofstream(dir / "points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"; }
  expectSceneError(R"({"bodies": [{"mesh": ")" + (dir / "points.obj").string() +
                       R"(", "renderMesh": ")" + kAssets + R"(/meshes/suzanne.obj"}]})",
                   "bodies[0].mesh: cannot bind the render mesh");
}

// A hand-written file's key order is kept by saving: its keys in its order (per kind of
// object, bodies with keys the others lack included), then the keys it did not have; saving the
// saved file again gives the same bytes.
TEST(Scene, SaveKeepsTheKeyOrderOfTheFileItCameFrom) {
  const std::string mesh = kAssets + "/meshes/suzanne_cage.obj";
  const std::string text = R"({"bodies": [)"
                           R"({"alpha": 0.3, "mesh": ")" +
                           mesh +
                           R"(", "name": "a"},)"
                           R"({"name": "b", "damping": 0.2, "mesh": ")" +
                           mesh +
                           R"(", "translation": [0, 2, 0], "alpha": 0.4,)"
                           R"( "clusters": {"overlap": 0.3, "kind": "grid", "cellSize": 0.6}}],)"
                           R"( "world": {"substeps": 2, "gravity": [0, -9.81, 0]}})";
  const Scene scene = parseScene(text, "order.json", kAssets);
  const std::string saved = sceneText(scene, kAssets + "/order.json");
  // Where each key is first written (-1: missing).
  auto at = [&](const std::string& key, std::size_t from = 0) {
    const std::size_t p = saved.find("\"" + key + "\":", from);
    return p == std::string::npos ? -1L : long(p);
  };
  ASSERT_GE(at("bodies"), 0);
  EXPECT_LT(at("bodies"), at("world")) << saved;      // the file's top-level order
  EXPECT_LT(at("world"), at("colliders")) << saved;   // then what the file did not have
  EXPECT_LT(at("substeps"), at("gravity")) << saved;  // world: the file's order
  EXPECT_LT(at("gravity"), at("timeStep")) << saved;  // then the rest
  // Body a: alpha, mesh, name as written; body b's damping and translation go where b had them
  // (after name, after mesh), before the keys neither had.
  const long a = at("alpha");
  EXPECT_LT(a, at("mesh")) << saved;
  EXPECT_LT(at("mesh"), at("name")) << saved;
  const long b = at("name", std::size_t(at("name") + 1));
  ASSERT_GT(b, a);
  const std::size_t bFrom = std::size_t(at("alpha", std::size_t(a + 1)));  // body b's alpha
  EXPECT_LT(long(bFrom), at("mesh", bFrom)) << saved;
  EXPECT_LT(at("mesh", bFrom), at("name", bFrom)) << saved;
  EXPECT_LT(at("name", bFrom), at("damping", bFrom)) << saved;
  EXPECT_LT(at("damping", bFrom), at("mode", bFrom)) << saved;
  EXPECT_LT(at("overlap", bFrom), at("kind", bFrom)) << saved;  // nested objects too
  EXPECT_LT(at("kind", bFrom), at("cellSize", bFrom)) << saved;
  // Saved, loaded and saved again: the same bytes.
  const Scene back = parseScene(saved, "saved.json", kAssets);
  EXPECT_EQ(sceneText(back, kAssets + "/order.json"), saved);
}

TEST(Scene, SaveRoundTripsParametersAtomically) {
  Scene scene = loadScene(defaultScenePath());
  const BodyHandle h = scene.bodies[0].handle;
  BodyParams p = scene.world.params(h);
  p.mode = Mode::Linear;
  p.alpha = 0.123;
  p.plasticity = {0.2, 0.7, 0.3};
  p.restitution = 0.45;
  scene.world.setParams(h, p);
  WorldSettings s = scene.world.settings();
  s.substeps = 7;
  s.sleep = false;
  s.restitutionThreshold = 0.25;
  s.rollingResistance = 0.125;
  s.maxSubstep = 0.004;
  scene.world.setSettings(s);
  const fs::path dir = fs::temp_directory_path() / "softbody_save_test" / "sub";
  fs::create_directories(dir);
  const std::string path = (dir / "saved.json").string();
  saveScene(scene, path);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  const Scene back = loadScene(path);  // mesh paths were rebased to the new folder
  ASSERT_EQ(back.bodies.size(), scene.bodies.size());
  const BodyParams q = back.world.params(back.bodies[0].handle);
  EXPECT_EQ(q.mode, Mode::Linear);
  EXPECT_DOUBLE_EQ(q.alpha, 0.123);
  EXPECT_DOUBLE_EQ(q.plasticity.creep, 0.7);
  EXPECT_EQ(back.world.settings().substeps, 7);
  EXPECT_DOUBLE_EQ(q.restitution, 0.45);
  EXPECT_FALSE(back.world.settings().sleep);
  EXPECT_DOUBLE_EQ(back.world.settings().restitutionThreshold, 0.25);
  EXPECT_DOUBLE_EQ(back.world.settings().rollingResistance, 0.125);
  EXPECT_DOUBLE_EQ(back.world.settings().maxSubstep, 0.004);
  EXPECT_EQ(back.world.clusterCount(back.bodies[1].handle),
            scene.world.clusterCount(scene.bodies[1].handle));
  // A failed save leaves the existing file as it was.
  const std::string before = [&] {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_THROW(saveScene(scene, (dir / "no_such_dir" / "x.json").string()), SceneError);
  const std::string after = [&] {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_EQ(before, after);
}

// A body that names only a detailed mesh and "cage": {"auto": true}: its particles are the
// vertices of an automatic cage within the budget (a closed surface: the World accepts it as the
// body's contact surface), the detailed mesh is its render mesh and reproduces the placed file
// at rest; the detailed mesh may be named as renderMesh or as mesh; saving writes the cage
// settings back and no particle mesh; the second load reads the cached cage (same particles).
TEST(Scene, AutomaticCageFromADetailedMesh) {
  const fs::path dir = fs::temp_directory_path() / "softbody_auto_cage_scene";
  fs::remove_all(dir);
  ::setenv("SOFTBODY_CACHE_DIR", (dir / "cache").c_str(), 1);
  // The bunny's hand-made cage stands in for a detailed mesh: small, so the test is quick.
  const std::string detailPath = kAssets + "/meshes/bunny_cage.obj";
  const std::string placement = R"("translation": [0.5, 1, 0], "rotationDegrees": [0, 30, 0],
      "scale": 0.2, "mode": "rigid", "alpha": 1)";
  const std::string text = R"({"bodies": [
      {"name": "a", "renderMesh": ")" +
                           detailPath +
                           R"(", "cage": {"auto": true, "vertices": 60, "tightness": 0},
       "interior": {"spacing": 0.25}, )" +
                           placement + R"(},
      {"name": "b", "mesh": ")" +
                           detailPath +
                           R"(", "cage": {"auto": true, "vertices": 60, "tightness": 0},
       )" + placement + R"(}]})";
  const Scene scene = parseScene(text, "auto.json", "");
  ASSERT_EQ(scene.bodies.size(), 2u);
  const mesh::TriangleMesh detail = mesh::readMesh(detailPath);
  const Mat3 R = Eigen::AngleAxisd(30 * M_PI / 180, Vec3::UnitY()).toRotationMatrix();
  for (const SceneBody& b : scene.bodies) {
    ASSERT_TRUE(b.autoCage);
    EXPECT_TRUE(b.meshPath.empty());
    ASSERT_TRUE(b.render);
    EXPECT_EQ(b.render->path, detailPath);
    EXPECT_GE(b.cageVertexCount, 4);
    EXPECT_LE(b.cageVertexCount, 60);
    EXPECT_FALSE(b.cageTriangles.empty());
  }
  // Body a also has particles on a 0.25 m lattice inside its cage (the bunny is ~2 m here),
  // after the cage's vertices; b has the cage's vertices only.
  const SceneBody &a = scene.bodies[0], &b = scene.bodies[1];
  EXPECT_EQ(a.cageVertexCount, b.cageVertexCount);
  EXPECT_EQ(scene.world.particleCount(b.handle), b.cageVertexCount);
  EXPECT_GT(scene.world.particleCount(a.handle) - a.cageVertexCount, 10);
  EXPECT_EQ(PointsRowMajor(scene.world.positions(a.handle).topRows(a.cageVertexCount)),
            PointsRowMajor(scene.world.positions(b.handle)));
  // Both forms give the same cage and share one bind.
  EXPECT_EQ(scene.bodies[0].render, scene.bodies[1].render);
  PointsRowMajor rendered;
  scene.renderVertices(0, rendered);
  ASSERT_EQ(size_t(rendered.rows()), detail.vertices.size());
  double worst = 0.0;
  for (size_t i = 0; i < detail.vertices.size(); ++i) {
    const Vec3 expected = R * (0.2 * detail.vertices[i]) + Vec3(0.5, 1, 0);
    worst = std::max(worst,
                     (rendered.row(Eigen::Index(i)).cast<double>().transpose() - expected).norm());
  }
  EXPECT_LT(worst, 1e-5);  // float particles: the placed bunny is ~2 m across

  const std::string path = (dir / "saved.json").string();
  saveScene(scene, path);
  const std::string saved = [&] {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_EQ(saved.find("\"mesh\""), std::string::npos) << saved;
  const Scene back = loadScene(path);  // the second load reads the cached cage
  ASSERT_EQ(back.bodies.size(), 2u);
  ASSERT_TRUE(back.bodies[0].autoCage);
  EXPECT_EQ(back.bodies[0].autoCage->vertices, 60);
  EXPECT_EQ(back.bodies[0].autoCage->tightness, 0.0);
  EXPECT_EQ(back.bodies[0].interiorSpacing, 0.25);
  EXPECT_EQ(back.world.positions(back.bodies[0].handle),
            scene.world.positions(scene.bodies[0].handle));
  ::unsetenv("SOFTBODY_CACHE_DIR");
  fs::remove_all(dir);
}

TEST(Scene, AutomaticCageErrorsNameTheField) {
  const std::string detail = kAssets + "/meshes/bunny_cage.obj";
  auto withCage = [&](const std::string& fields) {
    return R"({"bodies": [{"name": "b", )" + fields + "}]}";
  };
  expectSceneError(withCage(R"("renderMesh": ")" + detail + R"(", "cage": {"auto": false})"),
                   "bodies[0].cage.auto: must be true");
  expectSceneError(withCage(R"("renderMesh": ")" + detail + R"(", "cage": {})"),
                   "bodies[0].cage.auto: must be true");
  expectSceneError(
      withCage(R"("renderMesh": ")" + detail + R"(", "cage": {"auto": true, "vertices": 3})"),
      "bodies[0].cage.vertices: must be in [4, 100000], got 3");
  expectSceneError(
      withCage(R"("renderMesh": ")" + detail + R"(", "cage": {"auto": true, "tightness": 2})"),
      "bodies[0].cage.tightness: must be in [0, 1], got 2");
  expectSceneError(
      withCage(R"("renderMesh": ")" + detail + R"(", "cage": {"auto": true, "vertex": 9})"),
      "bodies[0].cage.vertex: unknown field");
  expectSceneError(withCage(R"("cage": {"auto": true})"),
                   "bodies[0].renderMesh: is required with an automatic cage");
  expectSceneError(withCage(R"("mesh": ")" + detail + R"(", "renderMesh": ")" + detail +
                            R"(", "cage": {"auto": true})"),
                   "bodies[0].cage: an automatic cage replaces 'mesh'");
  expectSceneError(withCage(R"("renderMesh": "no_such.obj", "cage": {"auto": true})"),
                   "bodies[0].renderMesh");
  expectSceneError(withCage(R"("mesh": "no_such.obj", "cage": {"auto": true})"), "bodies[0].mesh");
  const std::string cage = R"("mesh": ")" + detail + R"(", )";
  expectSceneError(withCage(cage + R"("interior": {"spacing": 0})"),
                   "bodies[0].interior.spacing: is required and must be positive");
  expectSceneError(withCage(cage + R"("interior": {})"),
                   "bodies[0].interior.spacing: is required and must be positive");
  expectSceneError(withCage(cage + R"("interior": {"spacing": 0.1, "space": 1})"),
                   "bodies[0].interior.space: unknown field");
  // Millions of lattice points in the bunny cage's box (~10 m in file units).
  expectSceneError(withCage(cage + R"("interior": {"spacing": 0.001})"),
                   "bodies[0].interior: spacing: 0.001");
}

// "embedding" per body: the method binds the render mesh (its kind is kept), bodies share a
// bind only when the method and its options match, the rest pose reproduces the placed mesh to
// each method's linear precision, and saving writes the method back (nothing for mvc).
TEST(Scene, EmbeddingMethodPerBody) {
  const fs::path dir = fs::temp_directory_path() / "softbody_embedding_scene";
  fs::remove_all(dir);
  ::setenv("SOFTBODY_CACHE_DIR", (dir / "cache").c_str(), 1);
  const std::string pair = R"("mesh": ")" + kAssets +
                           R"(/meshes/suzanne_cage.obj", "renderMesh": ")" + kAssets +
                           R"(/meshes/suzanne.obj", "translation": [0, 1, 0])";
  const std::string text = R"({"bodies": [
      {"name": "m", )" + pair +
                           R"(},
      {"name": "h", )" + pair +
                           R"(, "embedding": {"method": "harmonic", "resolution": 16}},
      {"name": "r", )" + pair +
                           R"(, "embedding": "rbf"},
      {"name": "r2", )" + pair +
                           R"(, "embedding": {"method": "rbf", "shape": 1}},
      {"name": "r3", )" + pair +
                           R"(, "embedding": {"method": "rbf", "shape": 0.5}},
      {"name": "g", )" + pair +
                           R"(, "embedding": "green"}]})";
  const Scene scene = parseScene(text, "embedding.json", "");
  constexpr size_t kBodies = 6;
  ASSERT_EQ(scene.bodies.size(), kBodies);
  const cage::EmbeddingKind kinds[] = {
      cage::EmbeddingKind::MeanValue, cage::EmbeddingKind::Harmonic, cage::EmbeddingKind::Rbf,
      cage::EmbeddingKind::Rbf,       cage::EmbeddingKind::Rbf,      cage::EmbeddingKind::Green};
  for (size_t i = 0; i < kBodies; ++i) {
    ASSERT_TRUE(scene.bodies[i].render);
    EXPECT_EQ(scene.bodies[i].render->embedding->kind(), kinds[i]) << i;
    EXPECT_EQ(scene.bodies[i].embedding.kind, kinds[i]) << i;
  }
  EXPECT_EQ(scene.bodies[2].render, scene.bodies[3].render);  // "rbf" is shape 1
  EXPECT_NE(scene.bodies[3].render, scene.bodies[4].render);
  EXPECT_NE(scene.bodies[0].render, scene.bodies[1].render);
  const mesh::TriangleMesh detail = mesh::readMesh(kAssets + "/meshes/suzanne.obj");
  const mesh::TriangleMesh cageMesh = mesh::readMesh(kAssets + "/meshes/suzanne_cage.obj");
  Eigen::AlignedBox3d box;
  for (const Vec3& v : cageMesh.vertices) box.extend(v);
  for (size_t i = 0; i < kBodies; ++i) {
    PointsRowMajor rendered;
    scene.renderVertices(int(i), rendered);
    ASSERT_EQ(size_t(rendered.rows()), detail.vertices.size());
    double worst = 0.0;
    for (size_t v = 0; v < detail.vertices.size(); ++v)
      worst = std::max(worst, (rendered.row(Eigen::Index(v)).cast<double>().transpose() -
                               (detail.vertices[v] + Vec3(0, 1, 0)))
                                  .norm());
    // Float particles; the harmonic grid's own error is its linear precision (about a cell).
    const double allowed =
        1e-5 + scene.bodies[i].render->embedding->stats().maxLinearError * box.diagonal().norm();
    EXPECT_LT(worst, allowed) << i;
  }
  const std::string path = (dir / "saved.json").string();
  saveScene(scene, path);
  const std::string saved = [&] {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_EQ(saved.find("\"mvc\""), std::string::npos) << saved;
  const Scene back = loadScene(path);
  ASSERT_EQ(back.bodies.size(), kBodies);
  for (size_t i = 0; i < kBodies; ++i)
    EXPECT_EQ(back.bodies[i].render->embedding->kind(), kinds[i]);
  EXPECT_EQ(back.bodies[1].embedding.harmonic.resolution, 16);
  EXPECT_EQ(back.bodies[4].embedding.rbf.shape, 0.5);
  ::unsetenv("SOFTBODY_CACHE_DIR");
  fs::remove_all(dir);
}

// The fold watch checks each body with a render mesh with its own method: moved as a whole it
// reports nothing; turned inside out (mirrored) every sample of that body folds, and only its.
TEST(FoldWatch, FindsTheBodyTurnedInsideOut) {
  const std::string pair = R"("mesh": ")" + kAssets +
                           R"(/meshes/suzanne_cage.obj", "renderMesh": ")" + kAssets +
                           R"(/meshes/suzanne.obj")";
  Scene scene = parseScene(R"({"bodies": [{"name": "a", )" + pair +
                               R"(, "translation": [0, 1, 0]}, {"name": "b", )" + pair +
                               R"(, "translation": [3, 1, 0], "embedding": "rbf"},
                                  {"name": "no render", "mesh": ")" +
                               kAssets + R"(/meshes/suzanne_cage.obj"}]})",
                           "folds.json", "");
  const FoldWatch watch(scene, 200);
  EXPECT_EQ(watch.watchedBodies(), 2);
  EXPECT_TRUE(watch.folded(scene).empty());
  auto transform = [&](int body, const Mat3& M) {
    const BodyHandle h = scene.bodies[size_t(body)].handle;
    const Eigen::MatrixX3d x = scene.world.positions(h).cast<double>();
    const Vec3 c = x.colwise().mean().transpose();
    Eigen::MatrixX3d y = x;
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      y.row(i) = (M * (x.row(i).transpose() - c) + c + Vec3(0.2, 0.5, -0.1)).transpose();
    scene.world.setState(h, y, Eigen::MatrixX3d::Zero(x.rows(), 3));
  };
  transform(0, Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix());
  EXPECT_TRUE(watch.folded(scene).empty());
  transform(1, Mat3(Vec3(-1, 1, 1).asDiagonal()));
  const std::vector<FoldWatch::BodyFolds> folds = watch.folded(scene);
  ASSERT_EQ(folds.size(), 1u);
  EXPECT_EQ(folds[0].body, 1);
  EXPECT_EQ(folds[0].report.folded, folds[0].report.samples);
  EXPECT_NEAR(folds[0].report.minDeterminant, -1.0, 1e-3);
}

// A Green body is bound in the mesh file's coordinates and placed scaled and rotated: its face
// frames must carry the placement's scale (stretch against the file's cage) and rotation. At
// rest it shows the placed mesh; moved by a similarity (rotation, uniform scale 0.8,
// translation) its mesh moves by exactly that similarity (Green coordinates reproduce them).
TEST(Scene, GreenBodyFollowsItsPlacementAndSimilarities) {
  Scene scene = parseScene(R"({"bodies": [{"name": "g", "mesh": ")" + kAssets +
                               R"(/meshes/suzanne_cage.obj", "renderMesh": ")" + kAssets +
                               R"(/meshes/suzanne.obj", "embedding": "green", "scale": 1.5,
                                 "rotationDegrees": [10, 40, 0], "translation": [1, 2, 3]}]})",
                           "green.json", "");
  const SceneBody& b = scene.bodies[0];
  ASSERT_TRUE(b.render);
  ASSERT_EQ(b.render->embedding->kind(), cage::EmbeddingKind::Green);
  const mesh::TriangleMesh detail = mesh::readMesh(kAssets + "/meshes/suzanne.obj");
  const Mat3 R = (Eigen::AngleAxisd(0.0, Vec3::UnitZ()) *
                  Eigen::AngleAxisd(40.0 * M_PI / 180.0, Vec3::UnitY()) *
                  Eigen::AngleAxisd(10.0 * M_PI / 180.0, Vec3::UnitX()))
                     .toRotationMatrix();
  PointsRowMajor rest;
  scene.renderVertices(0, rest);
  ASSERT_EQ(size_t(rest.rows()), detail.vertices.size());
  double worst = 0.0;
  for (size_t v = 0; v < detail.vertices.size(); ++v)
    worst = std::max(worst, (rest.row(Eigen::Index(v)).cast<double>().transpose() -
                             (R * (1.5 * detail.vertices[v]) + Vec3(1, 2, 3)))
                                .norm());
  EXPECT_LT(worst, 1e-4);  // float particles and render vertices of a ~2-m body

  const Eigen::MatrixX3d x = scene.world.positions(b.handle).cast<double>();
  const Vec3 c = x.colwise().mean().transpose();
  const Mat3 M = 0.8 * Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 d(0.2, 0.5, -0.1);
  Eigen::MatrixX3d y = x;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    y.row(i) = (M * (x.row(i).transpose() - c) + c + d).transpose();
  scene.world.setState(b.handle, y, Eigen::MatrixX3d::Zero(x.rows(), 3));
  PointsRowMajor moved;
  scene.renderVertices(0, moved);
  worst = 0.0;
  for (Eigen::Index v = 0; v < rest.rows(); ++v)
    worst = std::max(worst, (moved.row(v).cast<double>().transpose() -
                             (M * (rest.row(v).cast<double>().transpose() - c) + c + d))
                                .norm());
  EXPECT_LT(worst, 1e-4);
}

// Saves the scene as dir/saved.json (dir emptied first) and returns the file's text.
std::string saveInFreshFolder(const Scene& scene, const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  saveScene(scene, (dir / "saved.json").string());
  std::ifstream in(dir / "saved.json");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A lattice body: its particles are the lattice's nodes (x fastest), its surface the outer
// layer, its render mesh follows with the lattice's weights (the placed mesh at rest); it falls,
// rests on the floor with its mesh just above it, and saves as a lattice.
TEST(Scene, LatticeBodyFromAMeshWithoutCage) {
  const std::string text = R"({"colliders": [{"type": "plane", "normal": [0, 1, 0], "offset": 0}],
      "bodies": [{"name": "l", "renderMesh": ")" +
                           kAssets + R"(/meshes/suzanne.obj",
        "lattice": {"nodes": [4, 3, 3]}, "translation": [0, 1, 0], "scale": 0.3,
        "rotationDegrees": [0, 30, 0], "alpha": 0.5}]})";
  Scene scene = parseScene(text, "lattice.json", "");
  ASSERT_EQ(scene.bodies.size(), 1u);
  const SceneBody& b = scene.bodies[0];
  ASSERT_TRUE(b.lattice && b.latticeFrame && b.render);
  EXPECT_EQ(scene.world.particleCount(b.handle), 36);
  EXPECT_EQ(b.cageVertexCount, 36);
  EXPECT_EQ(b.cageTriangles.size(), 2u * (2 * (3 * 2) + 2 * (3 * 2) + 2 * (2 * 2)));
  EXPECT_EQ(b.render->embedding->kind(), cage::EmbeddingKind::FfdBernstein);
  const mesh::TriangleMesh detail = mesh::readMesh(kAssets + "/meshes/suzanne.obj");
  const Mat3 R = Eigen::AngleAxisd(30 * M_PI / 180, Vec3::UnitY()).toRotationMatrix();
  PointsRowMajor rendered;
  scene.renderVertices(0, rendered);
  double worst = 0.0;
  for (size_t i = 0; i < detail.vertices.size(); ++i)
    worst = std::max(worst, (rendered.row(Eigen::Index(i)).cast<double>().transpose() -
                             (R * (0.3 * detail.vertices[i]) + Vec3(0, 1, 0)))
                                .norm());
  EXPECT_LT(worst, 1e-5);

  for (int s = 0; s < 240 * 4; ++s) scene.world.step(1.0 / 240);  // 4 s: fallen and settled
  scene.renderVertices(0, rendered);
  const double lowest = rendered.col(1).minCoeff();
  // The surface is the lattice's box, 1 % of the mesh's diagonal (~1 m here) around the mesh.
  EXPECT_GT(lowest, -0.002);
  EXPECT_LT(lowest, 0.03);
  double fastest = 0.0;
  for (Eigen::Index i = 0; i < scene.world.velocities(b.handle).rows(); ++i)
    fastest = std::max(fastest, double(scene.world.velocities(b.handle).row(i).norm()));
  EXPECT_LT(fastest, 0.01);

  const fs::path dir = fs::temp_directory_path() / "softbody_lattice_scene";
  const std::string saved = saveInFreshFolder(scene, dir);
  EXPECT_EQ(saved.find("\"mesh\""), std::string::npos) << saved;
  const Scene back = loadScene((dir / "saved.json").string());
  ASSERT_TRUE(back.bodies[0].lattice);
  EXPECT_EQ(back.bodies[0].lattice->nodes, (std::array<int, 3>{4, 3, 3}));
  EXPECT_EQ(back.world.particleCount(back.bodies[0].handle), 36);
  fs::remove_all(dir);
}

// "clusters": {"kind": "lattice"}: one cluster per node holding the nodes within halfWidth
// index steps on every axis (checked against a pass over all node pairs); the body falls,
// comes to rest on the floor without inflating or collapsing, and saves as lattice regions.
TEST(Scene, LatticeRegionClusters) {
  const std::string text = R"({"colliders": [{"type": "plane", "normal": [0, 1, 0], "offset": 0}],
      "bodies": [{"name": "l", "renderMesh": ")" +
                           kAssets + R"(/meshes/suzanne.obj",
        "lattice": {"nodes": [5, 4, 4]}, "translation": [0, 1, 0], "scale": 0.3,
        "alpha": 0.5, "clusters": {"kind": "lattice", "halfWidth": 1}}]})";
  Scene scene = parseScene(text, "regions.json", "");
  const SceneBody& b = scene.bodies[0];
  ASSERT_TRUE(b.latticeFrame);
  EXPECT_EQ(b.latticeRegionHalfWidth, 1);
  const ClusterDef& def = scene.world.clusterDef(b.handle);
  ASSERT_EQ(def.kind, ClusterDef::Kind::Explicit);
  const std::array<int, 3> n{5, 4, 4};
  ASSERT_EQ(def.clusters.size(), size_t(n[0] * n[1] * n[2]));
  auto ijk = [&](int index) {
    return std::array<int, 3>{index % n[0], (index / n[0]) % n[1], index / (n[0] * n[1])};
  };
  for (int c = 0; c < int(def.clusters.size()); ++c) {
    std::vector<int> expected;
    for (int m = 0; m < n[0] * n[1] * n[2]; ++m) {
      int far = 0;
      for (int a = 0; a < 3; ++a)
        far = std::max(far, std::abs(ijk(c)[size_t(a)] - ijk(m)[size_t(a)]));
      if (far <= 1) expected.push_back(m);
    }
    EXPECT_EQ(def.clusters[size_t(c)], expected) << "region of node " << c;
  }
  EXPECT_EQ(def.clusters[0].size(), 8u);                             // a corner
  EXPECT_EQ(def.clusters[size_t(1 + 5 * (1 + 4 * 1))].size(), 27u);  // inside

  auto extent = [&] {
    const Eigen::MatrixX3d x = scene.world.positions(b.handle).cast<double>();
    return Vec3(x.colwise().maxCoeff() - x.colwise().minCoeff());
  };
  const Vec3 restExtent = extent();
  for (int s = 0; s < 240 * 6; ++s) scene.world.step(1.0 / 240);  // 6 s: fallen and settled
  double fastest = 0.0;
  for (Eigen::Index i = 0; i < scene.world.velocities(b.handle).rows(); ++i)
    fastest = std::max(fastest, double(scene.world.velocities(b.handle).row(i).norm()));
  EXPECT_LT(fastest, 0.01);
  PointsRowMajor rendered;
  scene.renderVertices(0, rendered);
  EXPECT_GT(rendered.col(1).minCoeff(), -0.002);
  const Vec3 restingExtent = extent();
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(restingExtent[a] / restExtent[a], 1.0, 0.05) << "axis " << a;

  const fs::path dir = fs::temp_directory_path() / "softbody_lattice_regions";
  const std::string saved = saveInFreshFolder(scene, dir);
  EXPECT_NE(saved.find("\"kind\": \"lattice\""), std::string::npos) << saved;
  const Scene back = loadScene((dir / "saved.json").string());
  EXPECT_EQ(back.world.clusterDef(back.bodies[0].handle).clusters, def.clusters);
  fs::remove_all(dir);
}

TEST(Scene, LatticeErrorsNameTheField) {
  const std::string suzanne = kAssets + "/meshes/suzanne.obj";
  auto with = [&](const std::string& fields) {
    return R"({"bodies": [{"name": "b", )" + fields + "}]}";
  };
  const std::string render = R"("renderMesh": ")" + suzanne + R"(", )";
  expectSceneError(with(R"("lattice": {"nodes": [4, 4, 4]})"),
                   "bodies[0].renderMesh: is required with a lattice");
  expectSceneError(with(render + R"("mesh": ")" + suzanne + R"(", "lattice": {})"),
                   "bodies[0].mesh: a lattice body's particles are its lattice's nodes");
  expectSceneError(with(render + R"("lattice": {"nodes": [4, 4]})"),
                   "bodies[0].lattice.nodes: must be three integers");
  expectSceneError(with(render + R"("lattice": {"nodes": [4, 1, 4]})"),
                   "bodies[0].lattice.nodes: each must be an integer in [2, 64], got 1");
  expectSceneError(with(render + R"("lattice": {"basis": "nurbs"})"),
                   "bodies[0].lattice.basis: must be bspline or bernstein, got 'nurbs'");
  expectSceneError(with(render + R"("lattice": {"nodes": [3, 4, 4], "basis": "bspline"})"),
                   "bodies[0].lattice: nodes: 3 on axis x");
  expectSceneError(
      with(render + R"("lattice": {}, "clusters": {"kind": "lattice", "halfWidth": 0})"),
      "bodies[0].clusters.halfWidth: must be in [1, 16], got 0");
  expectSceneError(R"({"bodies": [{"name": "b", "mesh": ")" + suzanne +
                       R"(", "clusters": {"kind": "lattice"}}]})",
                   "bodies[0].clusters.kind: 'lattice' regions need a lattice body");
  expectSceneError(with(render + R"("lattice": {"margin": 2})"),
                   "bodies[0].lattice.margin: must be in [0, 1], got 2");
  expectSceneError(with(render + R"("lattice": {}, "embedding": "rbf")"),
                   "bodies[0].embedding: a lattice body's particles are its lattice's nodes");
}

TEST(Scene, EmbeddingErrorsNameTheField) {
  const std::string render = R"(, "renderMesh": ")" + kAssets + R"(/meshes/suzanne.obj")";
  expectSceneError(body(render + R"(, "embedding": "nope")"),
                   "bodies[0].embedding: must be mvc, harmonic, rbf or green, got 'nope'");
  expectSceneError(body(render + R"(, "embedding": "ffd-bspline")"),
                   "bodies[0].embedding: 'ffd-bspline' is how a lattice body's render mesh");
  // Green coordinates are defined inside the cage only: the bunny sticks out of suzanne's.
  expectSceneError(
      body(R"(, "renderMesh": ")" + kAssets + R"(/meshes/bunny.obj", "embedding": "green")"),
      "is outside the cage");
  expectSceneError(body(render + R"(, "embedding": 3)"),
                   "bodies[0].embedding: must be a method name or an object");
  expectSceneError(body(render + R"(, "embedding": {"shape": 1})"),
                   "bodies[0].embedding.method: is required");
  expectSceneError(body(render + R"(, "embedding": {"method": "rbf", "shape": 11})"),
                   "bodies[0].embedding.shape: must be in [0, 10], got 11");
  expectSceneError(body(render + R"(, "embedding": {"method": "harmonic", "resolution": 3})"),
                   "bodies[0].embedding.resolution: must be in [4, 64], got 3");
  expectSceneError(body(render + R"(, "embedding": {"method": "harmonic", "resolutoin": 8})"),
                   "bodies[0].embedding.resolutoin: unknown field");
  expectSceneError(body(R"(, "embedding": "rbf")"),
                   "bodies[0].embedding: needs a render mesh to embed");
}

TEST(Scene, RestitutionAndSleepAreReadFromTheFile) {
  const Scene scene = parseScene(
      R"({"world": {"sleep": false, "restitutionThreshold": 0.5, "rollingResistance": 0},
          "colliders": [{"type": "plane", "restitution": 0.8}], "bodies": []})",
      "inline", ".");
  EXPECT_FALSE(scene.world.settings().sleep);
  EXPECT_DOUBLE_EQ(scene.world.settings().restitutionThreshold, 0.5);
  EXPECT_EQ(scene.world.settings().rollingResistance, 0.0);
  ASSERT_EQ(scene.world.colliders().size(), 1u);
  EXPECT_DOUBLE_EQ(scene.world.colliders()[0].restitution, 0.8);
}

TEST(Scene, MissingFileIsAClearError) {
  try {
    loadScene("/definitely/not/here.json");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/definitely/not/here.json: cannot open"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace sb

namespace sb {
namespace {

// Frames written by `softbody run --export`: read back independently and compared with the
// World's positions.
TEST(FrameExport, BinaryAndObjFramesHoldTheParticlePositions) {
  Scene scene = loadScene(defaultScenePath());
  for (int s = 0; s < 10; ++s) scene.world.step();
  const fs::path dir = fs::temp_directory_path() / "softbody_frame_test";
  fs::create_directories(dir);
  const std::string bin = (dir / "f.bin").string(), obj = (dir / "f.obj").string();
  writeFrame(scene, bin, FrameFormat::Binary);
  writeFrame(scene, obj, FrameFormat::Obj);

  std::ifstream in(bin, std::ios::binary);
  char magic[8];
  in.read(magic, 8);
  ASSERT_EQ(std::string(magic, 8), "SBFRAME1");
  std::uint32_t bodies = 0;
  double time = 0;
  in.read(reinterpret_cast<char*>(&bodies), 4);
  in.read(reinterpret_cast<char*>(&time), 8);
  ASSERT_EQ(bodies, scene.bodies.size());
  EXPECT_DOUBLE_EQ(time, scene.world.time());
  size_t total = 0;
  for (const SceneBody& b : scene.bodies) {
    std::uint32_t n = 0;
    in.read(reinterpret_cast<char*>(&n), 4);
    const ConstPointsRef x = scene.world.positions(b.handle);
    ASSERT_EQ(n, static_cast<std::uint32_t>(x.rows()));
    for (std::uint32_t i = 0; i < n; ++i) {
      float p[3];
      in.read(reinterpret_cast<char*>(p), sizeof p);
      for (int a = 0; a < 3; ++a) ASSERT_EQ(p[a], x(int(i), a));
    }
    total += n;
  }
  EXPECT_EQ(in.peek(), EOF);  // nothing after the last body

  std::ifstream text(obj);
  std::string line;
  size_t vertices = 0, objects = 0;
  double firstX = 0;
  while (std::getline(text, line)) {
    if (line.rfind("v ", 0) == 0) {
      if (vertices == 0) firstX = std::stod(line.substr(2));
      ++vertices;
    }
    if (line.rfind("o ", 0) == 0) ++objects;
  }
  EXPECT_EQ(vertices, total);
  EXPECT_EQ(objects, scene.bodies.size());
  EXPECT_NEAR(firstX, scene.world.positions(scene.bodies[0].handle)(0, 0), 1e-6);
}

}  // namespace
}  // namespace sb

namespace sb {
namespace {

// The runner skips the deform of bodies that sleep and were deformed since they fell asleep;
// its meshes must still equal a fresh deform at every moment: while the scene rests, and after
// a body is moved (which wakes it) and steps on.
TEST(SceneRunner, MeshesOfSleepingBodiesStayCurrent) {
  Scene scene = loadScene(defaultScenePath());
  SceneRunner runner(scene, /*deform=*/true);
  auto expectCurrent = [&](const char* when) {
    for (size_t i = 0; i < scene.bodies.size(); ++i) {
      PointsRowMajor fresh;
      scene.renderVertices(int(i), fresh);
      EXPECT_TRUE(fresh == runner.renderMeshes()[i]) << when << ", body " << i;
    }
  };
  int steps = 0;
  while (scene.world.sleepingCount() < int(scene.bodies.size()) && steps < 1200) {
    runner.step();
    ++steps;
  }
  ASSERT_EQ(scene.world.sleepingCount(), int(scene.bodies.size())) << "not asleep in 20 s";
  for (int s = 0; s < 3; ++s) runner.step();
  expectCurrent("asleep");
  const BodyHandle b = scene.bodies[1].handle;
  Eigen::MatrixX3d x = scene.world.positions(b).cast<double>();
  x.col(1).array() += 0.2;  // lifted: it wakes and falls back
  scene.world.setState(b, x, Eigen::MatrixX3d::Zero(x.rows(), 3));
  for (int s = 0; s < 30; ++s) {
    runner.step();
    expectCurrent("after the lift");
  }
}

}  // namespace
}  // namespace sb

namespace sb {
namespace {

// Bodies added to and removed from a loaded scene, as the viewer does for a mesh dropped on it:
// the same fields and checks as in a scene file; a bad body leaves the scene as it was.
TEST(Scene, BodiesAreAddedAndRemovedOneAtATime) {
  Scene scene = loadScene(defaultScenePath());
  const size_t before = scene.bodies.size();
  const std::string dir = std::string(SOFTBODY_ASSET_DIR) + "/meshes";
  const int added = addSceneBody(scene, R"({"name": "extra", "mesh": "bunny_cage.obj",
      "translation": [0, 3, 0], "scale": 0.1, "mode": "rigid", "alpha": 1})",
                                 "dropped", dir);
  ASSERT_EQ(scene.bodies.size(), before + 1);
  EXPECT_EQ(added, int(before));
  const BodyHandle h = scene.bodies[size_t(added)].handle;
  EXPECT_EQ(scene.world.name(h), "extra");
  EXPECT_EQ(scene.world.params(h).mode, Mode::Rigid);
  EXPECT_NEAR(scene.world.centreOfMass(h).y(), 3.0, 0.6);  // the file's origin is not its centre
  for (int s = 0; s < 60; ++s) scene.world.step();
  EXPECT_LT(scene.world.centreOfMass(h).y(), 3.0);  // it falls with the rest

  const std::uint64_t hash = scene.world.stateHash();
  try {
    addSceneBody(scene, R"({"mesh": "bunny_cage.obj", "alpha": 3})", "dropped", dir);
    ADD_FAILURE() << "alpha 3 was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("dropped: alpha"), std::string::npos) << e.what();
  }
  EXPECT_EQ(scene.bodies.size(), before + 1);
  EXPECT_EQ(scene.world.stateHash(), hash);

  const BodyHandle first = scene.bodies[0].handle;
  removeSceneBody(scene, 0);
  ASSERT_EQ(scene.bodies.size(), before);
  EXPECT_FALSE(scene.world.contains(first));
  EXPECT_EQ(scene.world.name(scene.bodies.back().handle), "extra");
  for (const SceneBody& b : scene.bodies) EXPECT_TRUE(scene.world.contains(b.handle));
  for (int s = 0; s < 10; ++s) scene.world.step();
  EXPECT_TRUE(scene.world.positions(scene.bodies.back().handle).allFinite());
}

// The viewer prepares a mesh body (reads it, makes its automatic cage, binds it) on another
// thread while the scene steps, then adds it: the same World, bit for bit, as stepping first and
// adding it in one call. Under TSan this also checks that preparing touches nothing the step uses.
TEST(Scene, ABodyPreparedWhileTheSceneStepsIsTheBodyAddedInOneCall) {
  const std::string dir = std::string(SOFTBODY_ASSET_DIR) + "/meshes";
  const std::string body = R"({"name": "dropped", "renderMesh": "bunny.obj",
      "cage": {"auto": true, "vertices": 120}, "translation": [0, 2.5, 0], "scale": 0.1,
      "mode": "linear", "alpha": 0.5})";
  // Prepared first: with an empty cache the cage is made while the scene steps.
  Scene twoParts = loadScene(defaultScenePath());
  std::future<PreparedBody> prepared =
      std::async(std::launch::async, [&] { return prepareSceneBody(body, "dropped", dir); });
  for (int s = 0; s < 30; ++s) twoParts.world.step();
  const int b = addPreparedBody(twoParts, prepared.get());

  Scene oneCall = loadScene(defaultScenePath());
  for (int s = 0; s < 30; ++s) oneCall.world.step();
  const int a = addSceneBody(oneCall, body, "dropped", dir);
  EXPECT_EQ(a, b);
  EXPECT_EQ(twoParts.world.stateHash(), oneCall.world.stateHash());
  EXPECT_EQ(twoParts.bodies[size_t(b)].render->path, oneCall.bodies[size_t(a)].render->path);
  for (int s = 0; s < 30; ++s) {
    oneCall.world.step();
    twoParts.world.step();
  }
  EXPECT_EQ(twoParts.world.stateHash(), oneCall.world.stateHash());
}

// A body whose cage file has quad faces: it loads (closed surface over the fan triangles,
// contact surface from them) and its render mesh is bound with polygon mean value coordinates,
// so the weights do not depend on the corner each quad starts at in the file.
TEST(Scene, QuadCageBodyBindsWithPolygonMvc) {
  const fs::path dir = fs::temp_directory_path() / "softbody_quad_cage_scene";
  fs::remove_all(dir);
  fs::create_directories(dir);
  ::setenv("SOFTBODY_CACHE_DIR", (dir / "cache").c_str(), 1);
  // A box [0,2]×[0,1]×[0,1.5] of six quads, written twice: each quad from its first corner and
  // from its second (the other diagonal for a fan triangulation).
  const std::vector<std::vector<int>> faces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                               {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int rotate = 0; rotate < 2; ++rotate) {
    std::ofstream f(dir / ("cage" + std::to_string(rotate) + ".obj"));
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) f << "v " << 2 * i << " " << j << " " << 1.5 * k << "\n";
    for (const auto& face : faces) {
      f << "f";
      for (int c = 0; c < 4; ++c) f << " " << face[size_t((c + rotate) % 4)] + 1;
      f << "\n";
    }
  }
  {
    std::ofstream f(dir / "detail.obj");
    f << "v 0.3 0.2 0.2\nv 1.7 0.3 0.4\nv 1.0 0.8 0.3\nv 0.9 0.5 1.3\n"
         "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  }
  std::vector<std::vector<std::pair<int, double>>> rows[2];
  for (int rotate = 0; rotate < 2; ++rotate) {
    const std::string text = R"({"bodies": [{"name": "q", "mesh": ")" +
                             (dir / ("cage" + std::to_string(rotate) + ".obj")).string() +
                             R"(", "renderMesh": ")" + (dir / "detail.obj").string() +
                             R"(", "translation": [0, 1, 0]}]})";
    Scene scene = parseScene(text, "quad.json", "");
    ASSERT_EQ(scene.bodies.size(), 1u);
    const SceneBody& b = scene.bodies[0];
    EXPECT_EQ(b.cageVertexCount, 8);
    EXPECT_EQ(b.cageTriangles.size(), 12u);
    EXPECT_EQ(b.cagePolygonOf.size(), 12u);
    ASSERT_TRUE(b.render && b.render->embedding);
    for (int i = 0; i < 4; ++i) {
      rows[rotate].emplace_back();
      b.render->embedding->rowWeights(i, rows[rotate].back());
    }
    // A re-bind (the viewer's switch) binds the quads as the load did.
    rebindRenderMesh(scene, 0, cage::EmbeddingMethod{});
    std::vector<std::pair<int, double>> again;
    for (int i = 0; i < 4; ++i) {
      scene.bodies[0].render->embedding->rowWeights(i, again);
      ASSERT_EQ(again.size(), rows[rotate][size_t(i)].size());
      for (size_t k = 0; k < again.size(); ++k)
        EXPECT_NEAR(again[k].second, rows[rotate][size_t(i)][k].second, 1e-12);
    }
    // At rest the render mesh is the placed file.
    PointsRowMajor rendered;
    scene.renderVertices(0, rendered);
    ASSERT_EQ(rendered.rows(), 4);
    EXPECT_NEAR(rendered(0, 1), 1.2f, 1e-6f);
    EXPECT_NEAR(rendered(3, 2), 1.3f, 1e-6f);
  }
  // Same weights from both files (a triangle bind would not give them: test_polygon_mvc.cpp).
  for (int i = 0; i < 4; ++i) {
    ASSERT_EQ(rows[0][size_t(i)].size(), rows[1][size_t(i)].size());
    for (size_t k = 0; k < rows[0][size_t(i)].size(); ++k)
      EXPECT_NEAR(rows[0][size_t(i)][k].second, rows[1][size_t(i)][k].second, 1e-14);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sb
