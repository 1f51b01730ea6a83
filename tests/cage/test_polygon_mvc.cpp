// Quad and polygon cages: the readers keep which triangles form one polygon, and polygon mean
// value coordinates (sim/cage/polygon_mvc.h) do not depend on the diagonal a reader picks. The
// "which triangulation?" question of the thesis is answered by DiagonalQuestion.* below: with
// triangle MVC the diagonal does not matter for affine cage motions (linear precision) and does
// for general motions; polygon MVC is the same for every labelling.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "sim/cage/bind.h"
#include "sim/cage/embedding.h"
#include "sim/cage/mvc.h"
#include "sim/cage/polygon_mvc.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "tests/cage/cage_test_data.h"

namespace sb::cage {
namespace {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3>;
using Faces = std::vector<std::vector<int>>;

// An OBJ text of the vertices and faces, each face's corner list rotated left by rotate[f]
// (so the reader's fan starts at another corner and picks the other diagonal of a quad).
std::string objText(const std::vector<Vec3>& v, const Faces& faces,
                    const std::vector<int>& rotate = {}) {
  std::string s;
  char line[128];
  for (const Vec3& p : v) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
    s += line;
  }
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const std::size_t k = faces[f].size();
    const std::size_t r = rotate.empty() ? 0 : std::size_t(rotate[f]) % k;
    s += "f";
    for (std::size_t c = 0; c < k; ++c) s += " " + std::to_string(faces[f][(c + r) % k] + 1);
    s += "\n";
  }
  return s;
}

mesh::TriangleMesh readObj(const std::string& text) {
  return mesh::parseMesh(text, mesh::MeshFormat::Obj, "cage.obj");
}

// The same triangles without the polygon record: what triangle MVC sees.
mesh::TriangleMesh trianglesOnly(mesh::TriangleMesh m) {
  m.polygonOf.clear();
  return m;
}

// A box [0,2]×[0,1]×[0,1.5]: 6 rectangles, counter-clockwise from outside.
std::vector<Vec3> boxVertices() {
  std::vector<Vec3> v;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) v.emplace_back(2.0 * i, 1.0 * j, 1.5 * k);
  return v;
}
const Faces kHexFaces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

// A non-box hexahedron with planar, non-rectangular quads: a frustum of a pyramid over a
// general convex quadrilateral (the top is the bottom scaled towards the apex, so every side is
// a planar trapezoid).
std::vector<Vec3> frustumVertices() {
  const Vec3 bottom[4] = {{0.0, 0.0, 0.0}, {2.2, 0.3, 0.0}, {-0.2, 1.7, 0.0}, {1.9, 2.1, 0.0}};
  const Vec3 apex(0.7, 1.1, 3.0);
  std::vector<Vec3> v(bottom, bottom + 4);
  for (const Vec3& b : bottom) v.push_back(apex + 0.45 * (b - apex));
  return v;
}

// Interior points: a jittered grid strictly inside the convex hull of the cage.
std::vector<Vec3> interiorPoints(const std::vector<Vec3>& v, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  while (int(points.size()) < count) {
    // A random convex combination, pulled towards the centroid.
    std::vector<double> a(v.size());
    double sum = 0.0;
    for (double& x : a) sum += (x = std::pow(u(rng), 3.0));
    Vec3 centroid = Vec3::Zero(), p = Vec3::Zero();
    for (std::size_t j = 0; j < v.size(); ++j) {
      p += a[j] / sum * v[j];
      centroid += v[j] / double(v.size());
    }
    points.push_back(centroid + 0.9 * (p - centroid));
  }
  return points;
}

Points deformed(const Embedding& e, const Points& cage) {
  Points out;
  e.deformDouble(cage, out);
  return out;
}

