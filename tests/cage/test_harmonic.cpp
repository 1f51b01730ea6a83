// Harmonic coordinates (sim/cage/harmonic.h). Oracles independent of the solver: barycentric
// coordinates of a tetrahedron (linear on the boundary and harmonic, so they are the exact
// harmonic coordinates), linear precision, the discrete maximum principle, locality across the
// gap of a U-shaped cage compared with mean value coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "sim/cage/embedding.h"
#include "sim/cage/harmonic.h"
#include "sim/cage/interior_points.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/closest_point.h"
#include "sim/mesh/mesh_io.h"
#include "tests/mesh/mesh_fixtures.h"

namespace sb::cage {
namespace {

using Vec3 = Eigen::Vector3d;
using mesh::TriangleMesh;

TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  m.triangles = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  return m;
}

// A U-shaped prism, z in [0, 1]: the outline (0,0) (5,0) (5,4) (3,4) (3,1) (2,1) (2,4) (0,4),
// two prongs 2 wide and 3 long either side of a gap 1 wide. Caps triangulated by hand.
TriangleMesh uShape() {
  const double poly[8][2] = {{0, 0}, {5, 0}, {5, 4}, {3, 4}, {3, 1}, {2, 1}, {2, 4}, {0, 4}};
  TriangleMesh m;
  for (int z = 0; z < 2; ++z)
    for (const auto& p : poly) m.vertices.emplace_back(p[0], p[1], double(z));
  // Bottom-cap triangles, counter-clockwise seen from +z (the top cap); the bottom uses them
  // reversed.
  const int cap[6][3] = {{0, 1, 4}, {0, 4, 5}, {1, 2, 3}, {1, 3, 4}, {0, 5, 6}, {0, 6, 7}};
  for (const auto& t : cap) {
    m.triangles.push_back({8 + t[0], 8 + t[1], 8 + t[2]});
    m.triangles.push_back({t[0], t[2], t[1]});
  }
  for (int i = 0; i < 8; ++i) {
    const int j = (i + 1) % 8;
    m.triangles.push_back({i, j, 8 + j});
    m.triangles.push_back({i, 8 + j, 8 + i});
  }
  return m;
}

std::vector<Vec3> randomTetPoints(int count, double minBary, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<Vec3> out;
  while (static_cast<int>(out.size()) < count) {
    const Vec3 p(U(rng), U(rng), U(rng));
    if (p.minCoeff() >= minBary && 1.0 - p.sum() >= minBary) out.push_back(p);
  }
  return out;
}

TriangleMesh bunnyCage() {
  return mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny_cage.obj");
}

Eigen::Matrix<double, Eigen::Dynamic, 3> cageMatrix(const TriangleMesh& cage) {
  Eigen::Matrix<double, Eigen::Dynamic, 3> c(cage.vertices.size(), 3);
  for (std::size_t j = 0; j < cage.vertices.size(); ++j)
    c.row(Eigen::Index(j)) = cage.vertices[j].transpose();
  return c;
}

// Max over the points of |w − λ| (λ: barycentric coordinates of the tetrahedron).
double tetError(const Embedding& e, const std::vector<Vec3>& points) {
  double worst = 0.0;
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    const Vec3& p = points[size_t(i)];
    const double lambda[4] = {1.0 - p.sum(), p.x(), p.y(), p.z()};
    double w[4] = {0, 0, 0, 0};
    e.rowWeights(i, row);
    for (const auto& [j, v] : row) w[j] = v;
    for (int j = 0; j < 4; ++j) worst = std::max(worst, std::abs(w[j] - lambda[j]));
  }
  return worst;
}

// Tetrahedron: its barycentric coordinates are linear (so harmonic) and equal the hat functions
// on its faces, so they are its harmonic coordinates.
// ClosestPoint: the boundary values are taken at the closest cage point instead of at the node
// (O(h) error), which must fall like the cell size.
TEST(Harmonic, TetrahedronClosestPointBoundaryConvergesFirstOrder) {
  const TriangleMesh cage = tetrahedron();
  const auto points = randomTetPoints(300, 0.05, 1);
  double previous = std::numeric_limits<double>::infinity();
  // Measured 0.0625, 0.0309, 0.0153 at 16, 32, 64 (first order: the error halves with h).
  for (int res : {12, 24, 48}) {
    HarmonicOptions o;
    o.resolution = res;
    o.boundary = HarmonicBoundary::ClosestPoint;
    const double err = tetError(bindHarmonic(points, cage, o), points);
    std::printf("tetrahedron, closest point, res %d: max |w - barycentric| = %.3g, order %.2f\n",
                res, err, std::log2(previous / err));
    EXPECT_LT(err, 0.6 * previous) << "resolution " << res;
    previous = err;
  }
  EXPECT_LT(previous, 0.025);
}

