// Mean value coordinates: invariants (partition of unity, linear precision), the closed form
// against an independent implementation of the JSW pseudo-code, on-cage interpolation,
// continuity near faces, in-plane points, exterior points and scale invariance.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <vector>

#include "sim/cage/mvc.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "tests/draws.h"
#include "tests/mesh/mesh_fixtures.h"

namespace sb::cage {
using namespace sb::mesh;  // meshes, mesh files, surfaces
namespace {

using testing::diagonal;
using Vec3 = Eigen::Vector3d;

struct Eval {
  std::vector<double> w;
  MvcInfo info;
};

Eval evalAt(const MeanValueCage& mc, const Vec3& x) {
  Eval e;
  e.w.resize(mc.vertexCount());
  MeanValueCage::Scratch s;
  EXPECT_TRUE(mc.weights(x, e.w.data(), s, &e.info)) << x.transpose();
  return e;
}

// max(|Σw − 1|, |Σ w v − x| / L)
std::pair<double, double> errors(const TriangleMesh& cage, const std::vector<double>& w,
                                 const Vec3& x) {
  double sum = 0.0;
  Vec3 p = Vec3::Zero();
  for (std::size_t j = 0; j < w.size(); ++j) {
    EXPECT_TRUE(std::isfinite(w[j]));
    sum += w[j];
    p += w[j] * cage.vertices[j];
  }
  return {std::abs(sum - 1.0), (p - x).norm() / diagonal(cage)};
}

// Independent reference: the pseudo-code of Ju, Schaefer, Warren 2005 (Fig. 4), for points
// where it is well conditioned (not near the cage or the planes of its faces).
std::vector<double> jswReference(const TriangleMesh& cage, const Vec3& x) {
  const std::size_t n = cage.vertices.size();
  std::vector<Vec3> u(n);
  std::vector<double> d(n), w(n, 0.0);
  for (std::size_t j = 0; j < n; ++j) {
    d[j] = (cage.vertices[j] - x).norm();
    u[j] = (cage.vertices[j] - x) / d[j];
  }
  double total = 0.0;
  for (const auto& t : cage.triangles) {
    double theta[3], c[3], s[3], l[3];
    for (int i = 0; i < 3; ++i) {
      l[i] = (u[t[(i + 1) % 3]] - u[t[(i + 2) % 3]]).norm();
      theta[i] = 2.0 * std::asin(std::min(1.0, l[i] / 2.0));
    }
    const double h = (theta[0] + theta[1] + theta[2]) / 2.0;
    Eigen::Matrix3d U;
    U << u[t[0]], u[t[1]], u[t[2]];
    const double sign = U.determinant() < 0 ? -1.0 : 1.0;
    for (int i = 0; i < 3; ++i) {
      c[i] = 2.0 * std::sin(h) * std::sin(h - theta[i]) /
                 (std::sin(theta[(i + 1) % 3]) * std::sin(theta[(i + 2) % 3])) -
             1.0;
      s[i] = sign * std::sqrt(std::max(0.0, 1.0 - c[i] * c[i]));
    }
    for (int i = 0; i < 3; ++i) {
      const int ip = (i + 1) % 3, im = (i + 2) % 3;
      const double wi = (theta[i] - c[ip] * theta[im] - c[im] * theta[ip]) /
                        (d[t[i]] * std::sin(theta[ip]) * s[im]);
      w[t[i]] += wi;
      total += wi;
    }
  }
  for (auto& v : w) v /= total;
  return w;
}

struct Named {
  std::string name;
  TriangleMesh cage;
};

std::vector<Named> generatedCages() {
  return {{"cube", testing::makeBox(1, 1, 1)},
          {"box3", testing::makeBox(3, 2, 4, Vec3(1.0, 0.7, 1.3))},
          {"icosphere", testing::makeIcosphere(2)},
          {"L", testing::makeLShape()},
          {"star", testing::makeStar()},
          {"torus", testing::makeTorus()}};
}

bool insideNamed(const std::string& name, const Vec3& p) {
  if (name == "cube") return (p.array() > 0).all() && (p.array() < 1).all();
  if (name == "box3")
    return (p.array() > 0).all() && (p.array() < Eigen::Array3d(1.0, 0.7, 1.3)).all();
  if (name == "icosphere") return p.norm() < 0.9;  // the subdivided icosahedron contains r < 0.9
  if (name == "L") return testing::insideLShape(p);
  if (name == "star") return p.head<2>().norm() < 0.3 && p.z() > 0 && p.z() < 0.5;
  if (name == "torus") {
    const double rho = p.head<2>().norm();
    return std::hypot(rho - 1.0, p.z()) < 0.3;
  }
  return false;
}

TEST(CageFixtures, GeneratedCagesAreValid) {
  for (const auto& c : generatedCages())
    EXPECT_NO_THROW(validateClosedSurface(c.cage, c.name)) << c.name;
  EXPECT_EQ(testing::makeBox(6, 6, 20).vertices.size(), 554u);
  EXPECT_EQ(testing::makeBox(24, 24, 80).vertices.size(), 8834u);
}

TEST(Mvc, InteriorPartitionOfUnityAndLinearPrecision) {
  std::mt19937 rng(7);
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    Eigen::AlignedBox3d box;
    for (const auto& v : c.cage.vertices) box.extend(v);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    int tested = 0;
    for (int k = 0; k < 4000 && tested < 150; ++k) {
      const Vec3 x =
          box.min() + box.sizes().cwiseProduct(test::drawVector<Vec3>([&] { return U(rng); }));
      if (!insideNamed(c.name, x)) continue;
      ++tested;
      const Eval e = evalAt(mc, x);
      const auto [sumErr, linErr] = errors(c.cage, e.w, x);
      EXPECT_LT(sumErr, 1e-10) << c.name << " at " << x.transpose();
      EXPECT_LT(linErr, 1e-10) << c.name << " at " << x.transpose();
    }
    EXPECT_GE(tested, 100) << c.name;
  }
}

TEST(Mvc, MatchesIndependentJswFormulaAtGenericPoints) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    Eigen::AlignedBox3d box;
    for (const auto& v : c.cage.vertices) box.extend(v);
    const Vec3 centre = box.center();
    const double L = diagonal(c.cage);
    int tested = 0;
    for (int k = 0; k < 3000 && tested < 40; ++k) {
      // inside and outside, but at least 2% of L from every face plane (where JSW is accurate)
      const Vec3 x = centre + 0.8 * L * test::drawVector<Vec3>([&] { return U(rng); });
      bool clear = true;
      for (const auto& t : c.cage.triangles) {
        const Vec3 n = (c.cage.vertices[t[1]] - c.cage.vertices[t[0]])
                           .cross(c.cage.vertices[t[2]] - c.cage.vertices[t[0]])
                           .normalized();
        if (std::abs(n.dot(x - c.cage.vertices[t[0]])) < 0.005 * L) clear = false;
      }
      if (!clear) continue;
      ++tested;
      const auto ref = jswReference(c.cage, x);
      const Eval e = evalAt(mc, x);
      double maxAbs = 0.0;
      for (double v : ref) maxAbs = std::max(maxAbs, std::abs(v));
      for (std::size_t j = 0; j < ref.size(); ++j)
        ASSERT_NEAR(e.w[j], ref[j], 1e-9 * std::max(1.0, maxAbs))
            << c.name << " vertex " << j << " at " << x.transpose();
    }
    EXPECT_GE(tested, 5) << c.name;
  }
}