double maxDistance(const Points& a, const Points& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

Embedding bindDense(const std::vector<Vec3>& points, const mesh::TriangleMesh& cage) {
  BindOptions o;
  o.storage = WeightStorage::Dense;
  o.threads = 1;
  return bindToCage(points, cage, EmbeddingMethod{}, o);
}

struct Motions {
  Points affine, general;
};
Motions motionsOf(const std::vector<Vec3>& v, unsigned seed) {
  Eigen::Matrix3d A;
  A << 1.2, 0.3, -0.1, -0.2, 0.9, 0.4, 0.1, -0.3, 1.1;
  const Vec3 t(0.5, -1.0, 0.25);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  Motions m;
  m.affine.resize(Eigen::Index(v.size()), 3);
  m.general.resize(Eigen::Index(v.size()), 3);
  for (std::size_t j = 0; j < v.size(); ++j) {
    m.affine.row(Eigen::Index(j)) = (A * v[j] + t).transpose();
    m.general.row(Eigen::Index(j)) = (v[j] + Vec3(u(rng), u(rng), u(rng))).transpose();
  }
  return m;
}

// The thesis' question for one cage: triangle MVC over diagonal set A (every quad's fan from
// its first corner) against diagonal set B (every quad rotated by one corner: the other
// diagonal), and polygon MVC for both labellings.
struct DiagonalFigures {
  double triangleAffine, triangleGeneral, triangleGeneralMean, polygonAffine, polygonGeneral,
      polygonAffineExact;
};
DiagonalFigures diagonalFigures(const std::vector<Vec3>& v, const char* name) {
  const std::string a = objText(v, kHexFaces), b = objText(v, kHexFaces, {1, 1, 1, 1, 1, 1});
  const mesh::TriangleMesh ca = readObj(a), cb = readObj(b);
  // Every quad really is split along the other diagonal in B.
  for (std::size_t t = 0; t < ca.triangles.size(); t += 2)
    EXPECT_NE(ca.triangles[t][0], cb.triangles[t][0]);
  const std::vector<Vec3> points = interiorPoints(v, 200, 7);
  const Motions mo = motionsOf(v, 11);
  const Embedding ta = bindDense(points, trianglesOnly(ca)),
                  tb = bindDense(points, trianglesOnly(cb));
  const Embedding pa = bindDense(points, ca), pb = bindDense(points, cb);
  Eigen::Matrix3d A;
  A << 1.2, 0.3, -0.1, -0.2, 0.9, 0.4, 0.1, -0.3, 1.1;
  Points exact(Eigen::Index(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    exact.row(Eigen::Index(i)) = (A * points[i] + Vec3(0.5, -1.0, 0.25)).transpose();
  DiagonalFigures f;
  double size = 0.0;
  for (const Vec3& p : v) size = std::max(size, (p - v[0]).norm());
  f.triangleAffine = maxDistance(deformed(ta, mo.affine), deformed(tb, mo.affine)) / size;
  f.triangleGeneral = maxDistance(deformed(ta, mo.general), deformed(tb, mo.general)) / size;
  f.triangleGeneralMean =
      (deformed(ta, mo.general) - deformed(tb, mo.general)).rowwise().norm().mean() / size;
  f.polygonAffine = maxDistance(deformed(pa, mo.affine), deformed(pb, mo.affine)) / size;
  f.polygonGeneral = maxDistance(deformed(pa, mo.general), deformed(pb, mo.general)) / size;
  f.polygonAffineExact = maxDistance(deformed(pa, mo.affine), exact) / size;
  std::printf(
      "%s (200 interior points, max |difference| / cage size): triangle MVC diagonal A vs B: "
      "affine %.2e, general %.2e (mean %.2e); polygon MVC labelling A vs B: affine %.2e, general "
      "%.2e; "
      "polygon MVC vs the exact affine image %.2e\n",
      name, f.triangleAffine, f.triangleGeneral, f.triangleGeneralMean, f.polygonAffine,
      f.polygonGeneral, f.polygonAffineExact);
  return f;
}

TEST(DiagonalQuestion, BoxOfSixRectangles) {
  const DiagonalFigures f = diagonalFigures(boxVertices(), "box");
  EXPECT_LT(f.triangleAffine, 1e-12);  // linear precision: no diagonal dependence
  EXPECT_GT(f.triangleGeneral, 1e-3);  // general motion: the diagonal matters
  EXPECT_LT(f.polygonAffine, 1e-13);   // polygon MVC: none at all
  EXPECT_LT(f.polygonGeneral, 1e-13);
  EXPECT_LT(f.polygonAffineExact, 1e-12);
}

TEST(DiagonalQuestion, FrustumOfPlanarTrapezoids) {
  const DiagonalFigures f = diagonalFigures(frustumVertices(), "frustum");
  EXPECT_LT(f.triangleAffine, 1e-12);
  EXPECT_GT(f.triangleGeneral, 1e-3);
  EXPECT_LT(f.polygonAffine, 1e-13);
  EXPECT_LT(f.polygonGeneral, 1e-13);
  EXPECT_LT(f.polygonAffineExact, 1e-12);
}

// max(|Σw − 1|, |Σ w v − x| / size)
double invariantError(const std::vector<Vec3>& v, const std::vector<double>& w, const Vec3& x) {
  double sum = 0.0, size = 0.0;
  Vec3 p = Vec3::Zero();
  for (std::size_t j = 0; j < v.size(); ++j) {
    sum += w[j];
    p += w[j] * v[j];
    size = std::max(size, (v[j] - v[0]).norm());
  }
  return std::max(std::abs(sum - 1.0), (p - x).norm() / size);
}

std::vector<double> polygonWeights(const PolygonMeanValueCage& c, const Vec3& x,
                                   MvcInfo* info = nullptr) {
  std::vector<double> w(std::size_t(c.vertexCount()));
  PolygonMeanValueCage::Scratch s;
  EXPECT_TRUE(c.weights(x, w.data(), s, info)) << x.transpose();
  for (double wj : w) EXPECT_TRUE(std::isfinite(wj)) << x.transpose();
  return w;
}

TEST(PolygonMvc, TriangleCageGivesTriangleMvc) {
  const mesh::TriangleMesh& cage = test_data::bunnyCage();
  mesh::validateClosedSurface(cage, "cage");
  ASSERT_TRUE(cage.polygonOf.empty());
  const PolygonMeanValueCage poly(cage);
  const MeanValueCage tri(cage);
  // Points of the bunny (inside, some close to the cage) and points a hair off cage faces.
  std::vector<Vec3> points;
  const auto& bunny = test_data::bunny().vertices;
  for (std::size_t i = 0; i < bunny.size(); i += 97) points.push_back(bunny[i]);
  for (std::size_t t = 0; t < cage.triangles.size(); t += 7) {
    const auto& f = cage.triangles[t];
    const Vec3 a = cage.vertices[f[0]], b = cage.vertices[f[1]], c = cage.vertices[f[2]];
    const Vec3 n = (b - a).cross(c - a).normalized();
    points.push_back((a + b + c) / 3.0 - 1e-6 * n);
    points.push_back(0.5 * (a + b) - 1e-3 * n);
  }
  double worst = 0.0;
  std::vector<double> wt(std::size_t(tri.vertexCount()));
  MeanValueCage::Scratch s;
  for (const Vec3& x : points) {
    ASSERT_TRUE(tri.weights(x, wt.data(), s));
    const std::vector<double> wp = polygonWeights(poly, x);
    double scale = 0.0, diff = 0.0;
    for (std::size_t j = 0; j < wt.size(); ++j) {
      scale = std::max(scale, std::abs(wt[j]));
      diff = std::max(diff, std::abs(wt[j] - wp[j]));
    }
    worst = std::max(worst, diff / scale);
  }
  std::printf(
      "triangle cage: polygon MVC vs triangle MVC, max relative difference %.2e over %zu "
      "points\n",
      worst, points.size());
  EXPECT_LT(worst, 1e-12);
}

TEST(PolygonMvc, PlanarMeanValueClosedForms) {
  // A triangle: barycentric coordinates.
  const std::vector<Vec2> tri = {{0, 0}, {3, 0}, {0, 2}};
  double b[5];
  planarMeanValue(Vec2(0.6, 0.5), tri, b);
  EXPECT_NEAR(b[1], 0.2, 1e-15);
  EXPECT_NEAR(b[2], 0.25, 1e-15);
  EXPECT_NEAR(b[0], 0.55, 1e-15);
  // A regular pentagon's centre: 1/5 each (symmetry), either orientation.
  std::vector<Vec2> pent;
  for (int i = 0; i < 5; ++i)
    pent.emplace_back(std::cos(2 * M_PI * i / 5), std::sin(2 * M_PI * i / 5));
  planarMeanValue(Vec2(0, 0), pent, b);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(b[i], 0.2, 1e-15);
  // A square [0,1]²: at (x, y) on the diagonal by symmetry b1 = b3; and linear precision.
  const std::vector<Vec2> sq = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  planarMeanValue(Vec2(0.3, 0.3), sq, b);
  EXPECT_NEAR(b[1], b[3], 1e-15);
  Vec2 p = Vec2::Zero();
  for (int i = 0; i < 4; ++i) p += b[i] * sq[std::size_t(i)];
  EXPECT_NEAR((p - Vec2(0.3, 0.3)).norm(), 0.0, 1e-15);
  // On an edge: linear along it; on a corner: 1 there.
  planarMeanValue(Vec2(1.0, 0.25), sq, b);
  EXPECT_NEAR(b[1], 0.75, 1e-15);
  EXPECT_NEAR(b[2], 0.25, 1e-15);
  EXPECT_EQ(b[0], 0.0);
  planarMeanValue(Vec2(0.0, 1.0), sq, b);
  EXPECT_EQ(b[3], 1.0);
}

// A triangular prism: two triangles and three quads.
std::vector<Vec3> prismVertices() {
  return {{0, 0, 0}, {2, 0, 0}, {0.5, 1.5, 0}, {0, 0, 1.2}, {2, 0, 1.2}, {0.5, 1.5, 1.2}};
}
const Faces kPrismFaces = {{0, 2, 1}, {3, 4, 5}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};

TEST(PolygonMvc, PartitionOfUnityAndLinearPrecisionOnQuadAndMixedCages) {
  struct Case {
    const char* name;
    std::vector<Vec3> v;
    Faces faces;
  };
  const std::vector<Case> cases = {{"box", boxVertices(), kHexFaces},
                                   {"frustum", frustumVertices(), kHexFaces},
                                   {"prism", prismVertices(), kPrismFaces}};
  for (const Case& c : cases) {
    const mesh::TriangleMesh cage = readObj(objText(c.v, c.faces));
    mesh::validateClosedSurface(cage, c.name);
    ASSERT_TRUE(mesh::hasPolygonFaces(cage));
    const PolygonMeanValueCage poly(cage);
    EXPECT_EQ(poly.nonPlanarFaceCount(), 0) << c.name;
    for (const Vec3& x : interiorPoints(c.v, 300, 3)) {
      const std::vector<double> w = polygonWeights(poly, x);
      EXPECT_LT(invariantError(c.v, w, x), 1e-13) << c.name << " " << x.transpose();
      for (double wj : w) EXPECT_GT(wj, 0.0) << c.name;  // convex cage: positive (MVC)
    }
  }
  // The box's centre: 1/8 each by symmetry.
  const PolygonMeanValueCage box(readObj(objText(boxVertices(), kHexFaces)));
  for (double wj : polygonWeights(box, Vec3(1.0, 0.5, 0.75))) EXPECT_NEAR(wj, 0.125, 1e-15);
}

// Non-convex planar faces: an L-shaped prism (two L hexagons, six rectangles), with the bottom's
// fan from the reflex corner (its triangles tile the L) and from another corner (a fan triangle
// covers the notch and a reversed one cancels it: topologically closed, geometrically not a
// triangulation). Polygon MVC does not look at the fan: the same weights, linearly precise.
TEST(PolygonMvc, NonConvexHexagonFaces) {
  const std::vector<Vec2> l = {{1, 1}, {1, 2}, {0, 2}, {0, 0}, {2, 0}, {2, 1}};  // reflex first
  std::vector<Vec3> v;
  for (double z : {0.0, 0.7})
    for (const Vec2& p : l) v.emplace_back(p.x(), p.y(), z);
  Faces faces = {{0, 5, 4, 3, 2, 1}, {6, 7, 8, 9, 10, 11}};
  for (int i = 0; i < 6; ++i) faces.push_back({i, (i + 1) % 6, 6 + (i + 1) % 6, 6 + i});
  const mesh::TriangleMesh tiled = readObj(objText(v, faces));
  const mesh::TriangleMesh folded = readObj(objText(v, faces, {2, 0, 0, 0, 0, 0, 0, 0}));
  mesh::validateClosedSurface(tiled, "L prism");
  mesh::validateClosedSurface(folded, "L prism");
  const PolygonMeanValueCage a(tiled), b(folded);
  EXPECT_EQ(a.planarFaceCount(), 8);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.01, 0.99);
  int tested = 0;
  while (tested < 300) {
    const Vec3 x(2 * u(rng), 2 * u(rng), 0.7 * u(rng));
    if (x.x() > 1.0 && x.y() > 1.0) continue;  // the notch
    ++tested;
    const std::vector<double> wa = polygonWeights(a, x), wb = polygonWeights(b, x);
    EXPECT_LT(invariantError(v, wa, x), 1e-12) << x.transpose();
    for (std::size_t j = 0; j < wa.size(); ++j) EXPECT_NEAR(wa[j], wb[j], 1e-14);
  }
}

TEST(PolygonMvc, CyclicRelabellingChangesNothing) {
  const std::vector<Vec3> v = frustumVertices();
  const PolygonMeanValueCage reference(readObj(objText(v, kHexFaces)));
  const std::vector<std::vector<int>> rotations = {
      {1, 1, 1, 1, 1, 1}, {2, 3, 0, 1, 2, 3}, {3, 0, 2, 1, 3, 2}};
  const std::vector<Vec3> points = interiorPoints(v, 100, 5);
  for (const auto& r : rotations) {
    const mesh::TriangleMesh cage = readObj(objText(v, kHexFaces, r));
    const PolygonMeanValueCage relabelled(cage);
    for (const Vec3& x : points) {
      const std::vector<double> a = polygonWeights(reference, x), b = polygonWeights(relabelled, x);
      for (std::size_t j = 0; j < a.size(); ++j) EXPECT_NEAR(a[j], b[j], 1e-14);
    }
  }
}

TEST(PolygonMvc, NearAndOnFacesEdgesAndCorners) {
  const std::vector<Vec3> v = frustumVertices();
  const mesh::TriangleMesh cage = readObj(objText(v, kHexFaces));
  const PolygonMeanValueCage poly(cage);
  // The bottom face (z = 0), its edge 0–1 and corner 0, approached from inside; and points in
  // the bottom's plane outside the face.
  const Vec3 faceCentre = 0.25 * (v[0] + v[1] + v[2] + v[3]);
  const Vec3 edgeMid = 0.5 * (v[0] + v[1]);
  const Vec3 inward = (0.125 * (v[0] + v[1] + v[2] + v[3] + v[4] + v[5] + v[6] + v[7]));
  for (const Vec3& target : {faceCentre, edgeMid, v[0]}) {
    for (double eps : {1e-3, 1e-6, 1e-9, 1e-12, 1e-14, 1e-16, 0.0}) {
      const Vec3 x = target + eps * (inward - target).normalized();
      MvcInfo info;
      const std::vector<double> w = polygonWeights(poly, x, &info);
      EXPECT_LT(invariantError(v, w, x), 1e-9) << x.transpose() << " eps " << eps;
    }
  }
  // On the face centre: the bottom quad's planar mean value coordinates (the top corners get 0).
  MvcInfo info;
  const std::vector<double> on = polygonWeights(poly, faceCentre, &info);
  EXPECT_EQ(info.kind, MvcCase::OnSurface);
  for (int j = 4; j < 8; ++j) EXPECT_EQ(on[std::size_t(j)], 0.0);
  // A hair inside tends to it (continuity across the on-surface snap).
  const std::vector<double> near = polygonWeights(poly, faceCentre + Vec3(0, 0, 1e-11));
  for (std::size_t j = 0; j < on.size(); ++j) EXPECT_NEAR(near[j], on[j], 1e-8);
  // In the plane of the bottom face, outside it (and just off the plane), inside the cage's
  // box only for some; all finite and linearly precise.
  for (const Vec3& x : {Vec3(3.0, 0.5, 0.0), Vec3(-1.0, -1.0, 1e-12), Vec3(1.0, -0.5, -1e-9),
                        Vec3(5.0, 5.0, 0.0)}) {
    const std::vector<double> w = polygonWeights(poly, x);
    EXPECT_LT(invariantError(v, w, x), 1e-9) << x.transpose();
  }
}

TEST(PolygonMvc, NonPlanarQuadsUseTheFanAverage) {
  // The box with corner 7 pulled out diagonally: its three faces (top and two sides) twist.
  std::vector<Vec3> v = boxVertices();
  v[7] += Vec3(0.2, 0.2, 0.3);
  const mesh::TriangleMesh cage = readObj(objText(v, kHexFaces));
  mesh::validateClosedSurface(cage, "cage");
  const PolygonMeanValueCage poly(cage);
  EXPECT_EQ(poly.nonPlanarFaceCount(), 3);
  EXPECT_EQ(poly.planarFaceCount(), 3);
  const PolygonMeanValueCage rotated(readObj(objText(v, kHexFaces, {1, 3, 2, 1, 3, 1})));
  const std::vector<Vec3> points = interiorPoints(v, 200, 9);
  for (const Vec3& x : points) {
    const std::vector<double> w = polygonWeights(poly, x), r = polygonWeights(rotated, x);
    EXPECT_LT(invariantError(v, w, x), 1e-13);
    for (std::size_t j = 0; j < w.size(); ++j) EXPECT_NEAR(w[j], r[j], 1e-14);
  }
  // Close to the twisted top face and on it: finite and linearly precise.
  const Vec3 topMid = 0.25 * (v[4] + v[5] + v[6] + v[7]);
  for (double eps : {1e-2, 1e-6, 1e-12, 0.0}) {
    const Vec3 x = topMid - Vec3(0, 0, eps);
    EXPECT_LT(invariantError(v, polygonWeights(poly, x), x), 1e-9) << eps;
  }
  // One quad alone: when every face is a twisted quad, polygon MVC is the mean of the two
  // diagonals' triangle MVC weights. Check on a cage whose quads are all non-planar: a
  // "twisted" hexahedron with every corner jittered.
  std::vector<Vec3> t = boxVertices();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  for (Vec3& p : t) p += Vec3(u(rng), u(rng), u(rng));
  const mesh::TriangleMesh ta = readObj(objText(t, kHexFaces));
  const mesh::TriangleMesh tb = readObj(objText(t, kHexFaces, {1, 1, 1, 1, 1, 1}));
  const PolygonMeanValueCage twisted(ta);
  ASSERT_EQ(twisted.nonPlanarFaceCount(), 6);
  const MeanValueCage da(trianglesOnly(ta)), db(trianglesOnly(tb));
  // The unnormalised weights average, so compare up to the row's normalisation: the polygon
  // weights are proportional to (sa·wa + sb·wb) with sa, sb the triangle rows' sums. Equivalent
  // test: w lies on the segment between wa and wb and satisfies linear precision; here check
  // that w − wa is parallel to wb − wa.
  MeanValueCage::Scratch s;
  for (const Vec3& x : interiorPoints(t, 50, 2)) {
    std::vector<double> wa(8), wb(8);
    ASSERT_TRUE(da.weights(x, wa.data(), s));
    ASSERT_TRUE(db.weights(x, wb.data(), s));
    const std::vector<double> w = polygonWeights(twisted, x);
    Eigen::Map<const Eigen::Matrix<double, 8, 1>> A(wa.data()), B(wb.data()), W(w.data());
    const Eigen::Matrix<double, 8, 1> d = B - A, e = W - A;
    const double along = e.dot(d) / d.squaredNorm();
    EXPECT_GT(along, 0.0);
    EXPECT_LT(along, 1.0);
    EXPECT_LT((e - along * d).norm(), 1e-13 * (1.0 + d.norm()));
  }
}

TEST(PolygonCage, ReadersKeepPolygonsAndWriteThemBack) {
  const mesh::TriangleMesh cage = readObj(objText(prismVertices(), kPrismFaces));
  EXPECT_EQ(cage.triangles.size(), 8u);
  EXPECT_EQ(cage.polygonOf, (std::vector<int>{0, 1, 2, 2, 3, 3, 4, 4}));
  EXPECT_EQ(mesh::polygonFaces(cage), kPrismFaces);
  // OFF gives the same faces.
  std::string off = "OFF\n6 5 0\n";
  for (const Vec3& p : prismVertices())
    off += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const auto& f : kPrismFaces) {
    off += std::to_string(f.size());
    for (int c : f) off += " " + std::to_string(c);
    off += "\n";
  }
  EXPECT_EQ(mesh::polygonFaces(mesh::parseMesh(off, mesh::MeshFormat::Off, "c.off")), kPrismFaces);
  // So does ASCII PLY.
  std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty double x\nproperty double "
      "y\nproperty double z\nelement face 5\nproperty list uchar int "
      "vertex_indices\nend_header\n";
  for (const Vec3& p : prismVertices())
    ply += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const auto& f : kPrismFaces) {
    ply += std::to_string(f.size());
    for (int c : f) ply += " " + std::to_string(c);
    ply += "\n";
  }
  EXPECT_EQ(mesh::polygonFaces(mesh::parseMesh(ply, mesh::MeshFormat::Ply, "c.ply")), kPrismFaces);
  // A triangle file records nothing.
  EXPECT_TRUE(test_data::bunnyCage().polygonOf.empty());
  // writeObj → readMesh keeps the quads.
  const std::string path =
      (std::filesystem::temp_directory_path() / "softbody_polygon_cage_test.obj").string();
  mesh::writeObj(path, cage);
  const mesh::TriangleMesh back = mesh::readMesh(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.triangles, cage.triangles);
  EXPECT_EQ(back.polygonOf, cage.polygonOf);
}

