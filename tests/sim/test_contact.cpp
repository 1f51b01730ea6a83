// Body–body contact: the geometry kernels against independent recomputation, and the World's
// contact response against the guarantees of issue 5 (momentum, no tunnelling, resting, no NaN).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>

#include "../mesh/mesh_fixtures.h"
#include "scene_checks.h"
#include "sim/base/parallel.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "sim/world/contact/body_contact.h"
#include "sim/world/contact/box_tree.h"
#include "sim/world/contact/surface_grid.h"
#include "sim/world/mass_properties.h"
#include "test_util.h"
#include "tests/support/sanitizers.h"

namespace sb {
namespace {

using mesh::Triangle;
using mesh::TriangleFeature;
using test::pointTriangleDistance;
using test::windingNumber;

const std::string kBunnyCage = std::string(SOFTBODY_ASSET_DIR) + "/meshes/bunny_cage.obj";

// The bunny's cage scaled to about one metre, its centre of mass at `centre`.
struct Shape {
  std::vector<Vec3> points;
  std::vector<Triangle> triangles;
};

Shape bunnyCage(double scale, const Vec3& centre, const Mat3& rotation = Mat3::Identity()) {
  const mesh::TriangleMesh mesh = mesh::readMesh(kBunnyCage);
  Vec3 mean = Vec3::Zero();
  for (const Vec3& v : mesh.vertices) mean += v;
  mean /= double(mesh.vertices.size());
  Shape s;
  for (const Vec3& v : mesh.vertices) s.points.push_back(centre + rotation * (scale * (v - mean)));
  s.triangles = mesh.triangles;
  return s;
}

// A closed cube surface of edge `size` with n×n quads (2n² triangles) per face, outward.
Shape cubeSurface(double size, int n, const Vec3& centre) {
  Shape s;
  std::map<std::array<long, 3>, int> index;  // lattice point → vertex
  auto vertex = [&](const Eigen::Vector3i& q) {
    const std::array<long, 3> key{q.x(), q.y(), q.z()};
    const auto it = index.find(key);
    if (it != index.end()) return it->second;
    s.points.push_back(centre + size * (q.cast<double>() / n - Vec3::Constant(0.5)));
    return index[key] = int(s.points.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int a, int b) {
            Eigen::Vector3i q;
            q[axis] = side * n;
            q[u] = a;
            q[v] = b;
            return vertex(q);
          };
          const int c00 = at(i, j), c10 = at(i + 1, j), c11 = at(i + 1, j + 1), c01 = at(i, j + 1);
          // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
          if (side == 1) {
            s.triangles.push_back({c00, c10, c11});
            s.triangles.push_back({c00, c11, c01});
          } else {
            s.triangles.push_back({c00, c11, c10});
            s.triangles.push_back({c00, c01, c11});
          }
        }
    }
  return s;
}

BodyDef bodyFrom(const Shape& s, const std::string& name, Mode mode, double alpha) {
  BodyDef def;
  def.name = name;
  def.positions = s.points;
  def.surface = s.triangles;
  def.params.mode = mode;
  def.params.alpha = alpha;
  def.params.beta = 0.5;
  return def;
}

// Deepest particle of body a inside body b (metres), by winding number: independent of the
// contact code. 0 when none is inside.
double deepestInside(const World& w, BodyHandle a, BodyHandle b,
                     const std::vector<Triangle>& bTriangles) {
  const Eigen::MatrixX3d xa = test::toDouble(w.positions(a));
  const Eigen::MatrixX3d xb = test::toDouble(w.positions(b));
  double deepest = 0;
  for (int i = 0; i < xa.rows(); ++i) {
    const Vec3 p = xa.row(i).transpose();
    if (std::abs(windingNumber(p, xb, bTriangles)) <= 0.5) continue;
    double d = 1e30;
    for (const Triangle& t : bTriangles)
      d = std::min(d, pointTriangleDistance(p, xb.row(t[0]).transpose(), xb.row(t[1]).transpose(),
                                            xb.row(t[2]).transpose()));
    deepest = std::max(deepest, d);
  }
  return deepest;
}

// Gravity, 1/60 s in four sub-steps, a floor at y = 0 with friction 0.6; sleep as asked (off:
// the tests watch the motion itself, not a sleeping body).
World floorWorld(bool sleep = true) {
  WorldSettings settings;
  settings.timeStep = 1.0 / 60;
  settings.substeps = 4;
  settings.sleep = sleep;
  World world(settings);
  world.addCollider(Collider::plane(Vec3::UnitY(), 0.0, 0.6));
  return world;
}

// The shape moved up or down so that its lowest point is at `height` (m).
Shape onFloorAt(Shape s, double height) {
  double low = 1e30;
  for (const Vec3& p : s.points) low = std::min(low, p.y());
  for (Vec3& p : s.points) p.y() += height - low;
  return s;
}

Vec3 totalMomentum(const World& w) {
  Vec3 p = Vec3::Zero();
  for (BodyHandle b : w.bodies()) p += w.linearMomentum(b);
  return p;
}

// ---- geometry kernels ----------------------------------------------------------------------

TEST(SurfaceGeometry, ClosestPointMatchesExactDistance) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1, 1);
  auto rnd = [&] { return test::drawVector<Vec3f>([&] { return u(rng); }); };
  for (int trial = 0; trial < 20000; ++trial) {
    Vec3f a = rnd(), b = rnd(), c = rnd();
    if (trial % 5 == 0) c = a + 0.999f * (b - a) + 1e-3f * rnd();  // needle triangles
    const Vec3f p = 2.0f * rnd();
    const mesh::TrianglePoint<float> q = mesh::closestPointOnTriangle(p, a, b, c);
    ASSERT_GE(q.weights.minCoeff(), 0.0f);
    ASSERT_NEAR(q.weights.sum(), 1.0f, 1e-5f);
    const Vec3f closest = q.weights[0] * a + q.weights[1] * b + q.weights[2] * c;
    const double expected = pointTriangleDistance(p.cast<double>(), a.cast<double>(),
                                                  b.cast<double>(), c.cast<double>());
    ASSERT_NEAR((p - closest).norm(), expected, 1e-4) << "trial " << trial;
    // The feature names the weights that are zero.
    if (q.feature == TriangleFeature::Face) {
      ASSERT_GT(q.weights.minCoeff(), 0.0f);
    }
    if (q.feature == TriangleFeature::Vertex1) {
      ASSERT_EQ(q.weights[1], 1.0f);
    }
    if (q.feature == TriangleFeature::Edge1) {
      ASSERT_EQ(q.weights[0], 0.0f);
    }
  }
}

TEST(SurfaceGeometry, PseudoNormalSideAgreesWithWindingNumber) {
  const Shape s = bunnyCage(0.1, Vec3::Zero());
  const int n = int(s.points.size());
  Eigen::MatrixX3d xd(n, 3);
  Eigen::Matrix<float, Eigen::Dynamic, 3> xf(n, 3);
  for (int i = 0; i < n; ++i) {
    xd.row(i) = s.points[size_t(i)].transpose();
    xf.row(i) = s.points[size_t(i)].transpose().cast<float>();
  }
  const mesh::SurfaceTopology topology = mesh::buildSurfaceTopology(s.triangles, n);
  for (const auto& t : topology.neighbours) ASSERT_GE(std::min({t[0], t[1], t[2]}), 0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  std::normal_distribution<double> g(0.0, 0.01);
  int inside = 0, tested = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    Vec3 p = test::drawVector<Vec3>([&] { return u(rng); });
    if (trial % 2) {  // half of the points within about a centimetre of a random vertex
      p = s.points[size_t(trial) % s.points.size()] +
          test::drawVector<Vec3>([&] { return g(rng); });
    }
    const double w = windingNumber(p, xd, s.triangles);
    if (std::abs(std::abs(w) - 0.5) < 0.05) continue;  // on the surface: no defined side
    float best = 1e30f;
    int bestT = -1;
    mesh::TrianglePoint<float> bestQ{};
    Vec3f bestC = Vec3f::Zero();
    const Vec3f pf = p.cast<float>();
    for (size_t t = 0; t < s.triangles.size(); ++t) {
      const Vec3f a = xf.row(s.triangles[t][0]), b = xf.row(s.triangles[t][1]),
                  c = xf.row(s.triangles[t][2]);
      const mesh::TrianglePoint<float> q = mesh::closestPointOnTriangle(pf, a, b, c);
      const Vec3f cp = q.weights[0] * a + q.weights[1] * b + q.weights[2] * c;
      if ((pf - cp).squaredNorm() < best) {
        best = (pf - cp).squaredNorm();
        bestT = int(t);
        bestQ = q;
        bestC = cp;
      }
    }
    if (std::sqrt(best) < 1e-4f) continue;  // too close to the surface for float to decide
    const Vec3f side = mesh::pseudoNormal(s.triangles, topology, xf.col(0).data(), xf.col(1).data(),
                                          xf.col(2).data(), bestT, bestQ.feature);
    const bool pseudoInside = (pf - bestC).dot(side) < 0.0f;
    ASSERT_EQ(pseudoInside, std::abs(w) > 0.5) << "point " << p.transpose() << " w " << w;
    inside += pseudoInside;
    ++tested;
  }
  EXPECT_GT(inside, tested / 10);  // both sides were exercised
  EXPECT_LT(inside, tested - tested / 10);
}

// An L-shaped prism, z in [0, 1]: the union of [0, 2] × [0, 1] and [0, 1] × [0, 2] in (x, y),
// closed and outward. Its reflex edge runs along z through (1, 1), between the faces y = 1
// (x ≥ 1) and x = 1 (y ≥ 1).
// An obstacle as findContacts sees it: views of positions x and velocities v (#P × 3) and the
// surface of s, with its topology and grid; box, gap and margin left to the caller.
ContactGeometry obstacleView(const Eigen::Matrix<float, Eigen::Dynamic, 3>& x,
                             const Eigen::Matrix<float, Eigen::Dynamic, 3>& v, const Shape& s,
                             const mesh::SurfaceTopology& topology, const SurfaceGrid& grid) {
  ContactGeometry obstacle;
  for (int a = 0; a < 3; ++a) {
    obstacle.x[a] = x.col(a).data();
    obstacle.v[a] = v.col(a).data();
  }
  obstacle.count = int(x.rows());
  obstacle.triangles = &s.triangles;
  obstacle.topology = &topology;
  obstacle.grid = &grid;
  return obstacle;
}

Shape lShapedPrism() {
  const double outline[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};  // CCW
  Shape s;
  for (double z : {0.0, 1.0})
    for (const auto& q : outline) s.points.emplace_back(q[0], q[1], z);
  // Caps: the L as four triangles, CCW seen from +z (top), reversed at the bottom.
  const int cap[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}};
  for (const auto& t : cap) {
    s.triangles.push_back({t[0] + 6, t[1] + 6, t[2] + 6});
    s.triangles.push_back({t[0], t[2], t[1]});
  }
  // Sides: outline edge (i, i + 1), CCW, faces outward as (i, i + 1, top i + 1), (i, top i + 1,
  // top i).
  for (int i = 0; i < 6; ++i) {
    const int j = (i + 1) % 6;
    s.triangles.push_back({i, j, j + 6});
    s.triangles.push_back({i, j + 6, i + 6});
  }
  return s;
}