// CutCell: the 7-point stencil with linear ghost values reproduces linear functions exactly, so
// the grid values are the barycentric coordinates (up to the θ ≥ 1e-6 clamp) and so is their
// trilinear interpolation in every cell whose corners are all inside: points farther than a
// cell diagonal from the faces. Nearer the faces (cells with outside corners, which carry
// closest-point values) the error must still fall with the cell size.
TEST(Harmonic, TetrahedronCutCellBoundaryIsExactAwayFromTheFaces) {
  const TriangleMesh cage = tetrahedron();
  // Barycentric coordinates ≥ 0.15: ≥ 0.15/√3 = 0.087 from every face, more than √3·h at 24.
  const auto deep = randomTetPoints(300, 0.15, 1);
  for (int res : {24, 32}) {
    HarmonicOptions o;
    o.resolution = res;
    const double err = tetError(bindHarmonic(deep, cage, o), deep);
    std::printf("tetrahedron, cut cell, res %d, deep points: max |w - barycentric| = %.3g\n", res,
                err);
    EXPECT_LT(err, 1e-6) << "resolution " << res;
  }
  const auto near = randomTetPoints(300, 0.0, 4);
  double previous = std::numeric_limits<double>::infinity();
  // Measured 0.022, 0.010, 0.006 at 12, 24, 48.
  for (int res : {8, 16, 32}) {
    HarmonicOptions o;
    o.resolution = res;
    const double err = tetError(bindHarmonic(near, cage, o), near);
    std::printf("tetrahedron, cut cell, res %d, all points: max |w - barycentric| = %.3g\n", res,
                err);
    EXPECT_LT(err, 0.7 * previous) << "resolution " << res;
    previous = err;
  }
}

// Σw = 1, w ≥ 0 and linear precision on the bunny cage at points inside it; linear precision
// improves under refinement.
class BunnyCage : public ::testing::TestWithParam<HarmonicBoundary> {};

TEST_P(BunnyCage, PartitionOfUnityPositivityAndLinearPrecisionConverge) {
  const TriangleMesh cage = bunnyCage();
  const auto points = interiorLattice(cage, 0.02 * mesh::testing::diagonal(cage));
  ASSERT_GT(points.size(), 500u);
  const auto C = cageMatrix(cage);
  double previous = std::numeric_limits<double>::infinity();
  // Measured linear error (of the diagonal) at 8, 16, 32: ClosestPoint 0.072, 0.037, 0.016
  // (first order; 0.0088 at 64), CutCell 0.017, 0.0053, 0.0011 (the error left is in the cells
  // next to the cage, whose outside corners carry closest-point values).
  for (int res : {8, 16, 32}) {
    HarmonicOptions o;
    o.resolution = res;
    o.boundary = GetParam();
    HarmonicReport r;
    const Embedding e = bindHarmonic(points, cage, o, &r);
    ASSERT_EQ(e.meshVertexCount(), static_cast<int>(points.size()));
    ASSERT_EQ(e.cageVertexCount(), static_cast<int>(cage.vertices.size()));
    std::vector<std::pair<int, double>> row;
    double sumErr = 0.0, minW = 1.0, linErr = 0.0;
    for (int i = 0; i < e.meshVertexCount(); ++i) {
      e.rowWeights(i, row);
      double s = 0.0;
      Vec3 x = Vec3::Zero();
      for (const auto& [j, w] : row) {
        s += w;
        minW = std::min(minW, w);
        x += w * C.row(j).transpose();
      }
      sumErr = std::max(sumErr, std::abs(s - 1.0));
      linErr = std::max(linErr, (x - points[size_t(i)]).norm());
    }
    linErr /= mesh::testing::diagonal(cage);
    std::printf(
        "bunny, %s, res %d: unknowns %lld, sum err %.3g, min w %.3g, linear err %.3g, "
        "order %.2f\n",
        GetParam() == HarmonicBoundary::CutCell ? "cut cell" : "closest point", res,
        static_cast<long long>(r.interiorNodes), sumErr, minW, linErr,
        std::log2(previous / linErr));
    EXPECT_LT(sumErr, 1e-9);
    // The discrete maximum principle makes the grid values ≥ 0 exactly; what is left is the
    // round-off of the solve (~1e-16 relative to the values ≤ 1, times a small growth factor).
    EXPECT_GE(minW, -1e-12);
    EXPECT_NEAR(r.maxLinearError, linErr, 1e-12);
    EXPECT_NEAR(e.stats().maxLinearError, linErr, 1e-12);
    EXPECT_LT(linErr, 0.6 * previous) << "resolution " << res;
    previous = linErr;
  }
}

