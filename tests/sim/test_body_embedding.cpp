// Switching a body's embedding in a running scene (sim/scene/body_embedding.h) and watching it
// for folds afterwards (sim/scene/fold_watch.h).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <stdexcept>
#include <string>

#include "sim/scene/body_embedding.h"
#include "sim/scene/fold_watch.h"
#include "sim/scene/scene.h"

namespace sb {
namespace {

const std::string kAssets = SOFTBODY_ASSET_DIR;
const std::string kPair = R"("mesh": ")" + kAssets +
                          R"(/meshes/suzanne_cage.obj", "renderMesh": ")" + kAssets +
                          R"(/meshes/suzanne.obj")";

// Two bodies sharing one mesh–cage pair (so one RenderMesh), placed differently, and a lattice.
Scene twoSuzannes(const std::string& embedding = "") {
  const std::string extra = embedding.empty() ? "" : R"(, "embedding": )" + embedding;
  return parseScene(
      R"({"bodies": [{"name": "a", )" + kPair +
          R"(, "translation": [0, 1, 0], "rotationDegrees": [10, 20, 30], "scale": 0.5)" + extra +
          R"(}, {"name": "b", )" + kPair +
          R"(, "translation": [3, 1, 0], "rotationDegrees": [10, 20, 30], "scale": 0.5)" + extra +
          R"(}, {"name": "l", "renderMesh": ")" + kAssets +
          R"(/meshes/suzanne.obj", "lattice": {"nodes": [4, 4, 4]},
                           "translation": [-3, 1, 0]}]})",
      "switch.json", "");
}

cage::EmbeddingMethod harmonic(int resolution) {
  cage::EmbeddingMethod m;
  m.kind = cage::EmbeddingKind::Harmonic;
  m.harmonic.resolution = resolution;
  return m;
}

// The rebound mesh is the one a scene file naming the method binds: the same render vertices
// (to float rounding of the placed start positions), the same kind, and the scene saves it.
TEST(BodyEmbedding, RebindMatchesALoadWithThatMethod) {
  Scene scene = twoSuzannes();
  ASSERT_EQ(scene.bodies[0].render->embedding->kind(), cage::EmbeddingKind::MeanValue);
  rebindRenderMesh(scene, 0, harmonic(8));
  EXPECT_EQ(scene.bodies[0].embedding.kind, cage::EmbeddingKind::Harmonic);
  EXPECT_EQ(scene.bodies[0].embedding.harmonic.resolution, 8);
  EXPECT_EQ(scene.bodies[0].render->embedding->kind(), cage::EmbeddingKind::Harmonic);

  const Scene loaded = twoSuzannes(R"({"method": "harmonic", "resolution": 8})");
  PointsRowMajor ours, theirs, mvc;
  scene.renderVertices(0, ours);
  loaded.renderVertices(0, theirs);
  twoSuzannes().renderVertices(0, mvc);
  ASSERT_EQ(ours.rows(), theirs.rows());
  // Harmonic at resolution 8 differs visibly from mean value coordinates (so the comparison
  // below can tell the methods apart), and matches the file's bind to rounding.
  EXPECT_GT((ours - mvc).cwiseAbs().maxCoeff(), 1e-3f);
  EXPECT_LT((ours - theirs).cwiseAbs().maxCoeff(), 1e-5f);
  EXPECT_NE(sceneText(scene, "x.json").find(R"("method": "harmonic")"), std::string::npos);
}

// The other body sharing the pair keeps its binding; switching back gives mean value again.
TEST(BodyEmbedding, SharedRenderMeshesAreNotTouched) {
  Scene scene = twoSuzannes();
  ASSERT_EQ(scene.bodies[0].render, scene.bodies[1].render);
  const auto shared = scene.bodies[1].render;
  cage::EmbeddingMethod rbf;
  rbf.kind = cage::EmbeddingKind::Rbf;
  rbf.rbf.shape = 2.0;
  rebindRenderMesh(scene, 0, rbf);
  EXPECT_EQ(scene.bodies[1].render, shared);
  EXPECT_EQ(scene.bodies[1].render->embedding->kind(), cage::EmbeddingKind::MeanValue);
  EXPECT_EQ(scene.bodies[1].embedding.kind, cage::EmbeddingKind::MeanValue);
  EXPECT_EQ(scene.bodies[0].render->embedding->kind(), cage::EmbeddingKind::Rbf);
  EXPECT_EQ(scene.bodies[0].embedding.rbf.shape, 2.0);

  rebindRenderMesh(scene, 0, cage::EmbeddingMethod{});
  PointsRowMajor back, original;
  scene.renderVertices(0, back);
  twoSuzannes().renderVertices(0, original);
  EXPECT_LT((back - original).cwiseAbs().maxCoeff(), 1e-5f);
  EXPECT_TRUE(sameEmbeddingMethod(scene.bodies[0].embedding, cage::EmbeddingMethod{}));
  EXPECT_FALSE(sameEmbeddingMethod(harmonic(8), harmonic(16)));
}