// A particle inside a concave crease (closest to the reflex edge, behind both faces that meet
// there) is held by the face it is deepest behind, when contacts can rest: the plane through
// the edge along the direction to it lets the particle slide along it and stay inside for good
// (the pile: 6.8 mm behind one face of a reflex edge for 7 s). Otherwise, and for the particle
// with creases off, the direction to the closest point. Checked against the prism's geometry,
// and its inside against the winding number.
TEST(BodyContact, ParticleInAConcaveCreaseIsHeldByTheFaceItIsDeepestBehind) {
  const Shape s = lShapedPrism();
  const int n = int(s.points.size());
  Eigen::Matrix<float, Eigen::Dynamic, 3> x(n, 3);
  for (int i = 0; i < n; ++i) x.row(i) = s.points[size_t(i)].transpose().cast<float>();
  const Eigen::Matrix<float, Eigen::Dynamic, 3> v = Eigen::MatrixX3f::Zero(n, 3);
  const mesh::SurfaceTopology topology = mesh::buildSurfaceTopology(s.triangles, n);
  for (const auto& t : topology.neighbours) ASSERT_GE(std::min({t[0], t[1], t[2]}), 0);
  SurfaceGrid grid;
  const Eigen::AlignedBox3f region(Vec3f::Constant(-1), Vec3f::Constant(3));
  grid.build(s.triangles, x.col(0).data(), x.col(1).data(), x.col(2).data(), 0.3f, 0.25f, region);
  ContactGeometry obstacle = obstacleView(x, v, s, topology, grid);
  obstacle.box = Eigen::AlignedBox3f(Vec3f::Zero(), Vec3f(2, 2, 1));
  obstacle.gap = 0.01f;
  obstacle.margin = 0.05f;

  struct Case {
    Vec3f p;
    Vec3f face;       // outward normal of the face it is deepest behind
    float faceDepth;  // how far behind that face's plane (m)
  };
  for (const Case& c : {Case{Vec3f(0.97f, 0.9f, 0.5f), Vec3f::UnitY(), 0.1f},
                        Case{Vec3f(0.9f, 0.97f, 0.5f), Vec3f::UnitX(), 0.1f},
                        Case{Vec3f(0.95f, 0.88f, 0.3f), Vec3f::UnitY(), 0.12f}}) {
    ASSERT_GT(std::abs(windingNumber(c.p.cast<double>(), x.cast<double>(), s.triangles)), 0.5)
        << "inside the prism: " << c.p.transpose();
    std::vector<float> px = {c.p.x()}, py = {c.p.y()}, pz = {c.p.z()}, pv = {0.0f};
    ContactGeometry probe;
    probe.x[0] = px.data();
    probe.x[1] = py.data();
    probe.x[2] = pz.data();
    probe.v[0] = probe.v[1] = probe.v[2] = pv.data();
    probe.count = 1;
    probe.box = Eigen::AlignedBox3f(c.p, c.p);
    // The closest point is on the reflex edge, (1, 1, z).
    const Vec3f edge(1, 1, c.p.z());
    const Vec3f toEdge = edge - c.p;
    for (bool creases : {true, false}) {
      std::vector<Contact> out;
      findContacts(probe, obstacle, 1.0f / 240, false, creases, Vec3f::Zero(), out);
      ASSERT_EQ(out.size(), 1u) << c.p.transpose();
      const Contact& k = out[0];
      if (creases) {
        EXPECT_LT((k.normal - c.face).norm(), 1e-5f) << c.p.transpose();
        EXPECT_NEAR(k.distance, -c.faceDepth, 1e-5f) << c.p.transpose();
      } else {
        EXPECT_LT((k.normal - toEdge.normalized()).norm(), 1e-5f) << c.p.transpose();
        EXPECT_NEAR(k.distance, -toEdge.norm(), 1e-5f) << c.p.transpose();
      }
    }
  }
}

TEST(SurfaceGrid, CellHoldsEveryTriangleWithinReach) {
  const Shape s = bunnyCage(0.1, Vec3(3, 1, -2));
  const int n = int(s.points.size());
  Eigen::Matrix<float, Eigen::Dynamic, 3> x(n, 3);
  for (int i = 0; i < n; ++i) x.row(i) = s.points[size_t(i)].transpose().cast<float>();
  for (float reach : {0.01f, 0.07f, 0.3f}) {
    SurfaceGrid grid;
    Eigen::AlignedBox3f region(Vec3f(2.5f, 0.5f, -2.5f), Vec3f(3.2f, 1.2f, -1.6f));
    grid.build(s.triangles, x.col(0).data(), x.col(1).data(), x.col(2).data(), reach, 0.1f, region);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    for (int trial = 0; trial < 2000; ++trial) {
      const Vec3f p = region.min() +
                      test::drawVector<Vec3f>([&] { return u(rng); }).cwiseProduct(region.sizes());
      const SurfaceGrid::Range r = grid.candidates(p);
      const std::vector<int> got(r.begin, r.end);
      ASSERT_TRUE(std::is_sorted(got.begin(), got.end()));
      for (size_t t = 0; t < s.triangles.size(); ++t) {
        const double d = pointTriangleDistance(
            p.cast<double>(), s.points[size_t(s.triangles[t][0])],
            s.points[size_t(s.triangles[t][1])], s.points[size_t(s.triangles[t][2])]);
        if (d <= reach * 0.999) {
          ASSERT_TRUE(std::binary_search(got.begin(), got.end(), int(t)))
              << "triangle " << t << " at " << d << " m, reach " << reach;
        }
      }
    }
  }
}

// The bunny's cage at 0.1 m near (3, 1, −2), gridded with a reach of 2 cm, cells of 5 cm and a
// look-ahead of 3 cm over a region around it.
struct GriddedBunny {
  static constexpr float reach = 0.02f, lookAhead = 0.03f;
  Shape s = bunnyCage(0.1, Vec3(3, 1, -2));
  Eigen::AlignedBox3f region{Vec3f(2.5f, 0.5f, -2.5f), Vec3f(3.2f, 1.2f, -1.6f)};
  SurfaceGrid grid;
  GriddedBunny() {
    const int n = int(s.points.size());
    Eigen::Matrix<float, Eigen::Dynamic, 3> x(n, 3);
    for (int i = 0; i < n; ++i) x.row(i) = s.points[size_t(i)].transpose().cast<float>();
    grid.build(s.triangles, x.col(0).data(), x.col(1).data(), x.col(2).data(), reach, 0.05f, region,
               false, lookAhead);
  }
};

// With a look-ahead the cells hold every triangle within reach + lookAhead, and a look-up visits
// every triangle within reach + extra of the point, for extra below the look-ahead (one cell)
// and above it (several), for points inside the grid's bounds and outside them. (The points are
// at least the largest extra inside the region, as the Contacts phase grows its regions by how
// far particles look.)
TEST(SurfaceGrid, LookAheadKeepsEveryTriangleWithinReachInSight) {
  const GriddedBunny g;
  const Shape& s = g.s;
  const SurfaceGrid& grid = g.grid;
  const Eigen::AlignedBox3f& region = g.region;
  const float reach = GriddedBunny::reach;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  const Eigen::AlignedBox3f inner(region.min().array() + 0.07f, region.max().array() - 0.07f);
  long singleCell = 0, checked = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const Vec3f p =
        inner.min() + test::drawVector<Vec3f>([&] { return u(rng); }).cwiseProduct(inner.sizes());
    const SurfaceGrid::Range r = grid.candidates(p);
    const std::vector<int> cell(r.begin, r.end);
    for (float extra : {0.0f, 0.01f, 0.03f, 0.07f}) {
      std::vector<char> seen(s.triangles.size(), 0);
      grid.forEachNear(
          p, extra, [] { return std::numeric_limits<float>::infinity(); },
          [&](int t) { seen[size_t(t)] = 1; });
      for (size_t t = 0; t < s.triangles.size(); ++t) {
        const double d = pointTriangleDistance(
            p.cast<double>(), s.points[size_t(s.triangles[t][0])],
            s.points[size_t(s.triangles[t][1])], s.points[size_t(s.triangles[t][2])]);
        if (d > (reach + extra) * 0.999) continue;
        ASSERT_TRUE(seen[size_t(t)]) << "triangle " << t << " at " << d << " m, extra " << extra;
        ++checked;
        if (extra == 0.0f && grid.bounds().contains(p)) {
          ASSERT_TRUE(std::binary_search(cell.begin(), cell.end(), int(t)));
          ++singleCell;
        }
      }
    }
  }
  EXPECT_GT(checked, 2000);  // the points came near the surface often enough to mean something
  EXPECT_GT(singleCell, 200);
}

// A look-up's clearance bounds the distance from the point to every triangle of the surface
// (ProbeClearance skips look-ups by it): checked against the exact distance to each triangle, for
// points inside and outside the grid's bounds, at every extra (one cell, several cells), and it
// must mean something: for points away from the surface it exceeds the reach.
TEST(SurfaceGrid, ClearanceNeverExceedsTheDistanceToAnyTriangle) {
  const GriddedBunny g;
  const Shape& s = g.s;
  const SurfaceGrid& grid = g.grid;
  const Eigen::AlignedBox3f& region = g.region;
  const float reach = GriddedBunny::reach, lookAhead = GriddedBunny::lookAhead;
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0, 1);
  // Around the region, so that some points are outside the grid's bounds.
  const Eigen::AlignedBox3f around(region.min().array() - 0.1f, region.max().array() + 0.1f);
  long beyondReach = 0, outsideBounds = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const Vec3f p =
        around.min() + test::drawVector<Vec3f>([&] { return u(rng); }).cwiseProduct(around.sizes());
    double nearest = std::numeric_limits<double>::infinity();
    for (const Triangle& t : s.triangles)
      nearest =
          std::min(nearest, pointTriangleDistance(p.cast<double>(), s.points[size_t(t[0])],
                                                  s.points[size_t(t[1])], s.points[size_t(t[2])]));
    for (float extra : {0.0f, 0.01f, 0.03f, 0.07f}) {
      float clearance2 = -1;
      grid.forEachNear(
          p, extra, [] { return std::numeric_limits<float>::infinity(); }, [](int) {}, &clearance2);
      ASSERT_GE(clearance2, 0.0f);
      ASSERT_LE(std::sqrt(double(clearance2)), nearest * (1 + 1e-6) + 1e-7)
          << p.transpose() << " extra " << extra;
      if (std::sqrt(clearance2) > reach + lookAhead * 0.5f) ++beyondReach;
      if (!grid.bounds().contains(p) && clearance2 > 0.0f) ++outsideBounds;
    }
  }
  EXPECT_GT(beyondReach, 1000);
  EXPECT_GT(outsideBounds, 200);
}

