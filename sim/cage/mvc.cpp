#include "sim/cage/mvc.h"

#include "sim/mesh/closed_surface.h"
#include "sim/mesh/closest_point.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace sb::cage {

using mesh::TriangleMesh;

namespace {
using Vec3 = Eigen::Vector3d;

// atan of t in [0, 1] reduced around the anchors tan(jπ/16), j = 0..4, then an odd Taylor
// series on |z| ≤ tan(π/32) ≈ 0.0985 (8 terms: truncation below 1e-17 relative). Branch-free
// (selects only) so the edge loop vectorises; accurate to a few ulp.
struct AtanTable {
  double anchor[5], base[5], split[4];
  AtanTable() {
    for (int j = 0; j < 5; ++j) {
      anchor[j] = std::tan(j * M_PI / 16.0);
      base[j] = std::atan(anchor[j]);
    }
    for (int j = 0; j < 4; ++j) split[j] = std::tan((2 * j + 1) * M_PI / 32.0);
  }
};
const AtanTable kAtan;

// θ = atan2(s, c) for s ≥ 0 (θ in [0, π]).
inline double angleOf(double s, double c) {
  const double ac = std::abs(c);
  const double lo = s < ac ? s : ac;
  const double hi = s < ac ? ac : s;
  const double t = lo / (hi > 0.0 ? hi : 1.0);  // hi = 0 implies lo = 0
  const AtanTable& T = kAtan;
  const double a = t > T.split[3]   ? T.anchor[4]
                   : t > T.split[2] ? T.anchor[3]
                   : t > T.split[1] ? T.anchor[2]
                   : t > T.split[0] ? T.anchor[1]
                                    : 0.0;
  const double b = t > T.split[3]   ? T.base[4]
                   : t > T.split[2] ? T.base[3]
                   : t > T.split[1] ? T.base[2]
                   : t > T.split[0] ? T.base[1]
                                    : 0.0;
  const double z = (t - a) / (1.0 + t * a);
  const double z2 = z * z;
  double p = -1.0 / 15.0;
  p = p * z2 + 1.0 / 13.0;
  p = p * z2 - 1.0 / 11.0;
  p = p * z2 + 1.0 / 9.0;
  p = p * z2 - 1.0 / 7.0;
  p = p * z2 + 1.0 / 5.0;
  p = p * z2 - 1.0 / 3.0;
  const double r0 = b + (z + z * z2 * p);  // atan(t) in [0, π/4]
  const double r1 = s > ac ? M_PI_2 - r0 : r0;
  return c < 0.0 ? M_PI - r1 : r1;
}
}  // namespace

