#include "sim/cage/mvc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Geometry>

namespace sb::cage {

namespace {
using Vec3 = Eigen::Vector3d;
}

double closestPointBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               std::array<double, 3>& bary) {
  // Ericson, Real-Time Collision Detection, 5.1.5 (Voronoi regions of the triangle).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    bary = {1.0, 0.0, 0.0};
    return ap.norm();
  }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    bary = {0.0, 1.0, 0.0};
    return bp.norm();
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    bary = {1.0 - v, v, 0.0};
    return (p - (a + v * ab)).norm();
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    bary = {0.0, 0.0, 1.0};
    return cp.norm();
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    bary = {1.0 - w, 0.0, w};
    return (p - (a + w * ac)).norm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0.0, 1.0 - w, w};
    return (p - (b + w * (c - b))).norm();
  }
  // Inside the face region: barycentrics from the sub-triangle areas, computed with cross
  // products (accurate for points near the face, unlike the dot-product form).
  const Vec3 n = ab.cross(ac);
  const double nn = n.dot(n);
  const double wa = (b - p).cross(c - p).dot(n) / nn;
  const double wb = (c - p).cross(a - p).dot(n) / nn;
  const double wc = 1.0 - wa - wb;
  bary = {wa, wb, wc};
  const double h = std::abs(ap.dot(n)) / std::sqrt(nn);
  return h;
}

MeanValueCage::MeanValueCage(const TriangleMesh& cage) {
  const std::size_t nv = cage.vertices.size();
  vx_.resize(nv);
  vy_.resize(nv);
  vz_.resize(nv);
  Eigen::AlignedBox3d box;
  for (std::size_t i = 0; i < nv; ++i) {
    vx_[i] = cage.vertices[i].x();
    vy_[i] = cage.vertices[i].y();
    vz_[i] = cage.vertices[i].z();
    box.extend(cage.vertices[i]);
  }
  diagonal_ = nv ? box.diagonal().norm() : 0.0;
  centre_ = nv ? Vec3(box.center()) : Vec3::Zero();

  std::map<std::pair<int, int>, int> edgeIndex;
  tris_.reserve(cage.triangles.size());
  for (const auto& t : cage.triangles) {
    Tri tri;
    tri.v = t;
    for (int k = 0; k < 3; ++k) {
      const int a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = edgeIndex.find(key);
      if (it == edgeIndex.end()) {
        it = edgeIndex.emplace(key, static_cast<int>(edges_.size())).first;
        edges_.push_back({key.first, key.second});
      }
      tri.e[k] = it->second;
      tri.sign[k] = (a == key.first) ? 1.0 : -1.0;
    }
    const Vec3 p0 = cage.vertices[t[0]], p1 = cage.vertices[t[1]], p2 = cage.vertices[t[2]];
    const Vec3 n = (p1 - p0).cross(p2 - p0);
    tri.twiceArea = n.norm();
    tri.normal = tri.twiceArea > 0.0 ? Vec3(n / tri.twiceArea) : Vec3::Zero();
    tris_.push_back(tri);
  }
}

// The weights (before normalisation) of one triangle for point p, computed on their own:
// w_k = (m · c_k) / (det · d_k), m = ½ Σ θ_k n_k (integral of the unit normal over the
// spherical triangle), c_k = u_{k+1} × u_{k+2}, det = u_0 · (u_1 × u_2) = h · 2A / (d0 d1 d2).
void MeanValueCage::triangleAlone(const Vec3& p, const Tri& t, double out[3]) const {
  Vec3 u[3];
  double d[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3 r = vertex(t.v[k]) - p;
    d[k] = r.norm();
    u[k] = r / d[k];
  }
  Vec3 c[3], m = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    c[k] = u[(k + 1) % 3].cross(u[(k + 2) % 3]);
    const double s = c[k].norm();
    const double theta = std::atan2(s, u[(k + 1) % 3].dot(u[(k + 2) % 3]));
    if (s > 0.0) m += (0.5 * theta / s) * c[k];
  }
  const double h = t.normal.dot(vertex(t.v[0]) - p);
  const double det = h * t.twiceArea / (d[0] * d[1] * d[2]);
  for (int k = 0; k < 3; ++k) out[k] = m.dot(c[k]) / (det * d[k]);
}