// ProbeClearance only skips look-ups that would find nothing: a probe cloud around a moving bunny
// cage, over 48 sub-steps with a deep search every fourth, gives exactly the contacts (and the
// deep flag) of the same search without it, while making far fewer point–triangle tests. The
// cloud has particles near the surface, far from it, and deep inside (found by the deep search);
// some of it jumps now and then, and the surface drifts as the Contacts phase lets a kept grid.
TEST(BodyContact, KnownClearancesSkipLookUpsWithoutChangingTheContacts) {
  const Shape s = bunnyCage(1.0, Vec3(0, 0.5, 0));
  const int n = int(s.points.size());
  Eigen::Matrix<float, Eigen::Dynamic, 3> x(n, 3);
  for (int i = 0; i < n; ++i) x.row(i) = s.points[size_t(i)].transpose().cast<float>();
  const Eigen::Matrix<float, Eigen::Dynamic, 3> gridX = x;
  const Eigen::MatrixX3f v = Eigen::MatrixX3f::Zero(n, 3);
  const mesh::SurfaceTopology topology = mesh::buildSurfaceTopology(s.triangles, n);
  double spacing = 0;
  for (const Triangle& t : s.triangles)
    spacing += (s.points[size_t(t[0])] - s.points[size_t(t[1])]).norm();
  spacing /= double(s.triangles.size());
  const float h = 1.0f / 240;
  Eigen::AlignedBox3f box;
  for (int i = 0; i < n; ++i) box.extend(Vec3f(x.row(i).transpose()));
  // As the Contacts phase builds it: reach gap + margin, cells of a spacing, a quarter spacing
  // of look-ahead, over where the probes are.
  const float gap = 0.01f * float(spacing), margin = 0.25f * float(spacing);
  const Eigen::AlignedBox3f region(box.min().array() - 0.3f, box.max().array() + 0.3f);
  SurfaceGrid grid;
  grid.build(s.triangles, x.col(0).data(), x.col(1).data(), x.col(2).data(), gap + margin,
             float(spacing), region, false, 0.25f * float(spacing));

  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  const int m = 1200;
  Eigen::MatrixX3f px(m, 3), pv = Eigen::MatrixX3f::Zero(m, 3);
  const Eigen::AlignedBox3f cloud(box.min().array() - 0.2f, box.max().array() + 0.2f);
  for (int i = 0; i < m; ++i)
    px.row(i) =
        (cloud.min() + test::drawVector<Vec3f>([&] { return u(rng); }).cwiseProduct(cloud.sizes()))
            .transpose();
  ProbeClearance clearance;
  long testsWith = 0, testsWithout = 0, contacts = 0, deepFound = 0;
  for (int step = 0; step < 48; ++step) {
    // The probe: each particle moves a little, and a few jump by up to a spacing.
    for (int i = 0; i < m; ++i) {
      const Vec3f dv = test::drawVector<Vec3f>([&] { return u(rng) - 0.5f; });
      pv.row(i) = (0.4f * dv).transpose();
      const float jump = u(rng) < 0.02f ? float(spacing) : 0.0f;
      px.row(i) += (h * pv.row(i).transpose() + jump * dv).transpose();
    }
    // The surface: turned and shifted a little about where the grid was built (its drift stays
    // below the quarter spacing at which the Contacts phase would rebuild the grid).
    const float angle = 0.02f * std::sin(0.3f * float(step));
    const Eigen::Matrix3f turn = Eigen::AngleAxisf(angle, Vec3f::UnitY()).toRotationMatrix();
    const Vec3f centre = box.center();
    for (int i = 0; i < n; ++i)
      x.row(i) = (centre + turn * (Vec3f(gridX.row(i).transpose()) - centre) +
                  Vec3f(0.005f * std::cos(0.5f * float(step)), 0, 0))
                     .transpose();
    ContactGeometry obstacle = obstacleView(x, v, s, topology, grid);
    obstacle.gridDrift = std::sqrt((x - gridX).rowwise().squaredNorm().maxCoeff());
    ASSERT_LT(obstacle.gridDrift, 0.25f * spacing);
    obstacle.box.setEmpty();
    for (int i = 0; i < n; ++i) obstacle.box.extend(Vec3f(x.row(i).transpose()));
    obstacle.gap = gap;
    obstacle.margin = margin;
    ContactGeometry probe;
    for (int a = 0; a < 3; ++a) {
      probe.x[a] = px.col(a).data();
      probe.v[a] = pv.col(a).data();
    }
    probe.count = m;
    probe.box.setEmpty();
    for (int i = 0; i < m; ++i) probe.box.extend(Vec3f(px.row(i).transpose()));
    probe.maxRelativeSpeed = pv.rowwise().norm().maxCoeff();
    const bool deep = step % 4 == 3;
    std::vector<Contact> with, without;
    const bool deepWith =
        findContacts(probe, obstacle, h, deep, true, Vec3f::UnitY(), with, &testsWith, &clearance);
    const bool deepWithout =
        findContacts(probe, obstacle, h, deep, true, Vec3f::UnitY(), without, &testsWithout);
    ASSERT_EQ(deepWith, deepWithout) << "sub-step " << step;
    ASSERT_EQ(with.size(), without.size()) << "sub-step " << step;
    for (size_t k = 0; k < with.size(); ++k) {
      const Contact &a = with[k], &b = without[k];
      ASSERT_EQ(a.particle, b.particle) << "sub-step " << step;
      ASSERT_EQ(a.triangle, b.triangle);
      ASSERT_EQ(a.weights, b.weights);
      ASSERT_EQ(a.normal, b.normal);
      ASSERT_EQ(a.distance, b.distance);
    }
    contacts += long(with.size());
    deepFound += deepWith ? 1 : 0;
  }
  EXPECT_GT(contacts, 48 * 30);  // particles near the surface at every sub-step
  EXPECT_GT(deepFound, 6);       // and deep ones, found by the deep searches
  // Most look-ups are skipped once the clearances are known.
  EXPECT_LT(double(testsWith), 0.75 * double(testsWithout)) << testsWith << " " << testsWithout;
}

// The look-ups skip a triangle when its lower bound exceeds the distance to beat, so the bound
// must never exceed the squared distance the exact test computes in float (or a skipped triangle
// could have been the closest): checked for every triangle of a tilted bunny cage, near the origin
// and 60 m from it (where float rounding of a plane distance is largest), and for a collapsed
// triangle. The plane must also earn its place: for many points it is tighter than the box.
TEST(SurfaceGrid, DistanceLowerBoundNeverExceedsTheExactTest) {
  const Mat3 tilt = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (const Vec3& centre : {Vec3(0.1, 0.2, -0.1), Vec3(60, 3, -45)}) {
    Shape s = bunnyCage(0.1, centre, tilt);
    // A collapsed triangle: three points on a line (no plane).
    const int base = int(s.points.size());
    for (double t : {0.0, 0.3, 1.0}) s.points.push_back(centre + t * Vec3(0.05, 0.02, 0.01));
    s.triangles.push_back({base, base + 1, base + 2});
    const int n = int(s.points.size());
    Eigen::Matrix<float, Eigen::Dynamic, 3> x(n, 3);
    for (int i = 0; i < n; ++i) x.row(i) = s.points[size_t(i)].transpose().cast<float>();
    const Eigen::AlignedBox3f region(centre.cast<float>().array() - 0.15f,
                                     centre.cast<float>().array() + 0.15f);
    SurfaceGrid grid;
    grid.build(s.triangles, x.col(0).data(), x.col(1).data(), x.col(2).data(), 0.02f, 0.02f,
               region);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    long tighter = 0, pairs = 0;
    for (int trial = 0; trial < 1500; ++trial) {
      const Vec3f p = region.min() +
                      test::drawVector<Vec3f>([&] { return u(rng); }).cwiseProduct(region.sizes());
      const Eigen::Array4f p4 = SurfaceGrid::lanes(p);
      for (size_t t = 0; t < s.triangles.size(); ++t) {
        const Vec3f a = x.row(s.triangles[t][0]), b = x.row(s.triangles[t][1]),
                    c = x.row(s.triangles[t][2]);
        const mesh::TrianglePoint<float> q = mesh::closestPointOnTriangle(p, a, b, c);
        const float exact =
            (p - (q.weights[0] * a + q.weights[1] * b + q.weights[2] * c)).squaredNorm();
        const float bound = grid.distanceLowerBoundSquared(int(t), p4);
        Eigen::AlignedBox3f box;
        for (const Vec3f& v : {a, b, c}) box.extend(v);
        const float boxOnly = box.squaredExteriorDistance(p);
        // The box part may exceed the float exact test by rounding (as it always could: the
        // float closest point is not exactly on the triangle); the plane part must not.
        if (bound > boxOnly) {
          ASSERT_LE(bound, exact) << "triangle " << t << " point " << p.transpose();
        }
        tighter += bound > 1.5f * boxOnly + 1e-8f;
        ++pairs;
      }
    }
    EXPECT_GT(tighter, pairs / 25) << "the plane rarely beats the box";
  }
}

// The box hierarchy's nearest-first search, with the bound lowered to each closer box found,
// finds the box a pass over all boxes finds (nearest, ties to the lower index), visits every box
// that the final bound admits, and on a bunny's triangle boxes visits a small part of them.
// Returns the mean number of boxes visited per search.
double checkNearestSearch(const BoxTree& tree, const std::vector<Eigen::AlignedBox3f>& boxes,
                          const Vec3f& centre, unsigned seed) {
  auto distance2 = [&](int i, const Vec3f& p) {
    const Vec3f below = (boxes[size_t(i)].min() - p).cwiseMax(0.0f),
                above = (p - boxes[size_t(i)].max()).cwiseMax(0.0f);
    return (below + above).squaredNorm();
  };
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  long long visits = 0;
  const int trials = 3000;
  for (int trial = 0; trial < trials; ++trial) {
    const Vec3f p = centre + 0.8f * test::drawVector<Vec3f>([&] { return u(rng); });
    int brute = -1;
    float bruteD = std::numeric_limits<float>::infinity();
    for (int i = 0; i < int(boxes.size()); ++i)
      if (distance2(i, p) < bruteD) bruteD = distance2(i, p), brute = i;
    int best = -1;
    float bound = std::numeric_limits<float>::infinity();
    std::vector<char> seen(boxes.size(), 0);
    tree.visitNear(
        p, [&] { return bound; },
        [&](int i) {
          ++visits;
          seen[size_t(i)] = 1;
          const float d = distance2(i, p);
          if (d < bound || (d == bound && i < best)) bound = d, best = i;
        });
    EXPECT_EQ(best, brute) << "point " << p.transpose();
    for (int i = 0; i < int(boxes.size()); ++i)
      if (distance2(i, p) <= bound) {
        EXPECT_TRUE(seen[size_t(i)]) << "box " << i;
      }
    if (testing::Test::HasFailure()) break;
  }
  return double(visits) / trials;
}