TEST(Mvc, NegativeWeightsAreKeptForNonConvexCages) {
  const TriangleMesh cage = testing::makeLShape();
  const MeanValueCage mc(cage);
  // Deep in one arm of the L: vertices at the far end of the other arm get negative weight.
  const Vec3 x(1.8, 0.5, 0.5);
  const Eval e = evalAt(mc, x);
  double minW = 1.0;
  for (double v : e.w) minW = std::min(minW, v);
  EXPECT_LT(minW, -1e-4);
  const auto [sumErr, linErr] = errors(cage, e.w, x);
  EXPECT_LT(sumErr, 1e-12);
  EXPECT_LT(linErr, 1e-12);  // would fail if negative weights were clamped
}

TEST(Mvc, OnVerticesGiveKroneckerDelta) {
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    for (std::size_t j = 0; j < c.cage.vertices.size(); j += 3) {
      const Eval e = evalAt(mc, c.cage.vertices[j]);
      for (std::size_t k = 0; k < e.w.size(); ++k) ASSERT_EQ(e.w[k], k == j ? 1.0 : 0.0) << c.name;
    }
  }
}

// Expect exactly the barycentric coordinates (a, b, c) on triangle t's vertices and 0 elsewhere.
void expectBarycentric(const TriangleMesh& cage, const std::vector<double>& w,
                       const std::array<int, 3>& t, const std::array<double, 3>& bary, double tol,
                       const std::string& what) {
  for (std::size_t k = 0; k < w.size(); ++k) {
    double expect = 0.0;
    for (int i = 0; i < 3; ++i)
      if (t[i] == static_cast<int>(k)) expect += bary[i];
    ASSERT_NEAR(w[k], expect, tol) << what << " vertex " << k;
  }
  (void)cage;
}

