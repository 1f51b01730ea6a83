// Green coordinates (sim/cage/green.h): the reproduction identity at rest, Σφ = 1, similarity
// invariance, the closed forms against a numerical quadrature of the boundary integrals, shape
// preservation against mean value coordinates under a non-affine bend, thread invariance, the
// kind through a weight file, and refused input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "sim/cage/green.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::cage {
namespace {

using MatX3d = Eigen::Matrix<double, Eigen::Dynamic, 3>;
using mesh::testing::makeBox;

MatX3d toMatrix(const std::vector<Vec3>& v) {
  MatX3d m(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.row(Eigen::Index(i)) = v[i].transpose();
  return m;
}

const mesh::TriangleMesh& bunnyCage() {
  static const mesh::TriangleMesh c =
      mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny_cage.obj");
  return c;
}
const mesh::TriangleMesh& bunny() {
  static const mesh::TriangleMesh c =
      mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj");
  return c;
}

mesh::TriangleMesh tetrahedron() {
  mesh::TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

// Random points strictly inside the box [lo, hi]³ margin away from its faces.
std::vector<Vec3> boxPoints(int n, const Vec3& lo, const Vec3& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> p(static_cast<std::size_t>(n));
  for (Vec3& x : p) x = lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
  return p;
}

MatX3d deformed(const Embedding& e, const MatX3d& moved) {
  MatX3d out;
  e.deformDouble(moved, out);  // the attached cage extends the vertices (greenControls)
  return out;
}

TEST(Green, RestPoseReproducesThePointsAndPhiSumsToOne) {
  const auto& cage = bunnyCage();
  const auto& points = bunny().vertices;
  const Embedding e = bindGreen(points, cage);
  EXPECT_EQ(e.kind(), EmbeddingKind::Green);
  const int V = int(cage.vertices.size()), F = int(cage.triangles.size());
  ASSERT_EQ(e.weightColumns(), V + F);
  ASSERT_EQ(e.cageVertexCount(), V);
  ASSERT_EQ(e.meshVertexCount(), int(points.size()));
  const MatX3d out = deformed(e, toMatrix(cage.vertices));
  const double diag = mesh::testing::diagonal(cage);
  double err = 0.0, sumErr = 0.0;
  std::vector<std::pair<int, double>> row;
  for (std::size_t i = 0; i < points.size(); ++i) {
    err = std::max(err, (out.row(Eigen::Index(i)).transpose() - points[i]).norm() / diag);
    e.rowWeights(int(i), row);
    double s = 0.0;
    for (const auto& [j, w] : row)
      if (j < V) s += w;
    sumErr = std::max(sumErr, std::abs(s - 1.0));
  }
  EXPECT_LT(err, 1e-10);
  EXPECT_LT(sumErr, 1e-10);
  EXPECT_LT(e.stats().maxSumError, 1e-10);
  EXPECT_LT(e.stats().maxLinearError, 1e-10);
  std::printf("rest pose: max |W c - x| / diagonal %.2e, max |sum phi - 1| %.2e\n", err, sumErr);
  // ψ_j = (1/4π) ∫ 1/r > 0 for every face.
  for (std::size_t i = 0; i < points.size(); i += 97) {
    e.rowWeights(int(i), row);
    for (const auto& [j, w] : row)
      if (j >= V) {
        EXPECT_GT(w, 0.0);
      }
  }
}

TEST(Green, SimilarityOfTheCageMovesEveryPointTheSame) {
  const auto& cage = bunnyCage();
  const auto& points = bunny().vertices;
  const Embedding e = bindGreen(points, cage);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Vec3(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  const Vec3 t(0.3, -2.0, 5.0);
  const double diag = mesh::testing::diagonal(cage);
  for (double k : {1.0, 0.25, 3.0}) {
    MatX3d moved = toMatrix(cage.vertices);
    for (Eigen::Index j = 0; j < moved.rows(); ++j)
      moved.row(j) = (k * R * moved.row(j).transpose() + t).transpose();
    const MatX3d out = deformed(e, moved);
    double err = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i)
      err = std::max(err, (out.row(Eigen::Index(i)).transpose() - (k * R * points[i] + t)).norm());
    EXPECT_LT(err / (k * diag), 1e-9) << "scale " << k;
  }
  // A shear is affine but not a similarity: Green coordinates do not reproduce it (and must not
  // be mistaken for an affine-invariant scheme); the error is of the order of the shear.
  MatX3d sheared = toMatrix(cage.vertices);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(0, 1) = 0.5;
  for (Eigen::Index j = 0; j < sheared.rows(); ++j)
    sheared.row(j) = (S * sheared.row(j).transpose()).transpose();
  const MatX3d out = deformed(e, sheared);
  double err = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i)
    err = std::max(err, (out.row(Eigen::Index(i)).transpose() - S * points[i]).norm());
  EXPECT_GT(err / diag, 1e-3);
}

// The boundary integrals by quadrature: each triangle split into k² similar sub-triangles,
// Dunavant's 7-point degree-5 rule on each; Γ_i is the barycentric coordinate of the quadrature
// point, φ_i = (1/4π) Σ ∫ Γ_i (ξ−η)·n/|ξ−η|³, ψ_j = (1/4π) ∫ 1/|ξ−η|.
void quadrature(const mesh::TriangleMesh& cage, const Vec3& eta, int k, Eigen::VectorXd& phi,
                Eigen::VectorXd& psi) {
  const double w[3] = {0.225, 0.132394152788506, 0.125939180544827};
  const double a1 = 0.059715871789770, b1 = 0.470142064105115;
  const double a2 = 0.797426985353087, b2 = 0.101286507323456;
  std::vector<std::pair<Vec3, double>> rule = {{Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3), w[0]},
                                               {Vec3(a1, b1, b1), w[1]},
                                               {Vec3(b1, a1, b1), w[1]},
                                               {Vec3(b1, b1, a1), w[1]},
                                               {Vec3(a2, b2, b2), w[2]},
                                               {Vec3(b2, a2, b2), w[2]},
                                               {Vec3(b2, b2, a2), w[2]}};
  phi = Eigen::VectorXd::Zero(Eigen::Index(cage.vertices.size()));
  psi = Eigen::VectorXd::Zero(Eigen::Index(cage.triangles.size()));
  for (std::size_t j = 0; j < cage.triangles.size(); ++j) {
    const auto& t = cage.triangles[j];
    const Vec3 P[3] = {cage.vertices[size_t(t[0])], cage.vertices[size_t(t[1])],
                       cage.vertices[size_t(t[2])]};
    const Vec3 cr = (P[1] - P[0]).cross(P[2] - P[0]);
    const Vec3 n = cr.normalized();
    const double subArea = 0.5 * cr.norm() / (k * k);
    // Sub-triangles in barycentric (i, j) grid cells: "up" and "down" triangles.
    auto addTriangle = [&](const Vec3& B0, const Vec3& B1, const Vec3& B2) {
      for (const auto& [q, wq] : rule) {
        const Vec3 bary = q[0] * B0 + q[1] * B1 + q[2] * B2;
        const Vec3 xi = bary[0] * P[0] + bary[1] * P[1] + bary[2] * P[2];
        const Vec3 d = xi - eta;
        const double r = d.norm();
        const double dw = wq * subArea / (4.0 * M_PI);
        psi[Eigen::Index(j)] += dw / r;
        for (int c = 0; c < 3; ++c) phi[t[size_t(c)]] += dw * bary[c] * d.dot(n) / (r * r * r);
      }
    };
    for (int i = 0; i < k; ++i)
      for (int l = 0; l < k - i; ++l) {
        auto B = [&](int u, int v) {
          return Vec3(1.0 - double(u + v) / k, double(u) / k, double(v) / k);
        };
        addTriangle(B(i, l), B(i + 1, l), B(i, l + 1));
        if (l + 1 < k - i) addTriangle(B(i + 1, l), B(i + 1, l + 1), B(i, l + 1));
      }
  }
}

TEST(Green, ClosedFormsMatchQuadratureOfTheBoundaryIntegrals) {
  struct Case {
    mesh::TriangleMesh cage;
    std::vector<Vec3> points;
  };
  std::vector<Case> cases;
  cases.push_back({tetrahedron(), {{0.25, 0.25, 0.25}, {0.1, 0.2, 0.3}, {0.5, 0.2, 0.15}}});
  cases.push_back({makeBox(1, 1, 1), {{0.5, 0.5, 0.5}, {0.2, 0.7, 0.4}, {0.8, 0.15, 0.75}}});
  cases.push_back({makeBox(2, 1, 3, Vec3(2.0, 1.0, 1.5)), {{0.3, 0.4, 0.5}, {1.7, 0.8, 1.2}}});
  // Non-convex L: points in, or a hair off, the planes of the inner-corner faces, away from
  // those faces (the near-plane form of the solid angle, and Ω = 0 in the plane).
  cases.push_back({mesh::testing::makeLShape(),
                   {{0.5, 1.0, 0.5}, {0.5, 1.0 + 1e-3, 0.4}, {1.0 - 1e-4, 0.5, 0.6}}});
  double worstPhi = 0.0, worstPsi = 0.0;
  for (const Case& c : cases) {
    for (const Vec3& eta : c.points) {
      Eigen::VectorXd phi, psi, qphi, qpsi;
      const double winding = greenCoordinates(eta, c.cage, phi, psi);
      EXPECT_NEAR(winding, 1.0, 1e-12);
      quadrature(c.cage, eta, 64, qphi, qpsi);
      EXPECT_LT((phi - qphi).cwiseAbs().maxCoeff(), 1e-9) << eta.transpose();
      EXPECT_LT((psi - qpsi).cwiseAbs().maxCoeff(), 1e-9) << eta.transpose();
      worstPhi = std::max(worstPhi, (phi - qphi).cwiseAbs().maxCoeff());
      worstPsi = std::max(worstPsi, (psi - qpsi).cwiseAbs().maxCoeff());
      // The quadrature itself satisfies the identity (a check of the oracle).
      Vec3 p = Vec3::Zero();
      for (Eigen::Index i = 0; i < qphi.size(); ++i) p += qphi[i] * c.cage.vertices[size_t(i)];
      for (std::size_t j = 0; j < c.cage.triangles.size(); ++j) {
        const auto& t = c.cage.triangles[j];
        p += qpsi[Eigen::Index(j)] *
             (c.cage.vertices[size_t(t[1])] - c.cage.vertices[size_t(t[0])])
                 .cross(c.cage.vertices[size_t(t[2])] - c.cage.vertices[size_t(t[0])])
                 .normalized();
      }
      EXPECT_LT((p - eta).norm(), 1e-6);
    }
  }
  std::printf("closed form vs quadrature: max |dphi| %.2e, max |dpsi| %.2e\n", worstPhi, worstPsi);
}

// Shape preservation: a bar cage [-2, 2] × [-0.5, 0.5]² bent non-affinely, the local Jacobian J
// at 200 interior points by central differences, its conformality error σ_max/σ_min − 1
// (0 for a similarity). Mean value coordinates follow the cage's own map, which shears (parabolic
// bend) or stretches the outer fibres and compresses the inner ones (circular bend); Green
// coordinates keep the map closer to a similarity. Measured (mean over the points): parabolic
// bend green 0.156, mvc 0.402; circular bend green 0.085, mvc 0.113 (the cage map itself is far
// from conformal there: its fibres stretch by 1 ± y/ρ).
double meanConformalityError(const Embedding& e, const MatX3d& cage,
                             const std::vector<Vec3>& centres, double delta) {
  MatX3d out;
  e.deformDouble(cage, out);
  double sum = 0.0;
  for (std::size_t c = 0; c < centres.size(); ++c) {
    Eigen::Matrix3d J;
    for (int d = 0; d < 3; ++d)
      J.col(d) =
          (out.row(Eigen::Index(7 * c + 1 + 2 * d)) - out.row(Eigen::Index(7 * c + 2 + 2 * d)))
              .transpose() /
          (2.0 * delta);
    const Vec3 sv = Eigen::JacobiSVD<Eigen::Matrix3d>(J).singularValues();
    sum += sv[0] / sv[2] - 1.0;
  }
  return sum / double(centres.size());
}

TEST(Green, BendingKeepsShapesCloserToSimilaritiesThanMeanValueCoordinates) {
  const mesh::TriangleMesh bar = makeBox(8, 2, 2, Vec3(4.0, 1.0, 1.0), Vec3(-2.0, -0.5, -0.5));
  const std::vector<Vec3> centres = boxPoints(200, Vec3(-1.6, -0.3, -0.3), Vec3(1.6, 0.3, 0.3), 3);
  const double delta = 1e-4;
  std::vector<Vec3> points;
  for (const Vec3& c : centres) {
    points.push_back(c);
    for (int d = 0; d < 3; ++d) {
      points.push_back(c + delta * Vec3::Unit(d));
      points.push_back(c - delta * Vec3::Unit(d));
    }
  }
  const Embedding green = bindGreen(points, bar);
  const Embedding mvc = bindMeanValue(points, bar);
  auto errors = [&](auto bend) {
    MatX3d moved(Eigen::Index(bar.vertices.size()), 3);
    for (std::size_t v = 0; v < bar.vertices.size(); ++v)
      moved.row(Eigen::Index(v)) = bend(bar.vertices[v]).transpose();
    return std::make_pair(meanConformalityError(green, moved, centres, delta),
                          meanConformalityError(mvc, moved, centres, delta));
  };
  // Parabolic bend y += 0.2 x².
  const auto [gP, mP] =
      errors([](const Vec3& p) { return Vec3(p.x(), p.y() + 0.2 * p.x() * p.x(), p.z()); });
  EXPECT_LT(gP, 0.5 * mP) << "green " << gP << ", mvc " << mP;
  // Circular bend: the axis onto a circle of radius 2, x ↦ angle x/2 at radius 2 + y.
  const auto [gC, mC] = errors([](const Vec3& p) {
    const double a = p.x() / 2.0, r = 2.0 + p.y();
    return Vec3(r * std::sin(a), r * std::cos(a) - 2.0, p.z());
  });
  EXPECT_LT(gC, 0.85 * mC) << "green " << gC << ", mvc " << mC;
  std::printf(
      "conformality error, parabolic bend: green %.4f mvc %.4f; circular: green %.4f mvc %.4f\n",
      gP, mP, gC, mC);
}

// Points close to the cage (1e-3 … 1e-10 of the size inside a face, near an edge and a corner,
// near the shared diagonal of a split quad): the closed forms stay accurate there (no ε test,
// no cancellation in the edge integrals), so the identities still hold.
TEST(Green, PointsCloseToTheCageKeepTheIdentities) {
  // The box as given (exact coordinates, flat faces exactly coplanar) and rotated (every
  // coordinate rounded). Measured worst reproduction error (box size 1), rotated box:
  // d ≥ 1e-5: 5e-14, 1e-6: 5e-13, 1e-7: 5e-12, 1e-8: 1e-10, 1e-9: 2e-9, 1e-10: 3e-8,
  // 1e-11: 1.1e-7 — each face's solid angle near an edge is conditioned like 1e-16 / d, and the
  // faces' rounding no longer cancels; exact box: ≤ 6e-16 at every d.
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.9, Vec3(0.3, 1.0, -0.7).normalized()).toRotationMatrix();
  for (int rotated = 0; rotated < 2; ++rotated) {
    mesh::TriangleMesh box = makeBox(2, 2, 2);
    const Eigen::Matrix3d M = rotated ? R : Eigen::Matrix3d::Identity();
    for (Vec3& v : box.vertices) v = M * v;
    std::vector<Vec3> points;
    std::vector<double> distance;
    for (double d = 1e-2; d > 1e-11; d *= 0.1) {
      for (const Vec3& p : {Vec3(0.3, 0.6, 1.0 - d),               // over a face
                            Vec3(0.5, d, d),                       // near an edge
                            Vec3(d, d, d),                         // near a corner
                            Vec3(0.25 + d, 0.25, 1.0 - d),         // near a quad's diagonal
                            Vec3(0.5 + 0.5 * d, 0.5, 1.0 - d)}) {  // near a flat vertex
        points.push_back(M * p);
        distance.push_back(d);
      }
    }
    const Embedding e = bindGreen(points, box);
    const MatX3d out = deformed(e, toMatrix(box.vertices));
    std::vector<std::pair<int, double>> row;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double err = (out.row(Eigen::Index(i)).transpose() - points[i]).norm();
      e.rowWeights(int(i), row);
      double sum = -1.0;
      for (const auto& [j, w] : row)
        if (j < int(box.vertices.size())) sum += w;
      const double bound = !rotated ? 1e-14 : distance[i] >= 0.9e-7 ? 1e-11 : 1e-6;
      EXPECT_LT(err, bound) << "rotated " << rotated << ", d " << distance[i] << ", point " << i;
      EXPECT_LT(std::abs(sum), bound) << "rotated " << rotated << ", d " << distance[i];
    }
  }
}