INSTANTIATE_TEST_SUITE_P(Harmonic, BunnyCage,
                         ::testing::Values(HarmonicBoundary::CutCell,
                                           HarmonicBoundary::ClosestPoint));

// CutCell: linear precision is exact (to the θ clamp) at every point whose grid cell has all 8
// corners inside the cage, i.e. at points farther than a cell diagonal from it (distance
// computed here by brute force over the triangles).
TEST(Harmonic, CutCellLinearPrecisionIsExactAwayFromTheCage) {
  const TriangleMesh cage = bunnyCage();
  const double L = mesh::testing::diagonal(cage);
  HarmonicOptions o;
  o.resolution = 24;
  HarmonicReport r;
  bindHarmonic({Vec3::Zero()}, cage, o, &r);  // for the cell size
  const double h = r.cellSize;
  std::vector<Vec3> deep;
  for (const Vec3& p : interiorLattice(cage, 0.02 * L)) {
    double d = std::numeric_limits<double>::infinity();
    for (const auto& t : cage.triangles) {
      const Vec3 &a = cage.vertices[size_t(t[0])], &b = cage.vertices[size_t(t[1])],
                 &c = cage.vertices[size_t(t[2])];
      const auto cp = mesh::closestPointOnTriangle<double>(p, a, b, c);
      d = std::min(d, (cp.weights[0] * a + cp.weights[1] * b + cp.weights[2] * c - p).norm());
    }
    if (d > 1.01 * std::sqrt(3.0) * h) deep.push_back(p);
  }
  ASSERT_GT(deep.size(), 100u);
  const Embedding e = bindHarmonic(deep, cage, o, &r);
  std::printf("bunny, cut cell, res 24, %zu deep points: linear error %.3g of the diagonal\n",
              deep.size(), r.maxLinearError);
  EXPECT_LT(r.maxLinearError, 1e-7);
  EXPECT_LT(r.maxSumError, 1e-9);
  EXPECT_GE(r.minWeight, -1e-12);
  EXPECT_EQ(r.closestPointPoints, 0);
}

// Across the gap of a U: a vertex at the tip of one prong has next to no influence on a point in
// the tip of the other prong (the harmonic function must go around through the base), while
// mean value coordinates, which see straight across the gap, give it a clear weight.
TEST(Harmonic, UShapeLocalityAcrossTheGapUnlikeMeanValueCoordinates) {
  const TriangleMesh cage = uShape();
  ASSERT_NO_THROW(mesh::validateClosedSurface(cage, "U"));
  const std::vector<Vec3> points = {Vec3(4.0, 3.5, 0.5), Vec3(3.5, 3.0, 0.5)};
  HarmonicOptions o;
  o.resolution = 48;
  const Embedding h = bindHarmonic(points, cage, o);
  const Embedding mvc = bindMeanValue(points, cage);
  // Left prong tip vertices: (2,4) and (0,4) at z = 0 and 1: indices 6, 7, 14, 15.
  for (int i = 0; i < 2; ++i) {
    std::vector<std::pair<int, double>> rh, rm;
    h.rowWeights(i, rh);
    mvc.rowWeights(i, rm);
    double farH = 0.0, farM = 0.0;
    for (const auto& [j, w] : rh)
      if (j % 8 == 6 || j % 8 == 7) farH += std::abs(w);
    for (const auto& [j, w] : rm)
      if (j % 8 == 6 || j % 8 == 7) farM += std::abs(w);
    std::printf("U point %d: harmonic far weight %.3g, MVC %.3g\n", i, farH, farM);
    EXPECT_LT(farH, 0.01);
    EXPECT_GT(farM, 10.0 * farH);
  }
}