TEST(Mvc, OnEdgesAndFacesGiveBarycentricCoordinates) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0.02, 0.98);
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    for (std::size_t ti = 0; ti < c.cage.triangles.size(); ti += 5) {
      const auto& t = c.cage.triangles[ti];
      const Vec3 a = c.cage.vertices[t[0]], b = c.cage.vertices[t[1]], d = c.cage.vertices[t[2]];
      // on edge a-b
      const double s = U(rng);
      const Vec3 xe = (1 - s) * a + s * b;
      expectBarycentric(c.cage, evalAt(mc, xe).w, t, {1 - s, s, 0.0}, 1e-12, c.name + " edge");
      // inside the face
      double l1 = U(rng), l2 = U(rng);
      if (l1 + l2 > 0.98) {
        l1 *= 0.5;
        l2 *= 0.5;
      }
      const Vec3 xf = a + l1 * (b - a) + l2 * (d - a);
      const Eval e = evalAt(mc, xf);
      expectBarycentric(c.cage, e.w, t, {1 - l1 - l2, l1, l2}, 1e-12, c.name + " face");
    }
  }
}

TEST(Mvc, CentreOfSplitBoxFaceIsOnTheDiagonal) {
  const TriangleMesh cube = testing::makeBox(1, 1, 1);
  const MeanValueCage mc(cube);
  for (const Vec3& x :
       {Vec3(0.5, 0.5, 1.0), Vec3(0.5, 0.5, 0.0), Vec3(1.0, 0.5, 0.5), Vec3(0.5, 0.0, 0.5)}) {
    const Eval e = evalAt(mc, x);
    // Exactly two diagonal corners of that face get 1/2.
    int halves = 0;
    for (std::size_t k = 0; k < e.w.size(); ++k) {
      if (std::abs(e.w[k] - 0.5) < 1e-14) {
        ++halves;
        EXPECT_NEAR((cube.vertices[k] - x).norm(), std::sqrt(0.5), 1e-14);
      } else {
        EXPECT_NEAR(e.w[k], 0.0, 1e-14);
      }
    }
    EXPECT_EQ(halves, 2) << x.transpose();
  }
}

// Points 1e-3 … 1e-9 (relative) off a face, inside and outside: no snapping, no blow-up; the
// weights converge to the barycentric coordinates roughly linearly in the offset.
TEST(Mvc, ContinuousNearFacesAndEdges) {
  const std::vector<Named> cages = {{"cube", testing::makeBox(1, 1, 1)},
                                    {"L", testing::makeLShape()},
                                    {"icosphere", testing::makeIcosphere(1)}};
  for (const auto& c : cages) {
    const MeanValueCage mc(c.cage);
    const double L = diagonal(c.cage);
    for (std::size_t ti = 0; ti < c.cage.triangles.size(); ti += 3) {
      const auto& t = c.cage.triangles[ti];
      const Vec3 a = c.cage.vertices[t[0]], b = c.cage.vertices[t[1]], d = c.cage.vertices[t[2]];
      const Vec3 n = (b - a).cross(d - a).normalized();
      // the centroid, and a point on edge a-b (the diagonal of a split quad for the cube)
      std::vector<std::pair<Vec3, std::array<double, 3>>> bases = {
          {(a + b + d) / 3.0, {1.0 / 3, 1.0 / 3, 1.0 / 3}}};
      // Edge a-b, when the neighbouring triangle across it is coplanar (e.g. a split quad's
      // diagonal); at a crease the offset point would lie on the other face.
      for (const auto& o : c.cage.triangles) {
        int shared = 0;
        for (int k = 0; k < 3; ++k) shared += (o[k] == t[0] || o[k] == t[1]) ? 1 : 0;
        if (shared == 2 && o != t) {
          const Vec3 no = (c.cage.vertices[o[1]] - c.cage.vertices[o[0]])
                              .cross(c.cage.vertices[o[2]] - c.cage.vertices[o[0]])
                              .normalized();
          if (no.dot(n) > 1.0 - 1e-12) bases.push_back({0.5 * (a + b), {0.5, 0.5, 0.0}});
        }
      }
      for (const auto& [p, bary] : bases) {
        for (double side : {1.0, -1.0}) {
          double prevDev = 1e300;
          for (double rel = 1e-3; rel >= 0.99e-9; rel /= 10.0) {
            const Vec3 x = p + side * rel * L * n;
            const Eval e = evalAt(mc, x);
            ASSERT_EQ(e.info.kind, MvcCase::General) << "snapped at offset " << rel;
            const auto [sumErr, linErr] = errors(c.cage, e.w, x);
            EXPECT_LT(sumErr, 1e-10) << c.name << " offset " << rel;
            EXPECT_LT(linErr, 1e-10) << c.name << " offset " << rel;
            double dev = 0.0;
            for (std::size_t k = 0; k < e.w.size(); ++k) {
              double expect = 0.0;
              for (int i = 0; i < 3; ++i)
                if (t[i] == static_cast<int>(k)) expect += bary[i];
              dev = std::max(dev, std::abs(e.w[k] - expect));
            }
            // Deviation O(offset · log): bounded, shrinking with the offset, never exactly 0.
            EXPECT_LT(dev, 200.0 * rel)
                << c.name << " tri " << ti << " offset " << rel << " side " << side;
            EXPECT_GT(dev, 0.0) << "snapped onto the face at offset " << rel;
            EXPECT_LT(dev, prevDev * 0.5) << c.name << " not converging at " << rel;
            prevDev = dev;
          }
        }
      }
    }
  }
}

