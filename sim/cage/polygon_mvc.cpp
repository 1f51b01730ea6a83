#include "sim/cage/polygon_mvc.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "sim/mesh/closest_point.h"

namespace sb::cage {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;

void planarMeanValue(const Vec2& q, const std::vector<Vec2>& corners, double* b) {
  const std::size_t k = corners.size();
  thread_local std::vector<Vec2> s;
  thread_local std::vector<double> r, t;
  s.resize(k);
  r.resize(k);
  t.resize(k);
  double scale = 0.0;
  for (std::size_t i = 0; i < k; ++i) {
    s[i] = corners[i] - q;
    r[i] = s[i].norm();
    scale = std::max(scale, r[i]);
  }
  std::fill(b, b + k, 0.0);
  for (std::size_t i = 0; i < k; ++i) {
    if (r[i] <= 1e-12 * scale) {  // on a corner
      b[i] = 1.0;
      return;
    }
  }
  // tan(α_i/2) of the signed angle α_i at q between corners i and i+1, in whichever of the two
  // equal forms has no cancellation (sin/(1+cos) unless the angle is obtuse).
  for (std::size_t i = 0; i < k; ++i) {
    const std::size_t j = (i + 1) % k;
    const double det = s[i].x() * s[j].y() - s[i].y() * s[j].x();
    const double dot = s[i].dot(s[j]);
    const double rr = r[i] * r[j];
    if (std::abs(det) <= 1e-12 * rr && dot < 0.0) {  // on edge (i, j): linear along it
      b[i] = r[j] / (r[i] + r[j]);
      b[j] = r[i] / (r[i] + r[j]);
      return;
    }
    t[i] = dot >= 0.0 ? det / (rr + dot) : (rr - dot) / det;
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < k; ++i) {
    b[i] = (t[(i + k - 1) % k] + t[i]) / r[i];
    sum += b[i];
  }
  for (std::size_t i = 0; i < k; ++i) b[i] /= sum;
}

PolygonMeanValueCage::PolygonMeanValueCage(const mesh::TriangleMesh& cage)
    : vertices_(cage.vertices) {
  Eigen::AlignedBox3d box;
  for (const Vec3& v : vertices_) box.extend(v);
  diagonal_ = vertices_.empty() ? 0.0 : box.diagonal().norm();
  centre_ = vertices_.empty() ? Vec3::Zero() : Vec3(box.center());

  auto makePiece = [&](std::vector<int> corners, const Vec3& normal, double share) {
    Piece p;
    p.corners = std::move(corners);
    p.normal = normal;
    p.share = share;
    p.origin = vertices_[std::size_t(p.corners[0])];
    const Vec3 edge = vertices_[std::size_t(p.corners[1])] - p.origin;
    p.e1 = (edge - normal * normal.dot(edge)).normalized();
    p.e2 = normal.cross(p.e1);
    for (const int c : p.corners) {
      const Vec3 r = vertices_[std::size_t(c)] - p.origin;
      p.corners2d.emplace_back(r.dot(p.e1), r.dot(p.e2));
    }
    pieces_.push_back(std::move(p));
  };

  for (const std::vector<int>& face : mesh::polygonFaces(cage)) {
    const std::size_t k = face.size();
    // Newell's normal and the corners' largest distance from their plane.
    Vec3 newell = Vec3::Zero(), centroid = Vec3::Zero();
    for (std::size_t i = 0; i < k; ++i) {
      const Vec3& a = vertices_[std::size_t(face[i])];
      newell += a.cross(vertices_[std::size_t(face[(i + 1) % k])]);
      centroid += a;
    }
    centroid /= double(k);
    const Vec3 n = newell.normalized();
    double size = 0.0, off = 0.0;
    for (const int c : face) {
      const Vec3 r = vertices_[std::size_t(c)] - centroid;
      size = std::max(size, r.norm());
      off = std::max(off, std::abs(n.dot(r)));
    }
    if (k == 3) {
      makePiece(face, n, 1.0);
    } else if (off <= kPlanarFaceTolerance * size) {
      ++planarFaces_;
      makePiece(face, n, 1.0);
    } else {
      // All k fan triangulations, each with share 1/k: symmetric in the corners.
      ++nonPlanarFaces_;
      for (std::size_t s = 0; s < k; ++s) {
        for (std::size_t j = 1; j + 1 < k; ++j) {
          const int a = face[s], b = face[(s + j) % k], c = face[(s + j + 1) % k];
          const Vec3 pa = vertices_[std::size_t(a)], pb = vertices_[std::size_t(b)],
                     pc = vertices_[std::size_t(c)];
          const Vec3 cross = (pb - pa).cross(pc - pa);
          const double longest =
              std::max({(pb - pa).squaredNorm(), (pc - pb).squaredNorm(), (pa - pc).squaredNorm()});
          // A zero-area fan triangle has a zero mean vector: leaving it out changes nothing.
          if (!(cross.norm() > 1e-12 * longest)) continue;
          makePiece({a, b, c}, cross.normalized(), 1.0 / double(k));
        }
      }
    }
  }
}

// The weights (before normalisation) of one planar piece for p, on its own: m = ½ Σ θ_e n_e
// over the piece's edges, q = where the ray p + t·m meets the plane, w_i = (n·m) b_i(q) / h.
// (For a triangle this is the unique split, the same as MeanValueCage's w_k.)
void PolygonMeanValueCage::pieceAlone(const Vec3& p, const Piece& f, double* out) const {
  const std::size_t k = f.corners.size();
  thread_local std::vector<Vec3> u;
  u.resize(k);
  for (std::size_t i = 0; i < k; ++i)
    u[i] = (vertices_[std::size_t(f.corners[i])] - p).normalized();
  Vec3 m = Vec3::Zero();
  for (std::size_t i = 0; i < k; ++i) {
    const Vec3 c = u[i].cross(u[(i + 1) % k]);
    const double s = c.norm();
    if (s > 0.0) m += (0.5 * std::atan2(s, u[i].dot(u[(i + 1) % k])) / s) * c;
  }
  const double h = f.normal.dot(f.origin - p);
  const double nm = f.normal.dot(m);
  const Vec3 q = p + (h / nm) * m - f.origin;
  planarMeanValue(Vec2(q.dot(f.e1), q.dot(f.e2)), f.corners2d, out);
  const double factor = nm / h;
  for (std::size_t i = 0; i < k; ++i) out[i] *= factor;
}

// Distance from p to the piece: along the normal over the face (accurate a hair off it), else
// to the closest point of its boundary (over the fan triangles of the piece).
double PolygonMeanValueCage::distanceToPiece(const Vec3& p, const Piece& f) const {
  double best = std::numeric_limits<double>::infinity();
  const Vec3& a = vertices_[std::size_t(f.corners[0])];
  for (std::size_t j = 1; j + 1 < f.corners.size(); ++j) {
    const Vec3& b = vertices_[std::size_t(f.corners[j])];
    const Vec3& c = vertices_[std::size_t(f.corners[j + 1])];
    const mesh::TrianglePoint<double> q = mesh::closestPointOnTriangle(p, a, b, c);
    if (q.feature == mesh::TriangleFeature::Face) return std::abs(f.normal.dot(a - p));
    const Vec3 closest = q.weights[0] * a + q.weights[1] * b + q.weights[2] * c;
    best = std::min(best, (p - closest).norm());
  }
  return best;
}

bool PolygonMeanValueCage::weights(const Vec3& x, double* w, Scratch& sc, MvcInfo* info) const {
  const int nv = vertexCount();
  const double onTol = kOnCageTolerance * diagonal_;
  if (info) {
    *info = MvcInfo{};
    info->distance = diagonal_ > 0.0 ? (x - centre_).norm() / diagonal_ : 0.0;
    info->far = info->distance > 4.0;
    if (info->far) info->errorEstimate = 1e-14 * std::pow(info->distance, 4.0);
  }
  sc.d.resize(std::size_t(nv));
  for (int j = 0; j < nv; ++j) {
    sc.d[std::size_t(j)] = (vertices_[std::size_t(j)] - x).norm();
    if (sc.d[std::size_t(j)] <= onTol) {
      std::fill(w, w + nv, 0.0);
      w[j] = 1.0;
      if (info) {
        info->kind = MvcCase::OnVertex;
        info->errorEstimate = 0.0;
      }
      return true;
    }
  }
  std::fill(w, w + nv, 0.0);
  double absSum = 0.0;
  thread_local std::vector<double> wt, wp, wm;
  for (const Piece& f : pieces_) {
    const std::size_t k = f.corners.size();
    wt.resize(k);
    const double h = f.normal.dot(f.origin - x);
    double dmin = std::numeric_limits<double>::infinity();
    for (const int c : f.corners) dmin = std::min(dmin, sc.d[std::size_t(c)]);
    if (std::abs(h) < kPlaneBand * dmin) {
      const double rho = distanceToPiece(x, f);
      if (rho <= onTol) {
        // On the cage: the face's planar mean value coordinates of the foot of x (barycentric
        // for a triangle, linear on an edge).
        const Vec3 foot = x + h * f.normal - f.origin;
        std::fill(w, w + nv, 0.0);
        planarMeanValue(Vec2(foot.dot(f.e1), foot.dot(f.e2)), f.corners2d, wt.data());
        for (std::size_t i = 0; i < k; ++i) w[f.corners[i]] += wt[i];
        if (info) {
          info->kind = MvcCase::OnSurface;
          info->errorEstimate = 1e-15;
        }
        return true;
      }
      if (std::abs(h) < kPlaneBand * rho) {
        // In (or a hair off) the plane, away from the face: the contribution is h·g(x) with g
        // smooth; evaluate g at heights ±δ and interpolate (as MeanValueCage does).
        const double delta =
            std::max(kPlaneBand * rho, 1e-12 * (diagonal_ + x.cwiseAbs().maxCoeff()));
        const Vec3 pp = x + (h - delta) * f.normal;
        const Vec3 pm = x + (h + delta) * f.normal;
        const double hp = f.normal.dot(f.origin - pp), hm = f.normal.dot(f.origin - pm);
        wp.resize(k);
        wm.resize(k);
        pieceAlone(pp, f, wp.data());
        pieceAlone(pm, f, wm.data());
        for (std::size_t i = 0; i < k; ++i) wt[i] = planeBandContribution(h, hp, hm, wp[i], wm[i]);
      } else {
        pieceAlone(x, f, wt.data());
      }
    } else {
      pieceAlone(x, f, wt.data());
    }
    for (std::size_t i = 0; i < k; ++i) {
      const double v = f.share * wt[i];
      w[f.corners[i]] += v;
      absSum += std::abs(v);
    }
  }
  double sum = 0.0;
  for (int j = 0; j < nv; ++j) sum += w[j];
  if (!(std::isfinite(sum) && sum != 0.0)) {
    std::fill(w, w + nv, std::numeric_limits<double>::quiet_NaN());
    if (info) info->conditioning = std::numeric_limits<double>::infinity();
    return false;
  }
  for (int j = 0; j < nv; ++j) w[j] /= sum;
  if (info) info->conditioning = absSum / std::abs(sum);
  return true;
}

}  // namespace sb::cage