TEST(PolygonCage, BrokenPolygonsNameFileAndLine) {
  const std::string head = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n";
  try {
    readObj(head + "f 1 2 3 2\n");
    FAIL() << "a repeated corner was accepted";
  } catch (const mesh::MeshError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "cage.obj: line 6: a polygon repeats a corner: corners 2 and 4 of 4"),
              std::string::npos)
        << e.what();
  }
  try {
    readObj(head + "f 1 2 5 2\n");
    FAIL() << "a repeated corner was accepted";
  } catch (const mesh::MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("line 6"), std::string::npos) << e.what();
  }
  try {
    readObj(head + "f 1 2 3 4\nf 1 2 5 1\n");
    FAIL();
  } catch (const mesh::MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("line 7"), std::string::npos) << e.what();
  }
  {  // one polygon of 200,000 corners on a circle, its last corner repeating its 7th: found
     // (sorted, not compared pairwise) with the first corner that repeats
    constexpr int kCorners = 200000;
    std::string text;
    for (int c = 0; c < kCorners; ++c) {
      const double a = 2.0 * M_PI * c / kCorners;
      text += "v " + std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0\n";
    }
    text += "f";
    for (int c = 1; c < kCorners; ++c) text += " " + std::to_string(c);
    text += " 7\n";
    try {
      readObj(text);
      FAIL() << "a repeated corner was accepted";
    } catch (const mesh::MeshError& e) {
      EXPECT_NE(std::string(e.what()).find("corners 7 and 200000 of 200000"), std::string::npos)
          << std::string(e.what()).substr(0, 300);
    }
  }
  try {  // all four corners on a line
    readObj("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n");
    FAIL() << "a degenerate quad was accepted";
  } catch (const mesh::MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("cage.obj: line 5: degenerate polygon of 4 corners"),
              std::string::npos)
        << e.what();
  }
}