// The embedding deforms like any other: a translated cage moves the points by the translation,
// here including points outside the cage (closest-point weights, also summing to 1).
TEST(Harmonic, TranslationMovesPointsByIt) {
  const TriangleMesh cage = mesh::testing::makeBox(2, 2, 2);
  std::vector<Vec3> points;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-0.5, 1.5);
  for (int i = 0; i < 200; ++i) points.emplace_back(U(rng), U(rng), U(rng));
  HarmonicOptions o;
  o.resolution = 16;
  HarmonicReport r;
  const Embedding e = bindHarmonic(points, cage, o, &r);
  // The unit cube at 16: h = 1/16, 16 cells + 1 + 2·2 margin = 21 nodes per axis.
  EXPECT_DOUBLE_EQ(r.cellSize, 1.0 / 16);
  EXPECT_EQ(r.gridNodes, (std::array<int, 3>{21, 21, 21}));
  EXPECT_GT(r.closestPointPoints, 0);
  EXPECT_LT(r.maxSumError, 1e-9);  // outside points too
  EXPECT_GE(r.minWeight, -1e-12);
  const Vec3 t(0.3, -1.7, 2.5);
  Eigen::Matrix<double, Eigen::Dynamic, 3> moved = cageMatrix(cage);
  moved.rowwise() += t.transpose();
  Eigen::Matrix<double, Eigen::Dynamic, 3> rest, out;
  e.deformDouble(cageMatrix(cage), rest);
  e.deformDouble(moved, out);
  for (int i = 0; i < e.meshVertexCount(); ++i)
    EXPECT_LT((out.row(i) - rest.row(i) - t.transpose()).norm(), 1e-9) << "point " << i;
}

// Binds with one thread and with two (otherwise options o) and expects bit-identical rows.
void expectSameWeightsOnOneAndTwoThreads(const std::vector<Vec3>& points, const TriangleMesh& cage,
                                         HarmonicOptions o) {
  o.threads = 1;
  const Embedding a = bindHarmonic(points, cage, o);
  o.threads = 2;
  const Embedding b = bindHarmonic(points, cage, o);
  std::vector<std::pair<int, double>> ra, rb;
  for (int i = 0; i < a.meshVertexCount(); ++i) {
    a.rowWeights(i, ra);
    b.rowWeights(i, rb);
    EXPECT_EQ(ra, rb) << "point " << i;
  }
}

TEST(Harmonic, ThreadCountDoesNotChangeTheWeights) {
  const TriangleMesh cage = tetrahedron();
  const auto points = randomTetPoints(50, 0.0, 2);
  HarmonicOptions o;
  o.resolution = 16;
  expectSameWeightsOnOneAndTwoThreads(points, cage, o);
}

// The nested-dissection numbering of the unknowns only reorders the same system: the weights
// must match those of Eigen's AMD ordering to round-off (a node numbered twice or skipped would
// change them), on a grid with enough unknowns for several levels of dissection.
TEST(Harmonic, NestedDissectionAndAmdOrderingsGiveTheSameWeights) {
  const TriangleMesh cage = bunnyCage();
  const auto points = interiorLattice(cage, 0.05 * mesh::testing::diagonal(cage));
  HarmonicOptions o;
  o.resolution = 24;
  HarmonicReport rn, ra;
  o.ordering = HarmonicOrdering::NestedDissection;
  const Embedding nd = bindHarmonic(points, cage, o, &rn);
  o.ordering = HarmonicOrdering::Amd;
  const Embedding amd = bindHarmonic(points, cage, o, &ra);
  EXPECT_EQ(rn.interiorNodes, ra.interiorNodes);
  EXPECT_GT(rn.interiorNodes, 1000);
  std::vector<std::pair<int, double>> a, b;
  double worst = 0.0;
  for (int i = 0; i < nd.meshVertexCount(); ++i) {
    nd.rowWeights(i, a);
    amd.rowWeights(i, b);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k)
      worst = std::max(worst, std::abs(a[k].second - b[k].second));
  }
  EXPECT_LT(worst, 1e-12);
}