namespace {

// Distance from p to the closest point q of triangle (a, b, c): measured along the face normal in
// the face region (accurate a hair off the face), else from the point on the edge or vertex.
double distanceToTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                          const mesh::TrianglePoint<double>& q) {
  switch (q.feature) {
    case mesh::TriangleFeature::Face: {
      const Vec3 n = (b - a).cross(c - a);
      return std::abs((p - a).dot(n)) / n.norm();
    }
    case mesh::TriangleFeature::Edge0:
      return (p - (a + q.weights[1] * (b - a))).norm();
    case mesh::TriangleFeature::Edge1:
      return (p - (b + q.weights[2] * (c - b))).norm();
    case mesh::TriangleFeature::Edge2:
      return (p - (a + q.weights[2] * (c - a))).norm();
    case mesh::TriangleFeature::Vertex0:
      return (p - a).norm();
    case mesh::TriangleFeature::Vertex1:
      return (p - b).norm();
    case mesh::TriangleFeature::Vertex2:
      return (p - c).norm();
  }
  return (p - a).norm();
}

}  // namespace

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

  // Edges from the shared adjacency (one undirected edge per pair of triangles).
  const mesh::SurfaceTopology topology =
      mesh::buildSurfaceTopology(cage.triangles, static_cast<int>(nv));
  edges_ = topology.edges;
  tris_.reserve(cage.triangles.size());
  for (std::size_t ti = 0; ti < cage.triangles.size(); ++ti) {
    const auto& t = cage.triangles[ti];
    Tri tri;
    tri.v = t;
    for (int k = 0; k < 3; ++k) {
      // The edge opposite corner k runs from corner k+1 to k+2: the topology's edge k+1.
      const int a = t[(k + 1) % 3];
      tri.e[k] = topology.triangleEdges[ti][(k + 1) % 3];
      tri.sign[k] = (a == edges_[tri.e[k]][0]) ? 1.0 : -1.0;
    }
    const Vec3 p0 = cage.vertices[t[0]], p1 = cage.vertices[t[1]], p2 = cage.vertices[t[2]];
    const Vec3 n = (p1 - p0).cross(p2 - p0);
    tri.twiceArea = n.norm();
    tri.normal = tri.twiceArea > 0.0 ? Vec3(n / tri.twiceArea) : Vec3::Zero();
    tris_.push_back(tri);
    tv0_.push_back(t[0]);
    tv1_.push_back(t[1]);
    tv2_.push_back(t[2]);
    te0_.push_back(tri.e[0]);
    te1_.push_back(tri.e[1]);
    te2_.push_back(tri.e[2]);
    ts0_.push_back(tri.sign[0]);
    ts1_.push_back(tri.sign[1]);
    ts2_.push_back(tri.sign[2]);
    tnx_.push_back(tri.normal.x());
    tny_.push_back(tri.normal.y());
    tnz_.push_back(tri.normal.z());
    tarea_.push_back(tri.twiceArea);
  }
  for (const auto& e : edges_) {
    ea_.push_back(e[0]);
    eb_.push_back(e[1]);
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

// The three passes below are plain loops over arrays, compiled for AVX2 and for the baseline
// (picked at load time); without FMA contraction both give bit-identical results.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define SB_CAGE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define SB_CAGE_CLONES
#endif

namespace {

// Unit directions u_j = (v_j − x)/d_j and distances.
SB_CAGE_CLONES void vertexPass(int nv, const double* vx, const double* vy, const double* vz,
                               double x, double y, double z, double* ux, double* uy, double* uz,
                               double* invd, double* dd) {
#pragma omp simd
  for (int j = 0; j < nv; ++j) {
    const double rx = vx[j] - x, ry = vy[j] - y, rz = vz[j] - z;
    const double d = std::sqrt(rx * rx + ry * ry + rz * rz);
    const double id = 1.0 / d;
    ux[j] = rx * id;
    uy[j] = ry * id;
    uz[j] = rz * id;
    invd[j] = id;
    dd[j] = d;
  }
}

// Per edge: arc angle θ (accurate at 0 and π) and the unit normal of the plane through x and
// the edge (zero if undefined: then θ·n = 0, or x is on the edge and is caught later).
SB_CAGE_CLONES void edgePass(int ne, const int* ea, const int* eb, const double* ux,
                             const double* uy, const double* uz, double* th, double* ss, double* nx,
                             double* ny, double* nz) {
#pragma omp simd
  for (int e = 0; e < ne; ++e) {
    const int a = ea[e], b = eb[e];
    const double cx = uy[a] * uz[b] - uz[a] * uy[b];
    const double cy = uz[a] * ux[b] - ux[a] * uz[b];
    const double cz = ux[a] * uy[b] - uy[a] * ux[b];
    const double s = std::sqrt(cx * cx + cy * cy + cz * cz);
    const double c = ux[a] * ux[b] + uy[a] * uy[b] + uz[a] * uz[b];
    th[e] = angleOf(s, c);
    ss[e] = s;
    const double is = 1.0 / (s > 0.0 ? s : 1.0);  // s = 0: the cross product is 0 as well
    nx[e] = cx * is;
    ny[e] = cy * is;
    nz[e] = cz * is;
  }
}

struct TriArrays {
  const int *v0, *v1, *v2, *e0, *e1, *e2;
  const double *s0, *s1, *s2, *nx, *ny, *nz, *area;
};
struct PointArrays {
  const double *vx, *vy, *vz, *d, *invd, *th, *ss, *enx, *eny, *enz;
};

// Per triangle: w_k = (m · c_k) / (det · d_k) with m = ½ Σ θ_k n_k, c_k = u_{k+1} × u_{k+2}
// = sign·s_e·n_e and det = h · 2A / (d0 d1 d2) (h from the face normal: accurate near the face).
// Flags the triangles whose plane passes within kPlaneBand·(distance to its vertices) of x.
SB_CAGE_CLONES void trianglePass(int nt, TriArrays T, PointArrays P, double x, double y, double z,
                                 double band, double* w0, double* w1, double* w2, int* flag) {
#pragma omp simd
  for (int t = 0; t < nt; ++t) {
    const int i0 = T.v0[t], i1 = T.v1[t], i2 = T.v2[t];
    const double h = T.nx[t] * (P.vx[i0] - x) + T.ny[t] * (P.vy[i0] - y) + T.nz[t] * (P.vz[i0] - z);
    const double d0 = P.d[i0], d1 = P.d[i1], d2 = P.d[i2];
    const double dmin = d0 < d1 ? (d0 < d2 ? d0 : d2) : (d1 < d2 ? d1 : d2);
    flag[t] = std::abs(h) < band * dmin ? 1 : 0;
    const double det = h * T.area[t] * P.invd[i0] * P.invd[i1] * P.invd[i2];
    const int e0 = T.e0[t], e1 = T.e1[t], e2 = T.e2[t];
    const double f0 = 0.5 * P.th[e0] * T.s0[t], f1 = 0.5 * P.th[e1] * T.s1[t],
                 f2 = 0.5 * P.th[e2] * T.s2[t];
    const double mx = f0 * P.enx[e0] + f1 * P.enx[e1] + f2 * P.enx[e2];
    const double my = f0 * P.eny[e0] + f1 * P.eny[e1] + f2 * P.eny[e2];
    const double mz = f0 * P.enz[e0] + f1 * P.enz[e1] + f2 * P.enz[e2];
    const double g0 = T.s0[t] * P.ss[e0], g1 = T.s1[t] * P.ss[e1], g2 = T.s2[t] * P.ss[e2];
    const double q0 = g0 * (mx * P.enx[e0] + my * P.eny[e0] + mz * P.enz[e0]);
    const double q1 = g1 * (mx * P.enx[e1] + my * P.eny[e1] + mz * P.enz[e1]);
    const double q2 = g2 * (mx * P.enx[e2] + my * P.eny[e2] + mz * P.enz[e2]);
    const double idet = 1.0 / (det != 0.0 ? det : 1.0);  // det = 0 only if flagged (h = 0)
    w0[t] = q0 * idet * P.invd[i0];
    w1[t] = q1 * idet * P.invd[i1];
    w2[t] = q2 * idet * P.invd[i2];
  }
}

}  // namespace

bool MeanValueCage::weights(const Vec3& x, double* w, Scratch& sc, MvcInfo* info) const {
  const int nv = vertexCount();
  const int ne = static_cast<int>(edges_.size());
  const int nt = static_cast<int>(tris_.size());
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
  sc.w0.resize(nt);
  sc.w1.resize(nt);
  sc.w2.resize(nt);
  sc.nearPlane.resize(nt);

  // 1. Unit directions to the vertices; on a vertex the weights are that vertex's.
  vertexPass(nv, vx_.data(), vy_.data(), vz_.data(), x.x(), x.y(), x.z(), sc.ux.data(),
             sc.uy.data(), sc.uz.data(), sc.invd.data(), sc.d.data());
  for (int j = 0; j < nv; ++j) {
    if (sc.d[j] <= onTol) {
      std::fill(w, w + nv, 0.0);
      w[j] = 1.0;
      if (info) {
        info->kind = MvcCase::OnVertex;
        info->errorEstimate = 0.0;
      }
      return true;
    }
  }

  // 2. Edges.
  edgePass(ne, ea_.data(), eb_.data(), sc.ux.data(), sc.uy.data(), sc.uz.data(), sc.theta.data(),
           sc.s.data(), sc.nx.data(), sc.ny.data(), sc.nz.data());

  // 3. Triangles.
  const TriArrays T{tv0_.data(), tv1_.data(), tv2_.data(),  te0_.data(), te1_.data(),
                    te2_.data(), ts0_.data(), ts1_.data(),  ts2_.data(), tnx_.data(),
                    tny_.data(), tnz_.data(), tarea_.data()};
  const PointArrays P{vx_.data(),      vy_.data(),  vz_.data(),   sc.d.data(),  sc.invd.data(),
                      sc.theta.data(), sc.s.data(), sc.nx.data(), sc.ny.data(), sc.nz.data()};
  trianglePass(nt, T, P, x.x(), x.y(), x.z(), kPlaneBand, sc.w0.data(), sc.w1.data(), sc.w2.data(),
               sc.nearPlane.data());

  // 4. Accumulate; triangles whose plane passes close to x take the careful path.
  std::fill(w, w + nv, 0.0);
  double absSum = 0.0;
  for (int ti = 0; ti < nt; ++ti) {
    const Tri& t = tris_[ti];
    double wt[3] = {sc.w0[ti], sc.w1[ti], sc.w2[ti]};
    if (sc.nearPlane[ti]) {
      const Vec3 p0 = vertex(t.v[0]), p1 = vertex(t.v[1]), p2 = vertex(t.v[2]);
      const double h = t.normal.dot(p0 - x);
      const mesh::TrianglePoint<double> closest = mesh::closestPointOnTriangle(x, p0, p1, p2);
      const Vec3& bary = closest.weights;
      const double rho = distanceToTriangle(x, p0, p1, p2, closest);
      if (rho <= onTol) {
        // On the cage: the weights are the triangle's barycentric coordinates.
        std::fill(w, w + nv, 0.0);
        w[t.v[0]] += bary[0];
        w[t.v[1]] += bary[1];
        w[t.v[2]] += bary[2];
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
        // δ is kept above the rounding level of the coordinates (x within ~1e-9 of the cage).
        const double delta =
            std::max(kPlaneBand * rho, 1e-12 * (diagonal_ + x.cwiseAbs().maxCoeff()));
        const Vec3 pp = x + (h - delta) * t.normal;  // height (v0 - p)·n = +δ
        const Vec3 pm = x + (h + delta) * t.normal;  // height -δ
        const double hp = t.normal.dot(p0 - pp), hm = t.normal.dot(p0 - pm);
        double wp[3], wm[3];
        triangleAlone(pp, t, wp);
        triangleAlone(pm, t, wm);
        for (int k = 0; k < 3; ++k) wt[k] = planeBandContribution(h, hp, hm, wp[k], wm[k]);
      }
      // else: close to the plane but over (or near) the face: the closed form is accurate.
    }
    for (int k = 0; k < 3; ++k) {
      w[t.v[k]] += wt[k];
      absSum += std::abs(wt[k]);
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