std::vector<Eigen::AlignedBox3f> triangleBoxes(const Shape& s) {
  std::vector<Eigen::AlignedBox3f> boxes;
  for (const mesh::Triangle& t : s.triangles) {
    Eigen::AlignedBox3f b;
    for (int i : t) b.extend(s.points[size_t(i)].cast<float>());
    boxes.push_back(b);
  }
  // Duplicates: ties must still go to the lower index.
  boxes.push_back(boxes[3]);
  boxes.push_back(boxes[0]);
  return boxes;
}

TEST(BoxTree, NearestSearchMatchesAPassOverAllBoxes) {
  const Shape s = bunnyCage(0.1, Vec3(3, 1, -2));
  std::vector<Eigen::AlignedBox3f> boxes = triangleBoxes(s);
  BoxTree tree;
  tree.build(boxes);
  ASSERT_FALSE(tree.empty());
  EXPECT_LT(checkNearestSearch(tree, boxes, Vec3f(3, 1, -2), 5), 0.25 * double(boxes.size()));
  // A box with a non-finite centre leaves the tree empty (the caller scans all boxes).
  boxes[1].max().x() = std::numeric_limits<float>::infinity();
  tree.build(boxes);
  EXPECT_TRUE(tree.empty());
}

// A tree refit to its boxes after the surface moved (turned by 90°, stretched, sheared and
// moved, as a deforming body's triangles do) searches exactly as one built anew, and still looks
// at a small part of the boxes; refit with a non-finite box it is empty, and refit again once
// the boxes are finite it is whole.
TEST(BoxTree, RefitAfterTheSurfaceMovedSearchesAsABuild) {
  Shape s = bunnyCage(0.1, Vec3(3, 1, -2));
  BoxTree tree;
  tree.build(triangleBoxes(s));
  Mat3 deform = Eigen::AngleAxisd(0.5 * M_PI, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  deform = deform * Eigen::Vector3d(1.4, 0.7, 1.1).asDiagonal();
  deform(0, 2) += 0.3;
  const Vec3 moved(-1, 2, 0.5);
  for (Vec3& p : s.points) p = deform * (p - Vec3(3, 1, -2)) + moved;
  std::vector<Eigen::AlignedBox3f> boxes = triangleBoxes(s);
  tree.refit(boxes);
  ASSERT_FALSE(tree.empty());
  BoxTree fresh;
  fresh.build(boxes);
  const double refitVisits = checkNearestSearch(tree, boxes, moved.cast<float>(), 9);
  const double freshVisits = checkNearestSearch(fresh, boxes, moved.cast<float>(), 9);
  EXPECT_LT(refitVisits, 0.25 * double(boxes.size()));
  std::printf("boxes visited per search: refit %.1f, built anew %.1f (of %zu)\n", refitVisits,
              freshVisits, boxes.size());
  const Eigen::AlignedBox3f kept = boxes[1];
  boxes[1].max().x() = std::numeric_limits<float>::quiet_NaN();
  tree.refit(boxes);
  EXPECT_TRUE(tree.empty());
  boxes[1] = kept;
  tree.refit(boxes);
  ASSERT_FALSE(tree.empty());
  checkNearestSearch(tree, boxes, moved.cast<float>(), 11);
}

// Closed forms: eight 1 kg masses at the corners (±1, ±1, ±1) + c have their centre at c and
// inertia 16·I (each contributes r² − rᵢ² = 2 per axis); two 1 kg masses at x = c ± 1 are
// collinear: inertia diag(0, 2, 2), and the pseudo-inverse inverts it where it can.
TEST(MassProperties, ClosedForms) {
  const Vec3 c(0.5, -2, 3);
  std::vector<float> x, y, z, m;
  for (int k = 0; k < 8; ++k) {
    x.push_back(float(c.x() + (k & 1 ? 1 : -1)));
    y.push_back(float(c.y() + (k & 2 ? 1 : -1)));
    z.push_back(float(c.z() + (k & 4 ? 1 : -1)));
    m.push_back(1.0f);
  }
  const MassProperties cube =
      massProperties(PointColumns{{x.data(), y.data(), z.data()}}, m.data(), 8);
  EXPECT_DOUBLE_EQ(cube.mass, 8.0);
  EXPECT_LT((cube.centre - c).norm(), 1e-12);
  EXPECT_LT((cube.inertia - 16.0 * Mat3::Identity()).norm(), 1e-10);
  EXPECT_LT((cube.inverseInertia - Mat3::Identity() / 16.0).norm(), 1e-12);

  const float lx[2] = {float(c.x() - 1), float(c.x() + 1)};
  const float ly[2] = {float(c.y()), float(c.y())}, lz[2] = {float(c.z()), float(c.z())};
  const float lm[2] = {1.0f, 1.0f};
  const MassProperties line = massProperties(PointColumns{{lx, ly, lz}}, lm, 2);
  EXPECT_LT((line.inertia - Vec3(0, 2, 2).asDiagonal().toDenseMatrix()).norm(), 1e-12);
  EXPECT_LT((line.inverseInertia - Vec3(0, 0.5, 0.5).asDiagonal().toDenseMatrix()).norm(), 1e-9);
}

// ---- the World's contact response ----------------------------------------------------------

// Two bodies fly into each other: no gravity, no colliders, so total momentum must stay what it
// was; with friction 0 and with friction (tangential impulses are equal and opposite too).
TEST(Contact, TwoBodyCollisionConservesMomentumAndSeparates) {
  for (double friction : {0.0, 0.8}) {
    for (Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic}) {
      WorldSettings settings = test::noGravity(1.0 / 60, 4);
      settings.contactFriction = friction;
      World world(settings);
      const Shape a = bunnyCage(0.1, Vec3(-0.7, 0, 0));
      std::mt19937 rng(3);
      const Shape b = bunnyCage(0.1, Vec3(0.7, 0.15, 0.1), test::randomRotation(rng));
      BodyDef da = bodyFrom(a, "a", mode, 0.4), db = bodyFrom(b, "b", Mode::Linear, 0.3);
      da.velocity = Vec3(3, 0, 0);
      db.velocity = Vec3(-2, 0.5, 0);
      da.totalMass = 2.0;
      db.clusters.kind = ClusterDef::Kind::Grid;
      db.clusters.cellSize = 0.4;
      db.clusters.overlap = 0.1;
      const BodyHandle ha = world.addBody(da), hb = world.addBody(db);
      const Vec3 before = totalMomentum(world);
      const Vec3 bBefore = world.linearMomentum(hb);
      int contacts = 0;
      double deepest = 0;
      for (int step = 0; step < 90; ++step) {
        world.step();
        contacts += world.lastContactCount();
        deepest = std::max(deepest, deepestInside(world, ha, hb, b.triangles));
        deepest = std::max(deepest, deepestInside(world, hb, ha, a.triangles));
        ASSERT_TRUE(world.takeEvents().empty());
      }
      const Vec3 after = totalMomentum(world);
      SCOPED_TRACE(std::string(modeName(mode)) + " friction " + std::to_string(friction));
      EXPECT_GT(contacts, 0);
      // Float round-off only: a one-sided or wrongly weighted impulse changes it by ~1 kg·m/s.
      EXPECT_LT((after - before).norm(), 1e-4 * before.norm()) << (after - before).transpose();
      // They met instead of passing through: momentum was exchanged, a is still on its side.
      EXPECT_GT((world.linearMomentum(ha) - Vec3(6, 0, 0)).norm(), 1.0);  // it was pushed
      // a is still on its side of the contact: along the impulse b received, b is ahead of a.
      // (Not necessarily along x: b is offset and turned, so they meet at a slant; with
      // restitution 0 and no friction they slide off each other, a below b, and a's centre may
      // then overtake b's in x without the surfaces ever overlapping.)
      const Vec3 impulse = world.linearMomentum(hb) - bBefore;
      EXPECT_GT((world.centreOfMass(hb) - world.centreOfMass(ha)).dot(impulse), 0.0);
      // Penetration stays shallow during the whole impact (mean edge ≈ 0.14 m).
      EXPECT_LT(deepest, 0.1 * 0.14);
    }
  }
}

// A fast small body hits a larger one: per sub-step it moves about one particle spacing, more
// than a static thickness-based test would catch.
TEST(Contact, FastBodyDoesNotTunnel) {
  World world(test::noGravity(1.0 / 60, 4));
  const Shape big = bunnyCage(0.12, Vec3::Zero());
  const Shape small = bunnyCage(0.04, Vec3(-2.0, 0.05, 0));
  BodyDef dBig = bodyFrom(big, "big", Mode::Linear, 0.5);
  BodyDef dSmall = bodyFrom(small, "small", Mode::Rigid, 1.0);
  dBig.totalMass = 5;
  dSmall.velocity = Vec3(30, 0, 0);  // 0.125 m per sub-step
  // Restitution 0.5: the 1 kg body comes back at (1 − 0.5·5)/6 · 30 = −7.5 m/s, the big soft one
  // (α 0.5) answering the impact as a whole (soft_impact.h). (Before, a soft body stopped the
  // impact particle by particle and the 1 kg body kept +0.4 m/s, an effective e of 0.18.)
  dBig.params.restitution = dSmall.params.restitution = 0.5;
  const BodyHandle hb = world.addBody(dBig), hs = world.addBody(dSmall);
  double deepest = 0;
  for (int step = 0; step < 30; ++step) {
    world.step();
    deepest = std::max(deepest, deepestInside(world, hs, hb, big.triangles));
  }
  EXPECT_LT(world.centreOfMass(hs).x(), world.centreOfMass(hb).x());  // stayed on its side
  // The bunnies meet off-centre, at a slant, so the bounce is not all along x: −6.54 m/s.
  EXPECT_NEAR(world.linearMomentum(hs).x() / world.mass(hs), -7.5, 0.15 * 7.5);
  EXPECT_LT(deepest, 0.05 * mesh::meanEdgeLength(small.triangles, small.points) + 0.02);
}