TEST(PolygonCage, BindUsesPolygonMvcAndItsOwnCacheKey) {
  const std::vector<Vec3> v = frustumVertices();
  const mesh::TriangleMesh cage = readObj(objText(v, kHexFaces));
  const std::vector<Vec3> points = interiorPoints(v, 50, 1);
  const PolygonMeanValueCage poly(cage);
  const std::string dir =
      (std::filesystem::temp_directory_path() / "softbody_polygon_cache_test").string();
  std::filesystem::remove_all(dir);
  BindOptions o;
  o.storage = WeightStorage::Dense;
  o.cacheDir = dir;
  EXPECT_NE(bindCacheKey(points, cage, o), bindCacheKey(points, trianglesOnly(cage), o));
  // A triangle bind of the same triangles first, in the same cache: not reused.
  const Embedding t = bindToCage(points, trianglesOnly(cage), EmbeddingMethod{}, o);
  const Embedding p = bindToCage(points, cage, EmbeddingMethod{}, o);
  const Embedding again = bindToCage(points, cage, EmbeddingMethod{}, o);  // from the cache
  std::filesystem::remove_all(dir);
  std::vector<std::pair<int, double>> row, rowT, rowAgain;
  double differs = 0.0;
  for (int i = 0; i < int(points.size()); ++i) {
    const std::vector<double> w = polygonWeights(poly, points[std::size_t(i)]);
    p.rowWeights(i, row);
    t.rowWeights(i, rowT);
    again.rowWeights(i, rowAgain);
    ASSERT_EQ(row.size(), 8u);
    for (const auto& [j, wj] : row) EXPECT_NEAR(wj, w[std::size_t(j)], 1e-15);
    EXPECT_EQ(row, rowAgain);
    for (std::size_t k = 0; k < row.size(); ++k)
      differs = std::max(differs, std::abs(row[k].second - rowT[k].second));
  }
  EXPECT_GT(differs, 1e-4);  // triangle and polygon MVC really differ on this cage
}

}  // namespace
}  // namespace sb::cage