bool MeanValueCage::weights(const Vec3& x, double* w, Scratch& sc, MvcInfo* info) const {
  const int nv = vertexCount();
  const int ne = static_cast<int>(edges_.size());
  const double onTol = kOnCageTolerance * diagonal_;
  if (info) {
    *info = MvcInfo{};
    info->distance = diagonal_ > 0.0 ? (x - centre_).norm() / diagonal_ : 0.0;
    info->far = info->distance > 4.0;
    if (info->far) info->errorEstimate = 1e-14 * std::pow(info->distance, 4.0);
  }
  sc.ux.resize(nv);
  sc.uy.resize(nv);
  sc.uz.resize(nv);
  sc.invd.resize(nv);
  sc.d.resize(nv);
  sc.theta.resize(ne);
  sc.s.resize(ne);
  sc.nx.resize(ne);
  sc.ny.resize(ne);
  sc.nz.resize(ne);
  double* ux = sc.ux.data();
  double* uy = sc.uy.data();
  double* uz = sc.uz.data();
  double* invd = sc.invd.data();
  double* dd = sc.d.data();

  // 1. Unit directions to the vertices; on a vertex the weights are that vertex's.
  for (int j = 0; j < nv; ++j) {
    const double rx = vx_[j] - x.x(), ry = vy_[j] - x.y(), rz = vz_[j] - x.z();
    const double d = std::sqrt(rx * rx + ry * ry + rz * rz);
    if (d <= onTol) {
      std::fill(w, w + nv, 0.0);
      w[j] = 1.0;
      if (info) {
        info->kind = MvcCase::OnVertex;
        info->errorEstimate = 0.0;
      }
      return true;
    }
    const double id = 1.0 / d;
    ux[j] = rx * id;
    uy[j] = ry * id;
    uz[j] = rz * id;
    invd[j] = id;
    dd[j] = d;
  }

  // 2. Per edge: arc angle θ (atan2 of |u_a × u_b| and u_a · u_b, accurate at 0 and π) and
  // the unit normal of the plane through x and the edge (zero if undefined, then θ·n = 0 or
  // x lies on the edge and step 3 reports it).
  double* th = sc.theta.data();
  double* ss = sc.s.data();
  double* nx = sc.nx.data();
  double* ny = sc.ny.data();
  double* nz = sc.nz.data();
  for (int e = 0; e < ne; ++e) {
    const int a = edges_[e][0], b = edges_[e][1];
    const double cx = uy[a] * uz[b] - uz[a] * uy[b];
    const double cy = uz[a] * ux[b] - ux[a] * uz[b];
    const double cz = ux[a] * uy[b] - uy[a] * ux[b];
    const double s = std::sqrt(cx * cx + cy * cy + cz * cz);
    const double c = ux[a] * ux[b] + uy[a] * uy[b] + uz[a] * uz[b];
    th[e] = std::atan2(s, c);
    ss[e] = s;
    const double is = s > 0.0 ? 1.0 / s : 0.0;
    nx[e] = cx * is;
    ny[e] = cy * is;
    nz[e] = cz * is;
  }

  // 3. Per triangle: w_k = (m · c_k) / (det · d_k).
  std::fill(w, w + nv, 0.0);
  double absSum = 0.0;
  for (const Tri& t : tris_) {
    const int i0 = t.v[0], i1 = t.v[1], i2 = t.v[2];
    const double rx = vx_[i0] - x.x(), ry = vy_[i0] - x.y(), rz = vz_[i0] - x.z();
    const double h = t.normal.x() * rx + t.normal.y() * ry + t.normal.z() * rz;
    const double dmin = std::min(dd[i0], std::min(dd[i1], dd[i2]));
    if (std::abs(h) < kPlaneBand * dmin) {
      // x is close to the plane of this triangle relative to its distance from the vertices.
      std::array<double, 3> bary;
      const Vec3 p0 = vertex(i0), p1 = vertex(i1), p2 = vertex(i2);
      const double rho = closestPointBarycentric(x, p0, p1, p2, bary);
      if (rho <= onTol) {
        // On the cage: the weights are the triangle's barycentric coordinates.
        std::fill(w, w + nv, 0.0);
        w[i0] = bary[0];
        w[i1] = bary[1];
        w[i2] = bary[2];
        if (info) {
          info->kind = MvcCase::OnSurface;
          info->errorEstimate = 1e-15;
        }
        return true;
      }
      if (std::abs(h) < kPlaneBand * rho) {
        // In (or a hair off) the plane of the triangle, away from it. The contribution is
        // h · g(x) with g smooth there (it vanishes in the plane); the closed form is 0/0.
        // Evaluate g at heights ±δ, δ = kPlaneBand·ρ, where the closed form is accurate,
        // and interpolate g to the height h (error O(δ³/ρ³) relative).
        const double delta = kPlaneBand * rho;
        const Vec3 pp = x + (h - delta) * t.normal;  // height (v0 - p)·n = +δ
        const Vec3 pm = x + (h + delta) * t.normal;  // height -δ
        const double hp = t.normal.dot(p0 - pp), hm = t.normal.dot(p0 - pm);
        double wp[3], wm[3];
        triangleAlone(pp, t, wp);
        triangleAlone(pm, t, wm);
        for (int k = 0; k < 3; ++k) {
          const double gp = wp[k] / hp, gm = wm[k] / hm;
          const double g = 0.5 * (gp + gm) + (h - 0.5 * (hp + hm)) * (gp - gm) / (hp - hm);
          const double wk = h * g;
          w[t.v[k]] += wk;
          absSum += std::abs(wk);
        }
        continue;
      }
    }
    const double det = h * t.twiceArea * invd[i0] * invd[i1] * invd[i2];
    double mx = 0.0, my = 0.0, mz = 0.0;
    double cxk[3], cyk[3], czk[3];
    for (int k = 0; k < 3; ++k) {
      const int e = t.e[k];
      const double sg = t.sign[k];
      const double f = 0.5 * th[e] * sg;
      mx += f * nx[e];
      my += f * ny[e];
      mz += f * nz[e];
      const double sc2 = sg * ss[e];
      cxk[k] = sc2 * nx[e];
      cyk[k] = sc2 * ny[e];
      czk[k] = sc2 * nz[e];
    }
    const double idet = 1.0 / det;
    for (int k = 0; k < 3; ++k) {
      const double wk = (mx * cxk[k] + my * cyk[k] + mz * czk[k]) * idet * invd[t.v[k]];
      w[t.v[k]] += wk;
      absSum += std::abs(wk);
    }
  }

  double sum = 0.0;
  for (int j = 0; j < nv; ++j) sum += w[j];
  if (!(std::isfinite(sum) && sum != 0.0)) {
    std::fill(w, w + nv, std::numeric_limits<double>::quiet_NaN());
    if (info) info->conditioning = std::numeric_limits<double>::infinity();
    return false;
  }
  const double inv = 1.0 / sum;
  for (int j = 0; j < nv; ++j) w[j] *= inv;
  if (info) info->conditioning = absSum / std::abs(sum);
  return true;
}

bool mvcWeights(const Vec3& x, const TriangleMesh& cage, double* w, MvcInfo* info) {
  const MeanValueCage prepared(cage);
  MeanValueCage::Scratch scratch;
  return prepared.weights(x, w, scratch, info);
}

}  // namespace sb::cage