// Soft bodies (α < 1) of every mode dropped from 1 m rise after the first impact to e² of their
// fall (the bracket, ± 0.05): their impacts are events of the pair as a whole
// (soft_impact.h). Before, the bounce acted on the touching particles and what came back was
// the deformation the impact stored: a linear α 0.3 box rebounded 0.14 for e = 0 and 0.11 for
// e = 0.9. (Measured now: 0.00–0.02, 0.23–0.25, 0.77–0.81.) Softer bodies (α ≤ 0.1) rise
// e²·H less their compression depth (5–9 cm here), since the rebound starts from there.
TEST(Contact, SoftBodiesReboundESquaredOfTheirFall) {
  const double fall = 1.0;
  for (Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic})
    for (double alpha : {0.3, 0.9})
      for (double e : {0.0, 0.5, 0.9}) {
        World world = floorWorld(/*sleep=*/false);
        BodyDef def =
            bodyFrom(onFloorAt(cubeSurface(0.4, 3, Vec3::Zero()), fall), "box", mode, alpha);
        def.params.beta = 0.3;
        def.params.restitution = e;
        const BodyHandle b = world.addBody(def);
        const double rest = world.centreOfMass(b).y() - fall;
        double apex = -1, before = 0;
        bool landed = false, rose = false;
        for (int step = 0; step < 150; ++step) {  // 2.5 s: the e = 0.9 flight ends by 1.7 s
          world.step();
          const double vy = world.linearMomentum(b).y() / world.mass(b);
          landed = landed || vy > before;  // free fall only ever speeds the body up downward
          before = vy;
          if (landed) apex = std::max(apex, world.centreOfMass(b).y() - rest);
          rose = rose || (landed && vy > 0.0);
          if (rose && vy < -0.5) break;  // falling again
        }
        SCOPED_TRACE(std::string(modeName(mode)) + " alpha " + std::to_string(alpha) + " e " +
                     std::to_string(e));
        ASSERT_TRUE(landed);
        EXPECT_NEAR(apex / fall, e * e, 0.05);
      }
}

// Two soft bodies meeting head on in free space part with e times their approach speed, and
// momentum is exchanged exactly: the pair's restitution is one impulse on both centres, equal
// and opposite. The bracket is the drop's, on the energy of the relative motion: e² ± 0.05.
// (Measured: parting 0.80 / 3.0000 / 5.4001 m/s for e = 0 / 0.5 / 0.9 at 6 m/s; for e = 0 what
// the compressed bodies still store when the hold ends springs back, 1.8 % of the energy.)
TEST(Contact, SoftBodiesPartWithETimesTheirApproach) {
  for (double e : {0.0, 0.5, 0.9}) {
    WorldSettings settings = test::noGravity(1.0 / 60, 4);
    settings.contactFriction = 0.0;
    World world(settings);
    BodyDef da = bodyFrom(cubeSurface(0.4, 3, Vec3(-0.5, 0, 0)), "a", Mode::Linear, 0.5);
    BodyDef db = bodyFrom(cubeSurface(0.4, 3, Vec3(0.5, 0, 0)), "b", Mode::Quadratic, 0.4);
    da.totalMass = 1;
    db.totalMass = 3;
    da.velocity = Vec3(4, 0, 0);
    db.velocity = Vec3(-2, 0, 0);
    da.params.restitution = e;
    const BodyHandle ha = world.addBody(da), hb = world.addBody(db);
    const Vec3 before = totalMomentum(world);
    for (int step = 0; step < 90; ++step) world.step();
    SCOPED_TRACE("e " + std::to_string(e));
    const Vec3 after = totalMomentum(world);
    // Issue 11's bound for momentum per collision: 1e-5 of Σ m|v| (1·4 + 3·2 kg·m/s).
    EXPECT_LT((after - before).norm(), 1e-5 * 10.0) << (after - before).transpose();
    const double parting = (world.linearMomentum(hb).x() / world.mass(hb) -
                            world.linearMomentum(ha).x() / world.mass(ha));
    EXPECT_GT(parting, 0.0);
    EXPECT_NEAR(parting * parting / 36.0, e * e, 0.05);
    std::printf("e %.1f parting %.4f m/s (approach 6), momentum change %.3g\n", e, parting,
                (after - before).norm());
  }
}

// A cube dropped on another on the floor comes to rest on top of it, still. Sleep is off: the
// contacts themselves must hold the stack still (asleep, nothing would move and no contact
// would be solved).
TEST(Contact, StackSettlesWithoutJitter) {
  World world = floorWorld(/*sleep=*/false);
  const Shape bottom = cubeSurface(1.0, 4, Vec3(0, 0.5, 0));
  const Shape top = cubeSurface(0.6, 4, Vec3(0.1, 1.6, 0.05));
  for (Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic}) {
    World w = world;
    BodyDef db = bodyFrom(bottom, "bottom", Mode::Quadratic, 0.3);
    BodyDef dt = bodyFrom(top, "top", mode, mode == Mode::Rigid ? 1.0 : 0.3);
    db.totalMass = 2;
    // Damping lets the two soft bodies' own vibration die out within the test's 3 s; with less
    // they ring for longer (a property of the bodies, not of the contact).
    db.params.damping = dt.params.damping = 0.1;
    const BodyHandle hb = w.addBody(db), ht = w.addBody(dt);
    for (int step = 0; step < 240; ++step) w.step();
    const Eigen::MatrixX3d x0 = test::toDouble(w.positions(ht));
    w.step();
    const Eigen::MatrixX3d x1 = test::toDouble(w.positions(ht));
    SCOPED_TRACE(modeName(mode));
    EXPECT_LT((x1 - x0).rowwise().norm().maxCoeff(), 1e-3 * 0.6 * std::sqrt(3.0));
    const double spacing = mesh::meanEdgeLength(top.triangles, top.points);
    EXPECT_LT(deepestInside(w, ht, hb, bottom.triangles), 0.05 * spacing);
    EXPECT_LT(deepestInside(w, hb, ht, top.triangles), 0.05 * spacing);
    // Resting on the bottom cube (top face at 1 m), not on the floor beside it.
    EXPECT_GT(x1.col(1).minCoeff(), 0.9);
    EXPECT_GT(w.lastContactCount(), 0);
  }
}

// Two 0.5 m cubes (4×4 quads a face) start overlapping by 60 %, 90 % and 100 % (coincident) of
// their edge on the floor, sleep off, 4 s, rigid and soft. Each particle was pushed out through
// its closest face, which for bodies more than halfway into each other is on the far side: the
// cubes pulled each other in and ended coincident (centres 0.3 % of the edge apart), a state
// their contacts then held, each particle lying on the other's surface — in the soak, bunnies so
// merged moved as one and drove others into the same state. They must come apart: centres at
// least 0.95 of the edge apart (side by side or one on the other), nothing inside the other,
// and no energy from the separation: the fastest particle ever below 1 m/s (the push-out moves
// positions at a bounded rate without velocity; measured at most 0.43 m/s) and still at the end.
TEST(Contact, BodiesOverlappingByMoreThanHalfComeApart) {
  World world = floorWorld(/*sleep=*/false);
  const double edge = 0.5;
  for (double overlap : {0.6, 0.9, 1.0})
    for (Mode mode : {Mode::Rigid, Mode::Linear}) {
      SCOPED_TRACE(std::string(modeName(mode)) + " overlapping " + std::to_string(overlap));
      World w = world;
      const double offset = 0.5 * edge * (1.0 - overlap);
      const Shape a = onFloorAt(cubeSurface(edge, 4, Vec3(-offset, 0, 0)), 0.001);
      const Shape b = onFloorAt(cubeSurface(edge, 4, Vec3(offset, 0, 0)), 0.001);
      const double alpha = mode == Mode::Rigid ? 1.0 : 0.5;
      const BodyHandle ha = w.addBody(bodyFrom(a, "a", mode, alpha));
      const BodyHandle hb = w.addBody(bodyFrom(b, "b", mode, alpha));
      double fastest = 0;
      for (int step = 0; step < 240; ++step) {
        w.step();
        for (BodyHandle h : {ha, hb})
          fastest = std::max(fastest, double(w.velocities(h).rowwise().norm().maxCoeff()));
      }
      EXPECT_GE((w.centreOfMass(ha) - w.centreOfMass(hb)).norm(), 0.95 * edge);
      const double spacing = mesh::meanEdgeLength(a.triangles, a.points);
      EXPECT_LT(deepestInside(w, ha, hb, b.triangles), 0.05 * spacing);
      EXPECT_LT(deepestInside(w, hb, ha, a.triangles), 0.05 * spacing);
      EXPECT_LT(fastest, 1.0);
      for (BodyHandle h : {ha, hb}) EXPECT_LT(w.velocities(h).rowwise().norm().maxCoeff(), 0.01);
    }
}

// Ten rigid 0.4 m cubes, each turned 7° about the vertical from the one below, stacked 1.5 mm
// apart on the floor, sleep off, 5 s. The position recovery used to push out every round-off
// residue of the resting contacts; each push turned a box a little about its centre and slid its
// other contacts sideways, always the same way: after 5 s this tower leaned 10 cm and swayed at
// 0.17 m/s (the same tower of the 98-point box asset fell within 10 s, sleep on or off). It
// must stand where it was put: every box at its stacked height (the contact tolerance of the
// shipped scenes, 5 % of a spacing per interface), none moved sideways by more than 2 % of the
// edge (5 mm with the slop), and the tower still at the end (fastest particle below 1 cm/s).
TEST(Contact, TallTwistedStackStandsStill) {
  World world = floorWorld(/*sleep=*/false);
  const double edge = 0.4, pitch = edge + 0.0015, turn = 7.0 * M_PI / 180.0;
  const int n = 10;
  std::vector<BodyHandle> boxes;
  std::vector<Vec3> start;
  double spacing = 0;
  for (int k = 0; k < n; ++k) {
    const Vec3 centre(0, 0.5 * edge + 0.0004 + k * pitch, 0);
    Shape s = cubeSurface(edge, 3, centre);
    const Mat3 r = Eigen::AngleAxisd(k * turn, Vec3::UnitY()).toRotationMatrix();
    for (Vec3& p : s.points) p = centre + r * (p - centre);
    spacing = mesh::meanEdgeLength(s.triangles, s.points);
    boxes.push_back(world.addBody(bodyFrom(s, "box", Mode::Rigid, 1.0)));
    start.push_back(world.centreOfMass(boxes.back()));
  }
  for (int step = 0; step < 300; ++step) world.step();
  double worstSideways = 0, worstHeight = 0, fastest = 0;
  for (int k = 0; k < n; ++k) {
    const Vec3 c = world.centreOfMass(boxes[size_t(k)]);
    const Vec3 d = c - start[size_t(k)];
    worstSideways = std::max(worstSideways, std::hypot(d.x(), d.z()));
    const double off = std::abs(c.y() - (k + 0.5) * edge);
    worstHeight = std::max(worstHeight, off);
    EXPECT_LE(off, (k + 1) * 0.05 * spacing) << "box " << k << " from the floor";
    fastest = std::max(
        fastest, test::toDouble(world.velocities(boxes[size_t(k)])).rowwise().norm().maxCoeff());
  }
  EXPECT_LT(worstSideways, 0.02 * edge);
  EXPECT_LT(fastest, 0.01);
  std::printf(
      "[ contact  ] twisted stack of %d: after 5 s a box at most %.3g m sideways, %.3g m off its "
      "stacked height; fastest particle %.3g m/s\n",
      n, worstSideways, worstHeight, fastest);
}