// A refused bind leaves the body as it was: the same RenderMesh object, the same method.
TEST(BodyEmbedding, RefusalKeepsTheOldBinding) {
  Scene scene = twoSuzannes();
  const auto before = scene.bodies[0].render;
  // Resolution 65 the cage library would bind (in seconds), but a scene file refuses it.
  EXPECT_THROW(rebindRenderMesh(scene, 0, harmonic(65)), std::invalid_argument);
  EXPECT_THROW(rebindRenderMesh(scene, 0, harmonic(3)), std::invalid_argument);
  cage::EmbeddingMethod badShape;
  badShape.kind = cage::EmbeddingKind::Rbf;
  badShape.rbf.shape = 11.0;
  EXPECT_THROW(rebindRenderMesh(scene, 0, badShape), std::invalid_argument);
  cage::EmbeddingMethod lattice;
  lattice.kind = cage::EmbeddingKind::FfdBSpline;
  EXPECT_THROW(rebindRenderMesh(scene, 0, lattice), std::invalid_argument);
  EXPECT_EQ(scene.bodies[0].render, before);
  EXPECT_EQ(scene.bodies[0].embedding.kind, cage::EmbeddingKind::MeanValue);
  // A lattice body's mesh follows its nodes; an index outside the scene is refused.
  EXPECT_THROW(rebindRenderMesh(scene, 2, harmonic(8)), std::invalid_argument);
  EXPECT_THROW(rebindRenderMesh(scene, 3, harmonic(8)), std::out_of_range);
}

// A scene parsed from text keeps its paths relative to the folder it was given: a switch reads
// the render mesh from there (not from the working folder), a body added from another folder
// is written against the same folder, and a save elsewhere rebases both.
TEST(BodyEmbedding, RelativePathsOfAParsedSceneResolveAgainstItsFolder) {
  const std::string scenes = kAssets + "/scenes";
  Scene scene = parseScene(
      R"({"bodies": [{"name": "a", "mesh": "../meshes/suzanne_cage.obj",
                      "renderMesh": "../meshes/suzanne.obj"}]})",
      "relative.json", scenes);
  EXPECT_EQ(scene.meshFolder, scenes);
  ASSERT_NO_THROW(rebindRenderMesh(scene, 0, harmonic(8)));
  EXPECT_EQ(scene.bodies[0].render->path, "../meshes/suzanne.obj");

  const int added = addSceneBody(
      scene, R"({"name": "b", "mesh": "suzanne_cage.obj", "renderMesh": "suzanne.obj"})", "b",
      kAssets + "/meshes");
  EXPECT_EQ(scene.bodies[size_t(added)].meshPath, "../meshes/suzanne_cage.obj");
  EXPECT_EQ(scene.bodies[size_t(added)].render->path, "../meshes/suzanne.obj");
  ASSERT_NO_THROW(rebindRenderMesh(scene, added, harmonic(8)));

  // Saved beside the meshes: both bodies name them from there.
  const std::string saved = sceneText(scene, kAssets + "/meshes/x.json");
  EXPECT_EQ(saved.find("../meshes/"), std::string::npos) << saved;
  EXPECT_NE(saved.find(R"("renderMesh": "suzanne.obj")"), std::string::npos) << saved;
}

// Mirror body `body` through its centre (turns its map inside out: every sample folds).
void mirror(Scene& scene, int body) {
  const BodyHandle h = scene.bodies[size_t(body)].handle;
  const Eigen::MatrixX3d x = scene.world.positions(h).cast<double>();
  const Vec3 c = x.colwise().mean().transpose();
  Eigen::MatrixX3d y = x;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    y.row(i) = (Vec3(-1, 1, 1).asDiagonal() * (x.row(i).transpose() - c) + c).transpose();
  scene.world.setState(h, y, Eigen::MatrixX3d::Zero(x.rows(), 3));
}

// foldedRegions reports what folded() does, with a point per folded sample inside the body;
// a watch in the start pose made after the body folded still sees the fold; rewatch follows a
// switched method.
TEST(BodyEmbedding, FoldRegionsAndRewatchAfterASwitch) {
  Scene scene = twoSuzannes();
  FoldWatch watch(scene, 200);
  EXPECT_TRUE(watch.foldedRegions(scene).empty());
  mirror(scene, 1);
  const std::vector<FoldWatch::BodyFolds> folds = watch.folded(scene);
  const std::vector<FoldWatch::FoldedRegion> regions = watch.foldedRegions(scene);
  ASSERT_EQ(folds.size(), 1u);
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_EQ(regions[0].body, 1);
  EXPECT_EQ(regions[0].report.folded, folds[0].report.folded);
  EXPECT_EQ(static_cast<int>(regions[0].points.size()), regions[0].report.folded);
  EXPECT_GT(regions[0].spacing, 0.0);
  const ConstPointsRef x = scene.world.positions(scene.bodies[1].handle);
  const Eigen::RowVector3f lo = x.colwise().minCoeff(), hi = x.colwise().maxCoeff();
  for (const Vec3& p : regions[0].points)
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(p[a], lo[a] - 1e-6);
      EXPECT_LE(p[a], hi[a] + 1e-6);
    }

  FoldWatch fromStart(scene, 200, FoldWatch::Pose::Start);
  const std::vector<FoldWatch::FoldedRegion> startRegions = fromStart.foldedRegions(scene);
  ASSERT_EQ(startRegions.size(), 1u);
  EXPECT_EQ(startRegions[0].body, 1);
  EXPECT_EQ(startRegions[0].report.folded, startRegions[0].report.samples);

  // After a switch, the body's samples are bound with the new method (an RBF map of the mirror
  // folds too); the other bodies' watches are kept. (In the start pose: the mirrored cage, turned
  // inward, is no pose to sample in.)
  cage::EmbeddingMethod rbf;
  rbf.kind = cage::EmbeddingKind::Rbf;
  rebindRenderMesh(scene, 1, rbf);
  fromStart.rewatch(scene, 1);
  EXPECT_EQ(fromStart.watchedBodies(), 3);
  const std::vector<FoldWatch::FoldedRegion> after = fromStart.foldedRegions(scene);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].body, 1);
  EXPECT_EQ(after[0].report.folded, after[0].report.samples);
}

}  // namespace
}  // namespace sb