// Points in the plane of a non-adjacent face of a non-convex cage: finite, linear precision,
// and continuous with the points slightly above and below that plane.
TEST(Mvc, PointsInThePlaneOfNonAdjacentFaces) {
  const TriangleMesh cage = testing::makeLShape();
  const MeanValueCage mc(cage);
  // The inner walls are x = 1 (y in [1,2]) and y = 1 (x in [1,2]); points of the plane y = 1
  // with x < 1 and of x = 1 with y < 1 are inside the L, away from those walls.
  std::vector<Vec3> pts;
  for (double s : {0.1, 0.3, 0.5, 0.7, 0.9, 0.99})
    for (double z : {0.25, 0.5, 0.75}) {
      pts.emplace_back(s, 1.0, z);
      pts.emplace_back(1.0, s, z);
    }
  // Also the plane z = 0.5 is not a face; use the top plane z=1 extended: points outside the L
  // in the plane of its top (x in (1,2), y in (1,2)).
  pts.emplace_back(1.5, 1.5, 1.0);
  pts.emplace_back(1.9, 1.2, 0.0);
  for (const Vec3& x : pts) {
    const Eval e0 = evalAt(mc, x);
    const auto [sumErr, linErr] = errors(cage, e0.w, x);
    EXPECT_LT(sumErr, 1e-10) << x.transpose();
    EXPECT_LT(linErr, 1e-10) << x.transpose();
    for (const Vec3& dir : {Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)}) {
      for (double off : {1e-6, 1e-9, 1e-12}) {
        for (double sgn : {1.0, -1.0}) {
          const Eval e1 = evalAt(mc, x + sgn * off * dir);
          double diff = 0.0;
          for (std::size_t k = 0; k < e0.w.size(); ++k)
            diff = std::max(diff, std::abs(e1.w[k] - e0.w[k]));
          EXPECT_LT(diff, 1e-9 + 100.0 * off) << x.transpose() << " offset " << off;
        }
      }
    }
  }
}

TEST(Mvc, ExteriorPointsUpToFourTimesTheCageSize) {
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 1.0);
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    Eigen::AlignedBox3d box;
    for (const auto& v : c.cage.vertices) box.extend(v);
    const double L = diagonal(c.cage);
    for (double dist : {0.75, 1.0, 2.0, 4.0}) {
      for (int k = 0; k < 20; ++k) {
        const Vec3 x =
            box.center() + dist * L * test::drawVector<Vec3>([&] { return N(rng); }).normalized();
        const Eval e = evalAt(mc, x);
        const auto [sumErr, linErr] = errors(c.cage, e.w, x);
        EXPECT_LT(sumErr, 1e-8) << c.name << " at " << dist;
        EXPECT_LT(linErr, 1e-8) << c.name << " at " << dist;
      }
    }
  }
}