// Five stiff soft boxes (0.4 m, α 0.9, β 0.2, linear and quadratic), stacked 1.5 mm apart,
// undamped, sleep off, 20 s: issue 11's stack, in the soft modes. Each resting particle used to
// be stopped on its own (constraint B), out of its body's goal; shape matching pulled it back in
// the next sub-step, and the friction of those pushes rocked and walked the column: its top box
// strayed up to 5.0 % (linear) and 2.8 % (quadratic) of the edge, the column sank 14 mm and
// buzzed at 3–6 mm/s. Resting contacts now move soft bodies as a whole in B too
// (ContactPoint::resting): 0.04 % and 0.1 %, 0.3–0.4 mm/s. The top box must stay within 1 % of
// the edge all along, every box at its stacked height (5 % of a spacing per interface, the
// shipped scenes' tolerance), and the column still at the end (fastest particle < 2 mm/s).
TEST(Contact, StiffSoftStackStandsWithSleepOff) {
  if (test_support::kSanitized) GTEST_SKIP() << "4,800 sub-steps of five bodies: GCC build only";
  for (Mode mode : {Mode::Linear, Mode::Quadratic}) {
    SCOPED_TRACE(mode == Mode::Linear ? "linear" : "quadratic");
    World world = floorWorld(/*sleep=*/false);
    const double edge = 0.4, pitch = edge + 0.0015;
    const int n = 5;
    std::vector<BodyHandle> boxes;
    std::vector<Vec3> start;
    double spacing = 0;
    for (int k = 0; k < n; ++k) {
      const Vec3 centre(0, 0.5 * edge + 0.0004 + k * pitch, 0);
      const Shape s = cubeSurface(edge, 4, centre);
      spacing = mesh::meanEdgeLength(s.triangles, s.points);
      BodyDef def = bodyFrom(s, "box", mode, 0.9);
      def.params.beta = 0.2;
      boxes.push_back(world.addBody(def));
      start.push_back(world.centreOfMass(boxes.back()));
    }
    double drift = 0;
    for (int step = 0; step < 1200; ++step) {
      world.step();
      const Vec3 d = world.centreOfMass(boxes.back()) - start.back();
      drift = std::max(drift, std::hypot(d.x(), d.z()));
    }
    EXPECT_LT(drift, 0.01 * edge);
    double fastest = 0;
    for (int k = 0; k < n; ++k) {
      const double off = std::abs(world.centreOfMass(boxes[size_t(k)]).y() - (k + 0.5) * edge);
      EXPECT_LE(off, (k + 1) * 0.05 * spacing) << "box " << k << " from the floor";
      fastest = std::max(
          fastest, test::toDouble(world.velocities(boxes[size_t(k)])).rowwise().norm().maxCoeff());
    }
    EXPECT_LT(fastest, 0.002);
    std::printf(
        "[ contact  ] %s stack of %d at alpha 0.9: top drift at most %.3g m in 20 s (%.2f %% "
        "of the edge); fastest particle %.3g m/s\n",
        mode == Mode::Linear ? "linear" : "quadratic", n, drift, 100 * drift / edge, fastest);
  }
}

// A very soft body (α 0.005: nearly a liquid, here with plastic flow) with stiffer bodies dropped
// on it. Shock propagation solves each body against the bodies below it held immovable; its
// impulses used to warm-start the next sub-step, where the soft body moves, and landed on its
// single light particles: the pile reached 10⁴ m/s within a second (found by the soak's random
// parameters). No particle may be faster than twice what the fall from the highest start can
// give (a light particle hit by a heavy body takes at most twice its speed).
TEST(Contact, VerySoftBodyUnderStifferOnesStaysBounded) {
  World w = floorWorld(/*sleep=*/false);
  BodyDef goo =
      bodyFrom(onFloorAt(bunnyCage(0.07, Vec3::Zero()), 0.01), "goo", Mode::Linear, 0.005);
  goo.params.beta = 0.971;
  goo.params.damping = 0.49;
  goo.params.plasticity.yield = 0.198;
  goo.params.plasticity.creep = 3.526;
  w.addBody(goo);
  const Mode modes[3] = {Mode::Rigid, Mode::Linear, Mode::Quadratic};
  double highest = 0;
  for (int k = 0; k < 3; ++k) {
    const Mat3 turn = Eigen::AngleAxisd(0.65 * k, Vec3::UnitY()).toRotationMatrix();
    const Shape s =
        onFloorAt(bunnyCage(0.07, Vec3(0.1 * (k % 2) - 0.05, 0, 0.05 * k), turn), 0.9 + 0.8 * k);
    BodyDef d =
        bodyFrom(s, "stiff " + std::to_string(k), modes[k], modes[k] == Mode::Rigid ? 1 : 0.5);
    d.params.damping = 0.2;
    w.addBody(d);
    for (const Vec3& p : s.points) highest = std::max(highest, p.y());
  }
  const double bound = 2 * std::sqrt(2 * 9.81 * highest);
  double fastest = 0;
  for (int step = 0; step < 150; ++step) {
    w.step();
    for (const WorldEvent& e : w.takeEvents()) ADD_FAILURE() << e.message;
    for (BodyHandle b : w.bodies())
      fastest = std::max(fastest, double(w.velocities(b).rowwise().norm().maxCoeff()));
  }
  EXPECT_LT(fastest, bound);
}

// A body with no stiffness at all (α = 0, the bottom of the accepted range, β 0.97) under three
// rigid bunnies of 20× its mass: it is a fluid and the pile sinks through it to the floor, but,
// held by its reach (no particle farther from its goal than the body's radius of gyration), it
// stays in one piece. Measured over 20 s (2-core VM): its diagonal at most 1.78× the rest one;
// without the reach it spread to 22× within 10 s and 27× by 20 s (the soak's failure, issue 18:
// a bunny at α 0.004 under the large scene's pile spread to 10×, contacts against its folded
// surface multiplied and the soak ended in NaN). Not asserted, because not yet true: the goo's
// particles still jitter (single particles up to 11 m/s, snapped back within reach), and its
// surface ends up inside out (docs/design.md §5.3).
// The jittering goo makes every contact look-up search far (its particles' speed widens the
// reach): 8 s in the GCC build, 23 s under ASan.
TEST(Contact, BodyWithoutStiffnessUnderAPileStaysWithinItsReach) {
  World w = floorWorld(/*sleep=*/false);
  const Shape gooShape = onFloorAt(bunnyCage(0.07, Vec3::Zero()), 0.01);
  BodyDef goo = bodyFrom(gooShape, "goo", Mode::Linear, 0.0);
  goo.params.beta = 0.97;
  goo.totalMass = 1;
  const BodyHandle g = w.addBody(goo);
  auto diagonal = [&] {
    const Eigen::MatrixX3f& x = w.positions(g);
    return double((x.colwise().maxCoeff() - x.colwise().minCoeff()).norm());
  };
  const double restDiagonal = diagonal();
  double top = -1e30;
  for (const Vec3& p : gooShape.points) top = std::max(top, p.y());
  std::vector<BodyHandle> pile;
  for (int k = 0; k < 3; ++k) {
    BodyDef d = bodyFrom(onFloorAt(bunnyCage(0.06, Vec3(0.02 * k, 0, 0)), top + 0.02 + 0.5 * k),
                         "heavy " + std::to_string(k), Mode::Rigid, 1.0);
    d.totalMass = 20;
    d.params.damping = 0.2;
    pile.push_back(w.addBody(d));
  }
  double largest = 0, lowest = 1e30;
  for (int step = 0; step < 600; ++step) {  // 10 s
    w.step();
    for (const WorldEvent& e : w.takeEvents()) ADD_FAILURE() << e.message;
    largest = std::max(largest, diagonal() / restDiagonal);
    for (BodyHandle b : pile) lowest = std::min(lowest, double(w.positions(b).col(1).minCoeff()));
  }
  EXPECT_LT(largest, 2.5);
  EXPECT_GT(lowest, -0.01);  // the floor still holds the pile
}

// Sleep (docs/design.md §5.5): a resting body falls asleep and then does not move at all; a
// body dropped on it wakes it (the sleeping body is an obstacle with the bounds it had when it
// fell asleep) and comes to rest on top instead of passing through; then both sleep again.
TEST(Sleep, ABodyLandingOnASleepingOneWakesItAndRestsOnIt) {
  World world = floorWorld();
  const BodyHandle lower = world.addBody(
      bodyFrom(onFloorAt(cubeSurface(0.4, 3, Vec3::Zero()), 0.002), "lower", Mode::Rigid, 1.0));
  int steps = 0;
  for (; steps < 600 && !world.isSleeping(lower); ++steps) world.step();
  ASSERT_TRUE(world.isSleeping(lower)) << "not asleep within 10 s";
  const Eigen::MatrixX3d still = test::toDouble(world.positions(lower));
  for (int s = 0; s < 60; ++s) world.step();
  EXPECT_TRUE(world.isSleeping(lower));
  EXPECT_EQ((test::toDouble(world.positions(lower)) - still).norm(), 0.0);  // not a bit moved

  const double top = still.col(1).maxCoeff();
  const BodyHandle upper = world.addBody(bodyFrom(
      onFloorAt(cubeSurface(0.4, 3, Vec3(0.05, 0, 0.03)), top + 0.5), "upper", Mode::Linear, 0.8));
  bool woke = false;
  for (int s = 0; s < 240; ++s) {  // 4 s
    world.step();
    woke = woke || !world.isSleeping(lower);
  }
  EXPECT_TRUE(woke);
  const double spacing = 0.4 / 3;
  EXPECT_GT(world.positions(upper).col(1).minCoeff(), top - 0.05 * spacing);  // on top of it
  EXPECT_NEAR(world.centreOfMass(upper).y(), top + 0.2, 0.02);
  for (int s = 0; s < 360 && !(world.isSleeping(lower) && world.isSleeping(upper)); ++s)
    world.step();
  EXPECT_TRUE(world.isSleeping(lower) && world.isSleeping(upper)) << "not asleep again in 6 s";
}

