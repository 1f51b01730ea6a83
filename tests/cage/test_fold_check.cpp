// The fold check (sim/cage/fold_check.h): det J against closed forms for affine motions (rest,
// a shear-and-scale, a mirror), a cage pushed through itself found folded where a moderate push
// is not, the same with RBF weights, and refused input.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sim/cage/embedding.h"
#include "sim/cage/fold_check.h"
#include "sim/cage/green.h"
#include "sim/cage/rbf.h"
#include "sim/mesh/mesh_io.h"
#include "tests/cage/cage_test_data.h"
#include "tests/mesh/mesh_fixtures.h"

namespace sb::cage {
namespace {

using MatX3d = Eigen::Matrix<double, Eigen::Dynamic, 3>;
using namespace test_data;

FoldProbes mvcProbes(const mesh::TriangleMesh& cage, int target = 600) {
  const FoldSampling s = foldSamples(cage, target);
  return makeFoldProbes(s.samples, s.step, [&](const std::vector<Vec3>& p) {
    BindOptions o;
    o.storage = WeightStorage::Dense;
    return bindMeanValue(p, cage, o);
  });
}

// The winding number of a closed, outward triangle mesh about p: Σ solid angles / 4π (the Van
// Oosterom–Strackee formula), 1 inside, 0 outside; computed here independently of the library.
double windingNumber(const Vec3& p, const mesh::TriangleMesh& m) {
  double sum = 0.0;
  for (const auto& t : m.triangles) {
    const Vec3 a = m.vertices[size_t(t[0])] - p, b = m.vertices[size_t(t[1])] - p,
               c = m.vertices[size_t(t[2])] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    sum += 2.0 * std::atan2(a.dot(b.cross(c)),
                            la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return sum / (4.0 * M_PI);
}

TEST(FoldCheck, SamplesLieInsideWithTheirOffsets) {
  const auto& cage = bunnyCage();
  const FoldSampling s = foldSamples(cage, 600);
  EXPECT_GE(s.samples.size(), 300u);
  EXPECT_LE(s.samples.size(), 3000u);
  ASSERT_GT(s.step, 0.0);
  // Every sample and each of its three offsets (the points the probes bind) is inside the cage.
  int outside = 0;
  for (const Vec3& x : s.samples)
    for (int d = -1; d < 3; ++d)
      if (windingNumber(d < 0 ? x : Vec3(x + s.step * Vec3::Unit(d)), cage) < 0.5) ++outside;
  EXPECT_EQ(outside, 0);
}

TEST(FoldCheck, AffineMotionsGiveTheirDeterminant) {
  const auto& cage = bunnyCage();
  const FoldProbes probes = mvcProbes(cage);
  const MatX3d rest = toMatrix(cage.vertices);
  const FoldReport atRest = checkFolds(probes, rest);
  EXPECT_EQ(atRest.folded, 0);
  EXPECT_NEAR(atRest.minDeterminant, 1.0, 1e-6);
  EXPECT_EQ(atRest.samples, int(probes.samples.size()));

  const Mat3 A = (Mat3() << 1.2, 0.3, -0.1, -0.2, 0.9, 0.4, 0.15, -0.25, 1.1).finished();
  for (const Mat3& M : {A, Mat3(Vec3(-1, 1, 1).asDiagonal())}) {  // a shear, a mirror
    MatX3d moved = rest;
    for (Eigen::Index j = 0; j < moved.rows(); ++j)
      moved.row(j) = (M * rest.row(j).transpose() + Vec3(3, -2, 1)).transpose();
    const FoldReport r = checkFolds(probes, moved);
    EXPECT_NEAR(r.minDeterminant, M.determinant(), 1e-6 * std::abs(M.determinant()));
    EXPECT_EQ(r.folded, M.determinant() > 0 ? 0 : r.samples);
  }
}

// A box cage whose top-centre vertex is pushed down: by a fifth of the height the map only
// squashes; through the bottom it turns the region under that vertex inside out.
TEST(FoldCheck, ACagePushedThroughItselfIsFoundFolded) {
  const mesh::TriangleMesh cage = mesh::testing::makeBox(2, 2, 2);
  int top = -1;
  for (int j = 0; j < int(cage.vertices.size()); ++j)
    if ((cage.vertices[size_t(j)] - Vec3(0.5, 0.5, 1.0)).norm() < 1e-12) top = j;
  ASSERT_GE(top, 0);
  const FoldProbes probes = mvcProbes(cage, 1000);
  MatX3d moved = toMatrix(cage.vertices);
  moved(top, 2) = 0.8;
  const FoldReport mild = checkFolds(probes, moved);
  EXPECT_EQ(mild.folded, 0);
  EXPECT_LT(mild.minDeterminant, 1.0);
  moved(top, 2) = -0.8;
  const FoldReport through = checkFolds(probes, moved);
  EXPECT_GT(through.folded, 0);
  EXPECT_LE(through.minDeterminant, 0.0);
  // The worst sample lies under the pushed vertex (the upper middle of the box).
  const Vec3 worst = probes.samples[size_t(through.worstSample)];
  EXPECT_LT((worst.head<2>() - Eigen::Vector2d(0.5, 0.5)).norm(), 0.35) << worst.transpose();
}

TEST(FoldCheck, WorksForAnyEmbedding) {
  const mesh::TriangleMesh cage = mesh::testing::makeBox(2, 2, 2);
  const FoldSampling s = foldSamples(cage, 500);
  const FoldProbes probes = makeFoldProbes(
      s.samples, s.step, [&](const std::vector<Vec3>& p) { return bindRbf(p, cage.vertices); });
  MatX3d moved = toMatrix(cage.vertices);
  EXPECT_EQ(checkFolds(probes, moved).folded, 0);
  for (Eigen::Index j = 0; j < moved.rows(); ++j) moved(j, 0) = -moved(j, 0);  // mirrored
  EXPECT_EQ(checkFolds(probes, moved).folded, int(s.samples.size()));
}

// Green coordinates take the cage's vertices like the others (their face frames are added by
// the embedding): a cage at rest does not fold, one pushed through itself does.
TEST(FoldCheck, ChecksGreenMapsThroughTheCageVertices) {
  const mesh::TriangleMesh cage = mesh::testing::makeBox(2, 2, 2);
  const FoldSampling s = foldSamples(cage, 500);
  const FoldProbes probes = makeFoldProbes(
      s.samples, s.step, [&](const std::vector<Vec3>& p) { return bindGreen(p, cage); });
  MatX3d moved = toMatrix(cage.vertices);
  const FoldReport rest = checkFolds(probes, moved);
  EXPECT_EQ(rest.folded, 0);
  EXPECT_NEAR(rest.minDeterminant, 1.0, 1e-6);
  int top = -1;
  for (int j = 0; j < int(cage.vertices.size()); ++j)
    if ((cage.vertices[size_t(j)] - Vec3(0.5, 0.5, 1.0)).norm() < 1e-12) top = j;
  ASSERT_GE(top, 0);
  moved(top, 2) = -0.8;
  EXPECT_GT(checkFolds(probes, moved).folded, 0);
}

TEST(FoldCheck, RefusesBadInput) {
  const mesh::TriangleMesh cage = mesh::testing::makeBox(1, 1, 1);
  auto bind = [&](const std::vector<Vec3>& p) { return bindMeanValue(p, cage); };
  EXPECT_THROW((void)makeFoldProbes({Vec3(0.5, 0.5, 0.5)}, 0.0, bind), std::invalid_argument);
  EXPECT_THROW((void)makeFoldProbes({Vec3(0.5, 0.5, 0.5)}, std::nan(""), bind),
               std::invalid_argument);
  EXPECT_THROW((void)makeFoldProbes({}, 0.01, bind), std::invalid_argument);
  EXPECT_THROW((void)foldSamples(cage, 7), std::invalid_argument);
  mesh::TriangleMesh open = cage;
  open.triangles.pop_back();
  EXPECT_THROW((void)foldSamples(open, 100), std::exception);
  const FoldProbes probes = makeFoldProbes({Vec3(0.5, 0.5, 0.5)}, 0.01, bind);
  try {
    (void)checkFolds(probes, MatX3d::Zero(5, 3));
    ADD_FAILURE() << "a wrong control count was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("5 control positions for an embedding of 8"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sb::cage