TEST(Green, ThreadCountDoesNotChangeTheWeights) {
  const auto& cage = bunnyCage();
  const auto& points = bunny().vertices;
  GreenOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const Embedding a = bindGreen(points, cage, one), b = bindGreen(points, cage, two);
  std::vector<std::pair<int, double>> ra, rb;
  for (int i = 0; i < a.meshVertexCount(); ++i) {
    a.rowWeights(i, ra);
    b.rowWeights(i, rb);
    ASSERT_EQ(ra, rb) << "row " << i;
  }
}

class GreenFile : public sb::test_support::TempDirTest {};

TEST_F(GreenFile, KindAndWeightsSurviveAWeightFile) {
  const auto& cage = bunnyCage();
  std::vector<Vec3> points(bunny().vertices.begin(), bunny().vertices.begin() + 50);
  const Embedding e = bindGreen(points, cage);
  const std::string path = this->path("green.sbw");
  e.save(path);
  const Embedding back = Embedding::load(path);
  EXPECT_EQ(back.kind(), EmbeddingKind::Green);
  EXPECT_STREQ(embeddingKindName(back.kind()), "green");
  std::vector<std::pair<int, double>> ra, rb;
  for (int i = 0; i < e.meshVertexCount(); ++i) {
    e.rowWeights(i, ra);
    back.rowWeights(i, rb);
    ASSERT_EQ(ra, rb);
  }
}