TEST(Mvc, FarAwayPointsAreFlaggedWithTheirAccuracy) {
  std::mt19937 rng(9);
  std::normal_distribution<double> N(0.0, 1.0);
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    for (double dist : {3.9, 10.0, 30.0, 100.0, 1000.0}) {
      for (int k = 0; k < 10; ++k) {
        const Vec3 x = mc.centre() + dist * mc.diagonal() * test::drawVector<Vec3>([&] {
                                                              return N(rng);
                                                            }).normalized();
        const Eval e = evalAt(mc, x);
        EXPECT_NEAR(e.info.distance, dist, 1e-9 * dist);
        EXPECT_EQ(e.info.far, dist > 4.0);
        const auto [sumErr, linErr] = errors(c.cage, e.w, x);
        // The documented accuracy (README.md) holds.
        EXPECT_LT(linErr, e.info.errorEstimate) << c.name << " at " << dist;
        EXPECT_LT(sumErr, std::max(1e-12, e.info.errorEstimate * dist)) << c.name << " at " << dist;
      }
    }
  }
}

// Weights are invariant under uniform scaling and translation of cage and point together.
TEST(Mvc, ScaleInvariance) {
  const TriangleMesh base = testing::makeLShape();
  const MeanValueCage mc(base);
  std::vector<Vec3> pts = {{0.3, 0.4, 0.5},        {1.5, 0.5, 0.5}, {0.5, 1.0, 0.5},
                           {1.0, 0.5, 0.9},        {0.5, 0.5, 1.0}, {0.5, 0.5, 1.0 + 1e-9},
                           {0.5, 0.5, 1.0 - 1e-7}, {2.0, 1.0, 1.0}, {3.0, -1.0, 2.0},
                           {0.25, 0.25, 0.0},      {1.0, 1.0, 0.5}};
  for (double scale : {1e-4, 1e4}) {
    TriangleMesh scaled = base;
    const Vec3 shift(0.25 * scale, -3.0 * scale, 1.5 * scale);
    for (auto& v : scaled.vertices) v = v * scale + shift;
    const MeanValueCage ms(scaled);
    for (const Vec3& x : pts) {
      const Eval e0 = evalAt(mc, x);
      const Eval e1 = evalAt(ms, x * scale + shift);
      EXPECT_EQ(e0.info.kind, e1.info.kind) << x.transpose();
      for (std::size_t k = 0; k < e0.w.size(); ++k)
        ASSERT_NEAR(e1.w[k], e0.w[k], 1e-9) << "scale " << scale << " at " << x.transpose();
      const auto [sumErr, linErr] = errors(scaled, e1.w, x * scale + shift);
      EXPECT_LT(sumErr, 1e-10);
      EXPECT_LT(linErr, 1e-10);
    }
  }
}

// A cage with a sliver triangle (height 1e-8 of its length) passes validation and gives finite
// weights with full accuracy around it.
TEST(Mvc, NearDegenerateTrianglesGiveNoNaN) {
  for (double eps : {1e-6, 1e-8, 1e-10}) {
    TriangleMesh cage = testing::makeBox(1, 1, 1);
    // Replace the top face (z = 1) by a fan around m, just inside edge (0,0,1)-(1,0,1).
    std::vector<std::array<int, 3>> tris;
    for (const auto& t : cage.triangles) {
      bool top = true;
      for (int k = 0; k < 3; ++k) top = top && cage.vertices[t[k]].z() == 1.0;
      if (!top) tris.push_back(t);
    }
    auto find = [&](const Vec3& p) {
      for (std::size_t i = 0; i < cage.vertices.size(); ++i)
        if ((cage.vertices[i] - p).norm() == 0.0) return static_cast<int>(i);
      return -1;
    };
    const int c00 = find({0, 0, 1}), c10 = find({1, 0, 1}), c11 = find({1, 1, 1}),
              c01 = find({0, 1, 1});
    cage.vertices.emplace_back(0.5, eps, 1.0);
    const int m = static_cast<int>(cage.vertices.size()) - 1;
    tris.push_back({m, c00, c10});  // the sliver
    tris.push_back({m, c10, c11});
    tris.push_back({m, c11, c01});
    tris.push_back({m, c01, c00});
    cage.triangles = tris;
    ASSERT_NO_THROW(validateClosedSurface(cage, "sliver"));
    const MeanValueCage mc(cage);
    for (const Vec3& x :
         {Vec3(0.5, 0.5, 0.5), Vec3(0.5, 0.0, 0.5), Vec3(0.5, 0.0, 1.0), Vec3(0.5, 0.5 * eps, 1.0),
          Vec3(0.5, 0.5 * eps, 1.0 + 1e-9), Vec3(0.5, -1e-9, 1.0 - 1e-9), Vec3(0.3, 1e-3, 0.999),
          Vec3(2.0, 0.0, 1.0), Vec3(0.5, 2.0, 1.0)}) {
      const Eval e = evalAt(mc, x);
      const auto [sumErr, linErr] = errors(cage, e.w, x);
      EXPECT_LT(sumErr, 1e-10) << eps << " " << x.transpose();
      EXPECT_LT(linErr, 1e-10) << eps << " " << x.transpose();
    }
  }
}