// Whatever can move a sleeping body wakes it: a force, new parameters, a settings or collider
// change, a new state (at once) and a drag (at the next step).
TEST(Sleep, ForcesParametersSettingsCollidersStatesAndDragsWakeABody) {
  World world = floorWorld();
  const BodyHandle b = world.addBody(
      bodyFrom(onFloorAt(cubeSurface(0.4, 3, Vec3::Zero()), 0.002), "box", Mode::Linear, 0.9));
  auto sleepNow = [&] {
    for (int s = 0; s < 900 && !world.isSleeping(b); ++s) world.step();
    ASSERT_TRUE(world.isSleeping(b));
  };
  sleepNow();
  world.addForce(b, 0, Vec3(0, 1, 0));
  EXPECT_FALSE(world.isSleeping(b)) << "force";
  sleepNow();
  BodyParams p = world.params(b);
  p.alpha = 0.7;
  world.setParams(b, p);
  EXPECT_FALSE(world.isSleeping(b)) << "parameters";
  sleepNow();
  WorldSettings ws = world.settings();
  ws.rollingResistance = 0.1;
  world.setSettings(ws);
  EXPECT_FALSE(world.isSleeping(b)) << "settings";
  sleepNow();
  world.addCollider(Collider::sphere(Vec3(5, 0, 0), 0.5));
  EXPECT_FALSE(world.isSleeping(b)) << "collider";
  sleepNow();
  world.setState(b, test::toDouble(world.positions(b)),
                 Eigen::MatrixX3d::Zero(world.particleCount(b), 3));
  EXPECT_FALSE(world.isSleeping(b)) << "state";
  sleepNow();
  DragDef drag;
  drag.body = b;
  drag.particles = {0};
  drag.weights = {1.0};
  drag.target = world.centreOfMass(b) + Vec3(0, 0.5, 0);
  drag.stiffness = 0.2;
  world.addDrag(drag);
  world.step();
  EXPECT_FALSE(world.isSleeping(b)) << "drag";
  EXPECT_GT(world.centreOfMass(b).y(), 0.2);  // and it moves towards the target
}

// Rolling resistance (docs/design.md §5.5): a rigid ball rolling on the floor slows down by the
// couple c·ρ·N, as the closed form for a rolling ball says: with I the moment about its rolling
// axis and R its radius, a = c·g·(ρ/R) / (1 + I/(mR²)), ρ and I recomputed here from the
// particles. The icosphere's facets slow it by themselves (each pivot over a vertex is a small
// inelastic impact); that part is measured with c = 0 and taken off. Without resistance it
// rolls on; with it, it stops, and its energy only goes down.
TEST(StaticContact, BallRollsToAStopAsRollingResistanceSays) {
  const mesh::TriangleMesh sphere = mesh::testing::makeIcosphere(4, 0.3, Vec3(0, 0.3, 0));
  Shape s{sphere.vertices, sphere.triangles};
  s = onFloorAt(s, 0.001);
  const double radius = 0.3, v0 = 1.5, g = 9.81;
  double rho2 = 0, axisMoment = 0;  // per unit mass (equal particle masses)
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : s.points) centre += p / double(s.points.size());
  for (const Vec3& p : s.points) {
    const Vec3 r = p - centre;
    rho2 += r.squaredNorm() / double(s.points.size());
    axisMoment += (r.x() * r.x() + r.y() * r.y()) / double(s.points.size());
  }
  // Speed lost between 0.5 and 1.5 s (m/s), speed at 4 s (m/s), and the largest rise of
  // kinetic plus potential energy in one step (J/kg).
  auto roll = [&](double c) {
    World world = floorWorld();
    WorldSettings ws = world.settings();
    ws.rollingResistance = c;
    ws.sleep = false;
    world.setSettings(ws);
    BodyDef def = bodyFrom(s, "ball", Mode::Rigid, 1.0);
    const BodyHandle b = world.addBody(def);
    Eigen::MatrixX3d v(s.points.size(), 3);
    const Vec3 spin(0, 0, -v0 / radius);  // rolling along +x without slipping
    for (size_t i = 0; i < s.points.size(); ++i)
      v.row(Eigen::Index(i)) = (Vec3(v0, 0, 0) + spin.cross(s.points[i] - centre)).transpose();
    world.setState(b, test::toDouble(world.positions(b)), v);
    double at05 = 0, at15 = 0, energyLast = 0, rise = 0;
    for (int step = 1; step <= 240; ++step) {
      world.step();
      const double speed = world.linearMomentum(b).x() / world.mass(b);
      if (step == 30) at05 = speed;
      if (step == 90) at15 = speed;
      const Eigen::MatrixX3d vel = test::toDouble(world.velocities(b));
      const double energy = 0.5 * vel.rowwise().squaredNorm().sum() / double(vel.rows()) +
                            g * world.centreOfMass(b).y();
      if (step > 1) rise = std::max(rise, energy - energyLast);
      energyLast = energy;
    }
    const double at4 = world.linearMomentum(b).x() / world.mass(b);
    return std::array<double, 3>{at05 - at15, at4, rise};
  };
  const auto facets = roll(0.0), resisted = roll(0.05), more = roll(0.1);
  // Per unit c (m/s²): 5.89 from the closed form; measured 5.64 and 5.53 (the facets slow a
  // slower ball less, so taking off their c = 0 share takes a little too much).
  const double perUnit = g * std::sqrt(rho2) / radius / (1.0 + axisMoment / (radius * radius));
  EXPECT_NEAR((resisted[0] - facets[0]) / 0.05, perUnit, 0.12 * perUnit);
  EXPECT_NEAR((more[0] - facets[0]) / 0.1, perUnit, 0.12 * perUnit);
  EXPECT_GT(facets[1], 1.0);           // without resistance it rolls on (1.18 m/s at 4 s)
  EXPECT_LT(std::abs(more[1]), 0.01);  // with c = 0.1 it has stopped
  // Energy (J/kg) only goes down with resistance (largest rise per step measured: 0 and 1e-5;
  // the faceted roll alone: 6e-4, where the ball tips over a vertex).
  EXPECT_LT(resisted[2], 1e-4);
  EXPECT_LT(more[2], 1e-4);
}

// A stiff body dropped on the floor lands as a whole: the floor's impulse on the touching
// particles reaches its rigid motion, so it does not bounce back up (when only the touching
// particles were stopped, the rest carried on and the goals turned the projection into an
// upward kick: it rebounded at ~45 % of its impact speed and wandered off by metres), and it
// comes to rest near where it fell. (A softer body, α < 1, stores the impact as deformation and
// bounces back elastically like a rubber ball; that is the shape-matching spring, not contact.)
// It tips over onto its side and rocks there: between pivot changes a rigid body rocking without
// slipping keeps its energy (KE + PE constant to 1e-4 J over each swing), and each change of
// pivot is an inelastic impact that takes 30–50 % of it, and rolling resistance takes the rest,
// so the body falls asleep. (Checked at 12 s: the old 5 s held only because the old contact
// dissipated energy it should not have.)
TEST(StaticContact, StiffBodyLandsWithoutBouncingOrWandering) {
  World world = floorWorld();
  const Shape s = bunnyCage(0.1, Vec3(0, 2.0, 0),
                            Eigen::AngleAxisd(0.5, Vec3(1, 0, 1).normalized()).toRotationMatrix());
  BodyDef def = bodyFrom(s, "bunny", Mode::Rigid, 1.0);
  def.params.damping = 0.1;  // the particles' vibration about the rigid goals, not the motion
  const BodyHandle b = world.addBody(def);
  double impactSpeed = 0, reboundSpeed = 0;
  bool landed = false;
  Eigen::MatrixX3d previous;
  constexpr int kSteps = 720;
  for (int step = 0; step < kSteps; ++step) {
    const double before = world.linearMomentum(b).y() / world.mass(b);
    world.step();
    const double vy = world.linearMomentum(b).y() / world.mass(b);
    if (!landed && world.positions(b).col(1).minCoeff() < 1e-3) {
      landed = true;
      impactSpeed = -before;
    }
    if (landed) reboundSpeed = std::max(reboundSpeed, vy);
    if (step == kSteps - 2) previous = test::toDouble(world.positions(b));
  }
  ASSERT_TRUE(landed);
  EXPECT_GT(impactSpeed, 4.0);
  EXPECT_LT(reboundSpeed, 0.1 * impactSpeed);
  const Vec3 c = world.centreOfMass(b);
  EXPECT_LT(std::hypot(c.x(), c.z()), 1.2);  // it tips over its edge, but does not slide away
  const Eigen::MatrixX3d x = test::toDouble(world.positions(b));
  EXPECT_LT((x - previous).rowwise().norm().maxCoeff(), 1e-3);  // at rest (body ≈ 1 m)
  EXPECT_TRUE(world.isSleeping(b));
}

// A soft bunny (0.7 m, as in the large scene) lying on the floor with friction 0.6 and sleep off
// stays where it came to rest. It rests on a few particles, and shape matching carries its weight
// to them through goals below the floor: every sub-step the integration pulls each support
// 3–8 mm in. Judged by that depth its contacts were never resting, constraint B stopped each
// support on its own, its friction and A's pulled against each other at their cones' limits, and
// the body walked here for ever (ContactPoint::resting). Centre moves between 15 and 45 s, before
// the fix / now: linear α 0.6 on its side 2.02 / 0.11 mm, quadratic α 0.6 2.99 / 0.004 mm,
// linear α 0.6 on its other side 2.55 / 0.67 mm. Not here: linear α 0.3 on its side, which still
// moves 3.1 mm (2.15 before) with its centre rising 0.9 mm, although its supports stay resting
// throughout; a slow change of shape that this test does not cover (open, issue 11's note).
TEST(StaticContact, SoftBodyRestingOnTheFloorDoesNotWalk) {
  struct Case {
    Mode mode;
    double alpha;
    Vec3 axis;  // it lies turned 90° about this axis
  };
  const Case cases[] = {{Mode::Linear, 0.6, Vec3::UnitZ()},
                        {Mode::Quadratic, 0.6, Vec3::UnitZ()},
                        {Mode::Linear, 0.6, Vec3::UnitX()}};
  for (const Case& k : cases) {
    World world = floorWorld(false);
    const Shape s = onFloorAt(
        bunnyCage(0.07, Vec3::Zero(), Eigen::AngleAxisd(0.5 * M_PI, k.axis).toRotationMatrix()),
        0.05);
    BodyDef def = bodyFrom(s, "bunny", k.mode, k.alpha);
    def.params.damping = 0.2;
    const BodyHandle b = world.addBody(def);
    for (int step = 0; step < 900; ++step) world.step();  // 15 s: landed and settled
    const Vec3 rested = world.centreOfMass(b);
    for (int step = 0; step < 1800; ++step) world.step();  // 30 s more
    // 1.5 % of its spacing (0.1 m) in 30 s.
    EXPECT_LT((world.centreOfMass(b) - rested).norm(), 1.5e-3)
        << modeName(k.mode) << " α " << k.alpha << " axis " << k.axis.transpose();
  }
}