// Multigrid-preconditioned CG solves the same system as the direct solver, to its tolerance:
// the weights agree to far below the discretisation error (README.md documents ≤ 1e-6; the
// measured gap is ~1e-10), with the partition of unity kept to round-off and w ≥ 0 — at every
// resolution and both numberings of the unknowns (its Gauss-Seidel sweeps follow the
// numbering).
TEST(Harmonic, MultigridCgAgreesWithTheDirectSolve) {
  const TriangleMesh cage = bunnyCage();
  const auto points = interiorLattice(cage, 0.05 * mesh::testing::diagonal(cage));
  const int m = static_cast<int>(cage.vertices.size());
  for (const int res : {24, 32}) {  // 3–8k unknowns: more than the coarsest level's 2000
    for (const HarmonicOrdering ordering :
         {HarmonicOrdering::Amd, HarmonicOrdering::NestedDissection}) {
      HarmonicOptions o;
      o.resolution = res;
      o.ordering = ordering;
      o.solver = HarmonicSolver::Direct;
      HarmonicReport rd, rc;
      const Embedding direct = bindHarmonic(points, cage, o, &rd);
      o.solver = HarmonicSolver::MultigridCg;
      const Embedding cg = bindHarmonic(points, cage, o, &rc);
      EXPECT_EQ(rc.interiorNodes, rd.interiorNodes);
      EXPECT_GT(rc.maxCgIterations, 1);
      EXPECT_LT(rc.maxCgIterations, 40) << "resolution " << res;  // the cycle works
      EXPECT_LT(rc.maxSumError, 1e-12) << "resolution " << res;
      EXPECT_GE(rc.minWeight, 0.0) << "resolution " << res;
      std::vector<std::pair<int, double>> a, b;
      double worst = 0.0;
      for (int i = 0; i < cg.meshVertexCount(); ++i) {
        Eigen::VectorXd wa = Eigen::VectorXd::Zero(m), wb = Eigen::VectorXd::Zero(m);
        direct.rowWeights(i, a);
        cg.rowWeights(i, b);
        for (const auto& [j, w] : a) wa[j] += w;
        for (const auto& [j, w] : b) wb[j] += w;
        worst = std::max(worst, (wa - wb).cwiseAbs().maxCoeff());
      }
      std::printf("bunny, res %d, %s: max |w_cg - w_direct| %.3g, CG iterations %d\n", res,
                  ordering == HarmonicOrdering::Amd ? "amd" : "nested dissection", worst,
                  rc.maxCgIterations);
      EXPECT_LT(worst, 1e-8) << "resolution " << res;
    }
  }
}

// Each cage vertex's CG runs alone, by the same operations whatever the split of the vertices
// across threads: the weights are bit-identical.
TEST(Harmonic, MultigridCgThreadCountDoesNotChangeTheWeights) {
  const TriangleMesh cage = bunnyCage();
  const auto points = interiorLattice(cage, 0.05 * mesh::testing::diagonal(cage));
  HarmonicOptions o;
  o.resolution = 24;
  o.solver = HarmonicSolver::MultigridCg;
  expectSameWeightsOnOneAndTwoThreads(points, cage, o);
}

