#include "scene_checks.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

namespace sb::test {

namespace {

Eigen::MatrixX3d positionsOf(const Scene& scene, int body) {
  return scene.world.positions(scene.bodies[size_t(body)].handle).cast<double>();
}

struct Box {
  Vec3 lo, hi;
  bool contains(const Vec3& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
};

Box boundsOf(const Eigen::MatrixX3d& x) {
  return {x.colwise().minCoeff().transpose(), x.colwise().maxCoeff().transpose()};
}

}  // namespace

double windingNumber(const Vec3& p, const Eigen::MatrixX3d& x,
                     const std::vector<std::array<int, 3>>& tris) {
  double solidAngle = 0.0;
  for (const auto& t : tris) {
    const Vec3 a = x.row(t[0]).transpose() - p;
    const Vec3 b = x.row(t[1]).transpose() - p;
    const Vec3 c = x.row(t[2]).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    // Van Oosterom & Strackee 1983: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| +
    // (b·c)|a|); atan2 keeps the quadrant, so Ω covers (−2π, 2π).
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    solidAngle += 2.0 * std::atan2(numerator, denominator);
  }
  return solidAngle / (4.0 * M_PI);
}

double pointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Closest point by Voronoi regions (Ericson, Real-Time Collision Detection §5.1.5).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

double particleSpacing(const Scene& scene, int body) {
  const SceneBody& b = scene.bodies[size_t(body)];
  const Eigen::MatrixX3d rest = scene.world.restPositions(b.handle).cast<double>();
  std::set<std::pair<int, int>> edges;
  for (const auto& t : b.cageTriangles)
    for (int k = 0; k < 3; ++k) edges.insert(std::minmax(t[size_t(k)], t[size_t((k + 1) % 3)]));
  if (edges.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& [i, j] : edges) sum += (rest.row(i) - rest.row(j)).norm();
  return sum / double(edges.size());
}

double boundingBoxDiagonal(const Scene& scene, int body) {
  const Box box = boundsOf(positionsOf(scene, body));
  return (box.hi - box.lo).norm();
}

Penetration deepestPenetration(const Scene& scene) {
  const int n = int(scene.bodies.size());
  std::vector<Eigen::MatrixX3d> x(static_cast<size_t>(n));
  std::vector<Box> boxes(static_cast<size_t>(n));
  std::vector<double> spacing(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[size_t(i)] = positionsOf(scene, i);
    boxes[size_t(i)] = boundsOf(x[size_t(i)]);
    spacing[size_t(i)] = particleSpacing(scene, i);
  }
  Penetration worst;
  for (int into = 0; into < n; ++into) {
    const auto& tris = scene.bodies[size_t(into)].cageTriangles;
    if (tris.empty()) continue;  // no closed surface to be inside of
    const Box& box = boxes[size_t(into)];
    const Eigen::MatrixX3d& y = x[size_t(into)];
    for (int body = 0; body < n; ++body) {
      if (body == into) continue;
      const Box& other = boxes[size_t(body)];
      if ((other.hi.array() < box.lo.array()).any() || (other.lo.array() > box.hi.array()).any())
        continue;
      const double scale = std::min(spacing[size_t(body)], spacing[size_t(into)]);
      for (int i = 0; i < x[size_t(body)].rows(); ++i) {
        const Vec3 p = x[size_t(body)].row(i).transpose();
        if (!box.contains(p)) continue;
        if (std::abs(windingNumber(p, y, tris)) <= 0.5) continue;
        double depth = std::numeric_limits<double>::infinity();
        for (const auto& t : tris)
          depth = std::min(
              depth, pointTriangleDistance(p, y.row(t[0]).transpose(), y.row(t[1]).transpose(),
                                           y.row(t[2]).transpose()));
        const double relative = scale > 0 ? depth / scale : depth;
        if (relative > worst.relativeDepth) worst = {depth, relative, body, i, into};
      }
    }
  }
  return worst;
}

ColliderClearance lowestColliderClearance(const Scene& scene) {
  ColliderClearance lowest;
  lowest.distance = lowest.relativeDistance = std::numeric_limits<double>::infinity();
  const auto& colliders = scene.world.colliders();
  for (int body = 0; body < int(scene.bodies.size()); ++body) {
    const Eigen::MatrixX3d x = positionsOf(scene, body);
    const double spacing = particleSpacing(scene, body);
    for (int c = 0; c < int(colliders.size()); ++c)
      for (int i = 0; i < x.rows(); ++i) {
        Vec3 normal;
        const double d = colliderDistance(colliders[size_t(c)], x.row(i).transpose(), &normal);
        const double relative = spacing > 0 ? d / spacing : d;
        if (relative < lowest.relativeDistance) lowest = {d, relative, body, i, c};
      }
  }
  return lowest;
}

double maxDeviationFromRigidFit(const Scene& scene, int body) {
  const BodyHandle h = scene.bodies[size_t(body)].handle;
  const Eigen::MatrixX3d x = scene.world.positions(h).cast<double>();
  const Eigen::MatrixX3d q = scene.world.restPositions(h).cast<double>();
  const Eigen::RowVector3d cx = x.colwise().mean(), cq = q.colwise().mean();
  const Eigen::MatrixX3d xc = x.rowwise() - cx, qc = q.rowwise() - cq;
  // Kabsch: the rotation maximising Σ xᵢ·(R qᵢ) from the SVD of Σ xᵢ qᵢᵀ, without reflection.
  const Mat3 covariance = xc.transpose() * qc;
  const Eigen::JacobiSVD<Mat3> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Mat3 R = svd.matrixU() * d * svd.matrixV().transpose();
  const Eigen::MatrixX3d fitted = qc * R.transpose();
  return (xc - fitted).rowwise().norm().maxCoeff();
}

}  // namespace sb::test