// Points 1e-6 … 1e-16 (relative) from cage vertices, edges and faces, along the face normal
// and in the face plane: always finite, partition of unity and linear precision.
TEST(Mvc, NearCageFuzzStaysFiniteAndAccurate) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> N(0.0, 1.0);
  for (const auto& c : generatedCages()) {
    const MeanValueCage mc(c.cage);
    MeanValueCage::Scratch s;
    std::vector<double> w(c.cage.vertices.size());
    const double L = mc.diagonal();
    double worst = 0.0;
    for (int it = 0; it < 1500; ++it) {
      const auto& t = c.cage.triangles[rng() % c.cage.triangles.size()];
      const Vec3 a = c.cage.vertices[t[0]], b = c.cage.vertices[t[1]], d = c.cage.vertices[t[2]];
      const Vec3 n = (b - a).cross(d - a).normalized();
      double r1 = U(rng), r2 = U(rng);
      if (r1 + r2 > 1.0) {
        r1 = 1.0 - r1;
        r2 = 1.0 - r2;
      }
      const Vec3 base = it % 3 == 0   ? a
                        : it % 3 == 1 ? Vec3(a + r1 * (b - a))
                                      : Vec3(a + r1 * (b - a) + r2 * (d - a));
      const double dist = std::pow(10.0, -6.0 - static_cast<double>(rng() % 11)) * L;
      Vec3 dir = test::drawVector<Vec3>([&] { return N(rng); });
      const int mode = static_cast<int>(rng() % 3);
      if (mode == 0)
        dir = n;
      else if (mode == 1)
        dir = -n;
      else
        dir -= dir.dot(n) * n;  // in the face plane
      const Vec3 x = base + dist * dir.normalized();
      ASSERT_TRUE(mc.weights(x, w.data(), s)) << c.name << " " << x.transpose();
      const auto [sumErr, linErr] = errors(c.cage, w, x);
      worst = std::max({worst, sumErr, linErr});
    }
    EXPECT_LT(worst, 1e-10) << c.name;
  }
}

TEST(Mvc, RealMeshesInsideTheirCages) {
  for (const auto& [meshName, cageName] :
       {std::pair<std::string, std::string>{"bunny.obj", "bunny_cage.obj"},
        {"suzanne.obj", "suzanne_cage.obj"}}) {
    const TriangleMesh mesh = readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/" + meshName);
    const TriangleMesh cage = readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/" + cageName);
    ASSERT_NO_THROW(validateClosedSurface(cage, cageName));
    const MeanValueCage mc(cage);
    MeanValueCage::Scratch s;
    std::vector<double> w(cage.vertices.size());
    double worstSum = 0.0, worstLin = 0.0;
    for (std::size_t i = 0; i < mesh.vertices.size(); i += 3) {
      ASSERT_TRUE(mc.weights(mesh.vertices[i], w.data(), s));
      const auto [sumErr, linErr] = errors(cage, w, mesh.vertices[i]);
      worstSum = std::max(worstSum, sumErr);
      worstLin = std::max(worstLin, linErr);
    }
    EXPECT_LT(worstSum, 1e-10) << meshName;
    EXPECT_LT(worstLin, 1e-10) << meshName;
  }
}

TEST(Mvc, StatelessKernelEqualsPreparedCage) {
  const TriangleMesh cage = testing::makeStar();
  const MeanValueCage mc(cage);
  const Vec3 x(0.1, 0.2, 0.3);
  std::vector<double> w(cage.vertices.size());
  ASSERT_TRUE(mvcWeights(x, cage, w.data()));
  const Eval e = evalAt(mc, x);
  for (std::size_t k = 0; k < w.size(); ++k) EXPECT_EQ(w[k], e.w[k]);
}

}  // namespace
}  // namespace sb::cage