// Contact forces are proportional to the masses they move, so scaling every mass in a world by a
// power of two (exact in floating point) must leave the motion unchanged bit for bit. Here a
// rigid bunny (0.15 m) falls tilted onto a soft one on the floor and both slide, turn and come to
// rest with friction, for 3 s. It failed while the friction visit skipped impulse changes within
// Eigen's isZero() precision (1e-5 N·s, an absolute figure) but kept them in the accumulated
// impulse: light bodies lost most of their friction, and a 1 g rigid bunny of 1.4 cm walked 2 cm
// in 20 s where a 1 kg one rested (the default scene scaled to 0.1 never slept).
TEST(StaticContact, MotionDoesNotDependOnTheMassScale) {
  auto run = [](double massScale) {
    World world = floorWorld(false);  // body friction: the default 0.5
    BodyDef soft =
        bodyFrom(onFloorAt(bunnyCage(0.03, Vec3::Zero()), 0.0), "soft", Mode::Linear, 0.6);
    soft.totalMass = 2.0 * massScale;
    const Mat3 tilt =
        (Eigen::AngleAxisd(0.7, Vec3::UnitZ()) * Eigen::AngleAxisd(-0.4, Vec3::UnitY()))
            .toRotationMatrix();
    BodyDef rigid = bodyFrom(onFloorAt(bunnyCage(0.015, Vec3(0.05, 0, 0.02), tilt), 0.4), "rigid",
                             Mode::Rigid, 1.0);
    rigid.totalMass = 0.5 * massScale;
    world.addBody(soft);
    world.addBody(rigid);
    for (int step = 0; step < 180; ++step) world.step();
    return world.stateHash();
  };
  const std::uint64_t kilograms = run(1.0);
  EXPECT_EQ(run(std::ldexp(1.0, -10)), kilograms);  // 2 g and 0.5 g
  EXPECT_EQ(run(std::ldexp(1.0, 10)), kilograms);   // 2 t and 0.5 t
}

// A bunny (1.5 m) dropped from 1 m onto a floor with friction 0.6, with one sub-step of h
// seconds per step, for 30 steps: the worst excess of kinetic energy over the potential energy
// the fall released (J; ≤ 0 for a body that started at rest, as contacts and shape matching only
// take energy away), the largest distance of a particle from the centre of mass and its rest
// value (m).
struct LargeStepLanding {
  double energyExcess = -1e30, largestRadius = 0, restRadius = 0, released = 0;
  double lowest = 0, height = 0;  // lowest particle and centre of mass at the end (m)
};

// exact: one sub-step of h per step, sleep off (the update itself at that sub-step); otherwise
// the default settings, which split the step into sub-steps of at most maxSubstep and let the
// body sleep once it rests.
LargeStepLanding landAtLargeSteps(Mode mode, double alpha, double h, bool exact = true) {
  WorldSettings settings = exact ? test::exactSubsteps(h) : WorldSettings{};
  settings.timeStep = h;
  if (exact) settings.sleep = false;
  World world(settings);
  world.addCollider(Collider::plane(Vec3::UnitY(), 0.0, 0.6));
  const Shape s =
      onFloorAt(bunnyCage(0.1, Vec3::Zero(),
                          Eigen::AngleAxisd(0.4, Vec3(1, 0, 1).normalized()).toRotationMatrix()),
                1.0);
  BodyDef def = bodyFrom(s, "bunny", mode, alpha);
  def.params.beta = 0.2;
  const BodyHandle b = world.addBody(def);
  const double mass = world.mass(b), y0 = world.centreOfMass(b).y();
  const Eigen::VectorXf m = world.masses(b);
  auto radius = [&] {
    const Eigen::MatrixX3d x = test::toDouble(world.positions(b));
    const Vec3 c = world.centreOfMass(b);
    return (x.rowwise() - c.transpose()).rowwise().norm().maxCoeff();
  };
  LargeStepLanding r;
  r.restRadius = radius();
  for (int step = 0; step < 30; ++step) {
    world.step();
    const Eigen::MatrixX3d v = test::toDouble(world.velocities(b));
    double kinetic = 0;
    for (int i = 0; i < v.rows(); ++i) kinetic += 0.5 * m[i] * v.row(i).squaredNorm();
    const double released = mass * 9.81 * (y0 - world.centreOfMass(b).y());
    r.energyExcess = std::max(r.energyExcess, kinetic - released);
    r.largestRadius = std::max(r.largestRadius, radius());
  }
  r.released = mass * 9.81 * y0;
  r.lowest = world.positions(b).col(1).minCoeff();
  r.height = world.centreOfMass(b).y();
  return r;
}

// Soft bodies landing at long sub-steps (the CLI accepts steps up to 10 s): the whole fall of a
// step ends in the floor, every particle is in contact, and the solve moves particles by metres.
// The fitted rigid motion used to follow the particles' moving positions instead of the lever
// arms the solve is linear about: friction then turned the body by 2 rad per sub-step and the
// kinetic energy grew ×10⁴ within five steps (the default scene's soft bodies at dt 1 s). With α
// applied per sub-step as given, a long sub-step also made the material very soft
// (k = α/((1 − α)h²)): at α 0.9 the same drop gained 3.5·10⁴ J at 1 s and 5·10³⁵ J at 3 s, at
// α 0.5 7.5·10¹² J at 3 s. Stated per 1/240 s and converted (substep_material.h), the material
// is the same at any sub-step: no energy gained, and the body keeps its size (1-s sub-steps
// are the longest accepted; at 3-s sub-steps, refused since, it grew at most ×1.21, at 10 s
// ×2.7).
TEST(Contact, SoftBodiesLandWithoutGainingEnergyAtLongSubSteps) {
  for (const Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic})
    for (const double alpha : {0.3, 0.5, 0.9})
      for (const double h : {0.25, 0.5, 1.0}) {
        const LargeStepLanding r = landAtLargeSteps(mode, alpha, h);
        const std::string label =
            std::string(modeName(mode)) + " α " + std::to_string(alpha) + " h " + std::to_string(h);
        EXPECT_LT(r.energyExcess, 1e-3 * r.released) << label;
        EXPECT_LT(r.largestRadius, 1.3 * r.restRadius) << label;
        EXPECT_GT(r.lowest, -0.1 * r.restRadius) << label;
        EXPECT_LT(r.height, r.restRadius) << label;
      }
}

// With the default settings a long step runs sub-steps of at most 1/120 s, so a soft body lands
// as it does at short steps whatever the step: no energy gained, its shape kept within its
// material's squash. α 0.9 is the case that gained energy at one sub-step of 0.5 s before the
// sub-step conversion (previous test); dt 3 s is 360 sub-steps per step.
TEST(Contact, SoftBodiesLandAsAtShortStepsWhenLongStepsAreSplit) {
  for (const Mode mode : {Mode::Linear, Mode::Quadratic})
    for (const double h : {0.5, 3.0}) {
      const LargeStepLanding r = landAtLargeSteps(mode, 0.9, h, false);
      const std::string label = std::string(modeName(mode)) + " dt " + std::to_string(h);
      EXPECT_LT(r.energyExcess, 1e-3 * r.released) << label;
      EXPECT_LT(r.largestRadius, 1.1 * r.restRadius) << label;
      EXPECT_GT(r.lowest, -0.01 * r.restRadius) << label;
      EXPECT_LT(r.height, r.restRadius) << label;
    }
}

// Rigid and stiff bodies (α 1) keep their shape on the floor at any step up to the scene maximum
// (issue 17: growth ≤ 1 %). At 10 s per step the contact turns a body by radians in one solve;
// its velocities used not to turn with it, a rigid field of the old orientation is a shear of the
// new one, and a linear body (β 0.2) grew by 20–30 % at every other step, a quadratic one ×3.
TEST(Contact, StiffBodiesKeepTheirShapeOnTheFloorAtTenSecondSteps) {
  for (const Mode mode : {Mode::Rigid, Mode::Linear, Mode::Quadratic})
    for (const double h : {1.0, 3.0, 10.0}) {
      const LargeStepLanding r = landAtLargeSteps(mode, 1.0, h);
      const std::string label = std::string(modeName(mode)) + " h " + std::to_string(h);
      EXPECT_LT(r.energyExcess, 1e-3 * r.released) << label;
      EXPECT_LT(r.largestRadius, 1.01 * r.restRadius) << label;
      // On the floor: a step falls g·h² (981 m at 10 s) into it and is lifted out by the solve;
      // what is left inside is pushed out over the next sub-steps (contact_solver.h), so the
      // lowest particle may end a little inside (12 cm at 10 s, quadratic).
      EXPECT_GT(r.lowest, -0.2 * r.restRadius) << label;
      EXPECT_LT(r.height, r.restRadius) << label;
      std::printf("[ contact  ] %s s: radius %.4f of %.4f m, lowest %.4f m, centre %.3f m\n",
                  label.c_str(), r.largestRadius, r.restRadius, r.lowest, r.height);
    }
}

TEST(Contact, SameResultOnOneAndTwoThreads) {
  auto run = [](int threads) {
    setThreadCount(threads);
    WorldSettings settings;
    settings.substeps = 2;
    World world(settings);
    world.addCollider(Collider::plane(Vec3::UnitY(), 0.0));
    for (int k = 0; k < 6; ++k) {
      const Shape s = bunnyCage(0.08, Vec3(0.1 * (k % 2), 0.5 + 0.9 * k, 0.05 * k));
      world.addBody(
          bodyFrom(s, "b" + std::to_string(k), k % 2 ? Mode::Linear : Mode::Quadratic, 0.4));
    }
    int contacts = 0;
    for (int step = 0; step < 150; ++step) {
      world.step();
      contacts += world.lastContactCount();
    }
    EXPECT_GT(contacts, 0);
    setThreadCount(0);
    return world.stateHash();
  };
  const std::uint64_t one = run(1);
  EXPECT_EQ(one, run(1));
  EXPECT_EQ(one, run(2));
}

TEST(Contact, SwitchedOffLetsBodiesPass) {
  WorldSettings settings = test::noGravity(1.0 / 60, 2);
  settings.bodyContact = false;
  World world(settings);
  BodyDef a = bodyFrom(bunnyCage(0.1, Vec3(-1, 0, 0)), "a", Mode::Rigid, 1.0);
  BodyDef b = bodyFrom(bunnyCage(0.1, Vec3(1, 0, 0)), "b", Mode::Rigid, 1.0);
  a.velocity = Vec3(3, 0, 0);
  const BodyHandle ha = world.addBody(a), hb = world.addBody(b);
  for (int step = 0; step < 60; ++step) world.step();
  EXPECT_GT(world.centreOfMass(ha).x(), world.centreOfMass(hb).x());
}

TEST(Contact, BadSurfacesAreRejectedByName) {
  World world;
  const Shape s = bunnyCage(0.1, Vec3::Zero());
  auto expectError = [&](const std::vector<Triangle>& triangles, const std::string& what) {
    BodyDef def = bodyFrom(s, "bunny", Mode::Linear, 0.5);
    def.surface = triangles;
    try {
      world.addBody(def);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("surface"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_TRUE(world.bodies().empty());  // nothing half-added
  };
  std::vector<Triangle> open = s.triangles;
  open.pop_back();
  expectError(open, "edge");
  std::vector<Triangle> flipped = s.triangles;
  std::swap(flipped[3][0], flipped[3][1]);
  expectError(flipped, "triangle 3");
  std::vector<Triangle> outOfRange = s.triangles;
  outOfRange[0][2] = 9999;
  expectError(outOfRange, "9999");
  std::vector<Triangle> inward = s.triangles;
  for (Triangle& t : inward) std::swap(t[0], t[1]);
  expectError(inward, "inverted");
}

}  // namespace
}  // namespace sb