// With the rest cage attached (bindGreen does it), deform takes the V cage vertices and equals
// the weights times the extended controls built here by hand, in float and in double; the same
// weights without the cage (a weight file loaded alone) take the V + F extended controls.
TEST_F(GreenFile, AnAttachedCageExtendsTheVerticesInEveryDeform) {
  const auto& cage = bunnyCage();
  const std::vector<Vec3> points(bunny().vertices.begin(), bunny().vertices.begin() + 300);
  const Embedding e = bindGreen(points, cage);
  ASSERT_NE(e.greenCage(), nullptr);
  const int V = int(cage.vertices.size()), F = int(cage.triangles.size());
  EXPECT_EQ(e.cageVertexCount(), V);
  EXPECT_EQ(e.weightColumns(), V + F);
  MatX3d moved(V, 3);
  for (int v = 0; v < V; ++v) {
    const Vec3& p = cage.vertices[size_t(v)];
    moved.row(v) = Vec3(p.x() + 0.3 * p.y() * p.y(), 1.2 * p.y(), p.z() - 0.2 * p.x()).transpose();
  }
  const MatX3d controls = greenControls(cage, moved);
  std::vector<std::pair<int, double>> row;
  MatX3d byHand(Eigen::Index(points.size()), 3);
  for (int i = 0; i < int(points.size()); ++i) {
    e.rowWeights(i, row);
    Vec3 x = Vec3::Zero();
    for (const auto& [j, w] : row) x += w * controls.row(j).transpose();
    byHand.row(i) = x.transpose();
  }
  EXPECT_LT((deformed(e, moved) - byHand).cwiseAbs().maxCoeff(), 1e-12);
  PointsRowMajor outF;
  e.deform(moved.cast<float>(), outF);
  EXPECT_LT((outF.cast<double>() - byHand).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_THROW(e.deform(controls.cast<float>(), outF), std::invalid_argument);  // V + F rows

  e.save(path("green.bin"));
  const Embedding alone = Embedding::load(path("green.bin"));
  EXPECT_EQ(alone.kind(), EmbeddingKind::Green);
  EXPECT_EQ(alone.greenCage(), nullptr);
  EXPECT_EQ(alone.cageVertexCount(), V + F);
  MatX3d outAlone;
  alone.deformDouble(controls, outAlone);
  EXPECT_LT((outAlone - byHand).cwiseAbs().maxCoeff(), 1e-12);
  Embedding other = bindMeanValue(points, cage);
  EXPECT_THROW(other.attachGreenCage(std::make_shared<const mesh::TriangleMesh>(cage)),
               std::invalid_argument);
}

TEST(Green, RefusesBadInput) {
  const mesh::TriangleMesh box = makeBox(1, 1, 1);
  auto message = [&](const std::vector<Vec3>& points, const mesh::TriangleMesh& cage) {
    try {
      bindGreen(points, cage);
    } catch (const std::exception& ex) {
      return std::string(ex.what());
    }
    return std::string("no error");
  };
  const std::vector<Vec3> inside = {{0.5, 0.5, 0.5}};
  mesh::TriangleMesh open = box;
  open.triangles.pop_back();
  EXPECT_NE(message(inside, open).find("cage"), std::string::npos) << message(inside, open);
  EXPECT_NE(message(inside, open).find("edge"), std::string::npos) << message(inside, open);
  mesh::TriangleMesh inverted = box;
  for (auto& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_NE(message(inside, inverted).find("cage"), std::string::npos);
  EXPECT_THROW(bindGreen(inside, inverted), mesh::SurfaceError);
  const std::string nan = message({{0.5, 0.5, 0.5}, {0.5, std::nan(""), 0.5}}, box);
  EXPECT_NE(nan.find("point 1 is not finite"), std::string::npos) << nan;
  const std::string outside = message({{0.5, 0.5, 0.5}, {0.2, 0.2, 0.2}, {1.5, 0.5, 0.5}}, box);
  EXPECT_NE(outside.find("point 2 (1.5, 0.5, 0.5) is outside the cage"), std::string::npos)
      << outside;
  const std::string onFace = message({{0.5, 0.5, 0.5}, {0.3, 0.6, 1.0}}, box);
  EXPECT_NE(onFace.find("point 1 (0.3, 0.6, 1) is on the cage"), std::string::npos) << onFace;
  const std::string onEdge = message({{0.5, 0.0, 0.0}}, box);
  EXPECT_NE(onEdge.find("point 0"), std::string::npos) << onEdge;
  // Not a refusal: a point a hair inside a face.
  EXPECT_NO_THROW(bindGreen({{0.3, 0.6, 1.0 - 1e-9}}, box));
  EXPECT_THROW(greenControls(box, MatX3d::Zero(3, 3)), std::invalid_argument);
}

// A deformed triangle crushed to a segment has no normal: its face control is zero and the
// deform stays finite.
TEST(Green, ACrushedFaceContributesNothingAndStaysFinite) {
  const mesh::TriangleMesh box = makeBox(1, 1, 1, Vec3(1.0, 1.0, 1.0), Vec3::Zero());
  MatX3d moved(Eigen::Index(box.vertices.size()), 3);
  for (std::size_t v = 0; v < box.vertices.size(); ++v)
    moved.row(Eigen::Index(v)) = box.vertices[v].transpose();
  const auto& t = box.triangles[0];
  moved.row(t[2]) = 0.5 * (moved.row(t[0]) + moved.row(t[1]));  // triangle 0 becomes a segment
  const MatX3d controls = greenControls(box, moved);
  EXPECT_EQ(controls.row(Eigen::Index(box.vertices.size())).norm(), 0.0);
  EXPECT_TRUE(controls.allFinite());
  const Embedding e = bindGreen({{0.5, 0.5, 0.5}, {0.2, 0.7, 0.4}}, box);
  EXPECT_TRUE(deformed(e, moved).allFinite());
}

}  // namespace
}  // namespace sb::cage