// Points on the cage get (to the discretisation error) the hat functions there; points far
// outside get exactly the hat functions of their closest cage point; the smallest resolution
// still gives a partition of unity.
TEST(Harmonic, PointsOnAndOutsideTheCage) {
  const TriangleMesh cage = tetrahedron();
  // On the faces: one barycentric coordinate 0.
  std::vector<Vec3> onFaces;
  for (int i = 0; i < 40; ++i) {
    Vec3 p = randomTetPoints(1, 0.0, 100u + unsigned(i))[0];
    if (i % 4 < 3)
      p[i % 4] = 0.0;  // on the face x = 0, y = 0 or z = 0
    else
      p /= p.sum();  // on the slanted face
    onFaces.push_back(p);
  }
  double previous = std::numeric_limits<double>::infinity();
  for (int res : {16, 32}) {
    HarmonicOptions o;
    o.resolution = res;
    const double err = tetError(bindHarmonic(onFaces, cage, o), onFaces);
    EXPECT_LT(err, 2.0 / res) << "resolution " << res;  // about a cell
    EXPECT_LT(err, 0.7 * previous);
    previous = err;
  }

  const std::vector<Vec3> far = {Vec3(2, 2, 2), Vec3(-3, 0.25, 0.25), Vec3(0.5, 0.25, -4)};
  HarmonicOptions o;
  o.resolution = 8;
  HarmonicReport r;
  const Embedding e = bindHarmonic(far, cage, o, &r);
  EXPECT_EQ(r.closestPointPoints, 3);
  // Closest points: (1/3, 1/3, 1/3) on the slanted face, (0, 0.25, 0.25) on x = 0,
  // (0.5, 0.25, 0) on z = 0; their barycentric coordinates (w0, w1, w2, w3).
  const double expected[3][4] = {
      {0, 1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0, 0.25, 0.25}, {0.25, 0.5, 0.25, 0}};
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < 3; ++i) {
    e.rowWeights(i, row);
    double w[4] = {0, 0, 0, 0};
    for (const auto& [j, v] : row) w[j] = v;
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(w[j], expected[i][j], 1e-12) << i << " " << j;
  }

  o.resolution = 4;
  const auto inside = randomTetPoints(20, 0.0, 9);
  const Embedding coarse = bindHarmonic(inside, cage, o, &r);
  EXPECT_LT(r.maxSumError, 1e-12);
  EXPECT_GE(r.minWeight, 0.0);
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(Harmonic, RefusesBadInputWithAClearMessage) {
  const TriangleMesh good = tetrahedron();
  const std::vector<Vec3> points = {Vec3(0.2, 0.2, 0.2)};

  TriangleMesh open = mesh::testing::makeBox(1, 1, 1);
  open.triangles.pop_back();
  EXPECT_THROW(bindHarmonic(points, open), mesh::SurfaceError);
  EXPECT_NE(messageOf([&] { bindHarmonic(points, open); }).find("cage: not closed"),
            std::string::npos);

  TriangleMesh inverted = good;
  for (auto& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(bindHarmonic(points, inverted), mesh::SurfaceError);
  EXPECT_NE(messageOf([&] { bindHarmonic(points, inverted); }).find("cage: inverted"),
            std::string::npos);

  // Two tetrahedra sharing a vertex (the second is the first reflected through vertex 0, which
  // reverses orientation, so its triangles are flipped back): a non-manifold vertex.
  TriangleMesh pinched = good;
  for (int k = 1; k < 4; ++k) pinched.vertices.push_back(-good.vertices[size_t(k)]);
  for (const auto& t : good.triangles) {
    auto map = [](int v) { return v == 0 ? 0 : v + 3; };
    pinched.triangles.push_back({map(t[0]), map(t[2]), map(t[1])});
  }
  EXPECT_THROW(bindHarmonic(points, pinched), mesh::SurfaceError);
  EXPECT_EQ(messageOf([&] { bindHarmonic(points, pinched); }).rfind("cage: ", 0), 0u);

  HarmonicOptions o;
  o.cgTolerance = 0.0;
  EXPECT_NE(messageOf([&] { bindHarmonic(points, good, o); }).find("cgTolerance must be in"),
            std::string::npos);
  o.cgTolerance = 1e-12;
  o.resolution = 3;
  EXPECT_NE(messageOf([&] { bindHarmonic(points, good, o); }).find("resolution must be at least 4"),
            std::string::npos);
  o.resolution = 100000;
  const std::string big = messageOf([&] { bindHarmonic(points, good, o); });
  EXPECT_NE(big.find("need about"), std::string::npos) << big;
  EXPECT_NE(big.find("allowed"), std::string::npos) << big;
  EXPECT_THROW(bindHarmonic(points, good, o), std::runtime_error);

  // A grid that fits (~6 MB at resolution 48 for the bunny cage) but a solve that does not
  // (~150 MB: 28k unknowns × 164 cage vertices and the factor): refused after the
  // classification, before the factorisation.
  HarmonicOptions small;
  small.resolution = 48;
  small.maxBytes = 20u << 20;
  const std::string solve = messageOf([&] { bindHarmonic(points, bunnyCage(), small); });
  EXPECT_NE(solve.find("the solve for"), std::string::npos) << solve;
  EXPECT_NE(solve.find("needs about"), std::string::npos) << solve;

  std::vector<Vec3> bad = {Vec3(0.1, 0.1, 0.1), Vec3(0.2, std::nan(""), 0.1)};
  EXPECT_NE(messageOf([&] { bindHarmonic(bad, good); }).find("point 1 is not finite"),
            std::string::npos);
  EXPECT_THROW(bindHarmonic(bad, good), std::invalid_argument);
}

}  // namespace
}  // namespace sb::cage
