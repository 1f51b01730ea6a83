#include "sim/cage/green.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include "sim/base/parallel_for.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/closest_point.h"

namespace sb::cage {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInv4Pi = 1.0 / (4.0 * kPi);

std::string at(const Vec3& p) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

// What each triangle needs for every point, computed once per bind.
struct Face {
  int v[3];
  Vec3 n;         // unit outward normal
  double twiceA;  // 2 · area
  Vec3 m[3];      // outward in-plane normal of edge k (corners k → k+1): ê_k × n
  double len[3];  // length of edge k
  double maxLen;  // longest edge
};

struct PreparedCage {
  std::vector<Vec3> x;
  std::vector<Face> faces;
  double diagonal = 0.0;
};

PreparedCage prepare(const mesh::TriangleMesh& cage) {
  PreparedCage c;
  c.x = cage.vertices;
  Eigen::AlignedBox3d box;
  for (const Vec3& p : c.x) box.extend(p);
  c.diagonal = box.diagonal().norm();
  c.faces.reserve(cage.triangles.size());
  for (const auto& t : cage.triangles) {
    Face f;
    for (int k = 0; k < 3; ++k) f.v[k] = t[size_t(k)];
    const Vec3 &a = c.x[size_t(f.v[0])], &b = c.x[size_t(f.v[1])], &cc = c.x[size_t(f.v[2])];
    const Vec3 cr = (b - a).cross(cc - a);
    f.twiceA = cr.norm();
    f.n = cr / f.twiceA;  // validateClosedSurface refused zero-area triangles
    const Vec3* corner[3] = {&a, &b, &cc};
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = *corner[(k + 1) % 3] - *corner[k];
      f.len[k] = e.norm();
      f.m[k] = (e / f.len[k]).cross(f.n);
    }
    f.maxLen = std::max({f.len[0], f.len[1], f.len[2]});
    c.faces.push_back(f);
  }
  return c;
}

// ∫ 1/|ξ − η| ds along the segment from η + a to η + b (length len):
// ln((|a| + |b| + len) / (|a| + |b| − len)). The denominator is rewritten as
// 2(|a||b| + a·b) / (|a| + |b| + len), and |a||b| + a·b as |a×b|² / (|a||b| − a·b) when a·b < 0,
// so a point near the edge (a, b almost opposite) loses no digits to cancellation.
// |a||b| + a·b without cancellation (a, b almost opposite: a point near their segment).
double dotPlusLengths(const Vec3& a, const Vec3& b, double la, double lb) {
  const double ab = a.dot(b);
  return ab >= 0.0 ? la * lb + ab : a.cross(b).squaredNorm() / (la * lb - ab);
}

double edgeIntegral(const Vec3& a, const Vec3& b, double la, double lb, double len) {
  const double s = dotPlusLengths(a, b, la, lb);
  const double num = la + lb + len;
  return std::log(num * num / (2.0 * s));
}

// Adds point eta's coordinates to phi (V) and psi (F) (both zeroed by the caller); returns the
// winding number Σ Ω / 4π; *onCage is set when eta is within tol of a triangle.
double evaluate(const PreparedCage& c, const Vec3& eta, double* phi, double* psi, double tol,
                bool* onCage) {
  double winding = 0.0;
  *onCage = false;
  for (std::size_t j = 0; j < c.faces.size(); ++j) {
    const Face& f = c.faces[j];
    Vec3 a[3];
    double l[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = c.x[size_t(f.v[k])] - eta;
      l[k] = a[k].norm();
    }
    // Signed height of the plane above eta (> 0 when eta is on the inner side).
    const double h = f.n.dot(a[0]);
    if (std::abs(h) <= tol) {
      const auto cp = mesh::closestPointOnTriangle<double>(
          eta, c.x[size_t(f.v[0])], c.x[size_t(f.v[1])], c.x[size_t(f.v[2])]);
      const Vec3 q = cp.weights[0] * c.x[size_t(f.v[0])] + cp.weights[1] * c.x[size_t(f.v[1])] +
                     cp.weights[2] * c.x[size_t(f.v[2])];
      if ((q - eta).norm() <= tol) *onCage = true;
    }
    // Signed solid angle. Away from the plane: van Oosterom & Strackee, with the triple product
    // a0·(a1×a2) written as 2A·h (exact in sign). Near the plane (|h| < 1e-2 of the longest
    // edge) that denominator cancels when eta is near an edge, and the error does not cancel
    // against the face across the edge (measured: 6e-7 at 1e-11 from the diagonal of a flat
    // quad); there Ω is summed over the sub-triangles (foot of eta, corner k, corner k+1), whose
    // denominators |h|(l_k l_{k+1} + a_k·a_{k+1}) + h²(l_k + l_{k+1}) are sums of non-negative
    // terms and whose edge terms are exact negatives of those of a coplanar neighbour.
    // In-plane distance of eta's foot from edge k's line (> 0 on the triangle's side), from the
    // nearer endpoint: its difference from eta carries the smaller absolute rounding error.
    double dist[3];
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3;
      dist[k] = f.m[k].dot(l[k] <= l[k1] ? a[k] : a[k1]);
    }
    double omega;
    if (std::abs(h) >= 1e-2 * f.maxLen) {
      const double den = l[0] * l[1] * l[2] + a[0].dot(a[1]) * l[2] + a[0].dot(a[2]) * l[1] +
                         a[1].dot(a[2]) * l[0];
      omega = 2.0 * std::atan2(f.twiceA * h, den);
    } else {
      omega = 0.0;
      for (int k = 0; k < 3; ++k) {
        const int k1 = (k + 1) % 3;
        const double x =
            std::abs(h) * dotPlusLengths(a[k], a[k1], l[k], l[k1]) + h * h * (l[k] + l[k1]);
        omega += 2.0 * std::atan2(h * dist[k] * f.len[k], x);
      }
    }
    winding += omega;
    // ∫_t 1/|x| = Σ_e d_e L_e − h Ω (divergence theorem in the plane applied to x_∥/|x|), and
    // g = ∫_t x/|x|³ = Ω n − Σ_e m_e L_e (the normal part is the solid angle, the in-plane part
    // the divergence theorem applied to ∇(1/|x|)).
    double psiRaw = -h * omega;
    Vec3 g = omega * f.n;
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3;
      const double L = edgeIntegral(a[k], a[k1], l[k], l[k1], f.len[k]);
      psiRaw += dist[k] * L;
      g -= L * f.m[k];
    }
    psi[j] = kInv4Pi * psiRaw;
    // g = Σ_k b_k a_k with b_k = ∫ Γ_k / |x|³ (x = Σ Γ_k a_k on the triangle); the vertex term
    // ∫ Γ_k (x·n)/|x|³ = h b_k follows by Cramer's rule, det(a0, a1, a2) = 2A h cancelling h.
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = a[(k + 1) % 3];
      const Vec3& q = a[(k + 2) % 3];
      phi[f.v[k]] += kInv4Pi * g.dot(p.cross(q)) / f.twiceA;
    }
  }
  return winding * kInv4Pi;
}

}  // namespace

double greenCoordinates(const Vec3& eta, const mesh::TriangleMesh& cage, Eigen::VectorXd& phi,
                        Eigen::VectorXd& psi) {
  const PreparedCage c = prepare(cage);
  phi = Eigen::VectorXd::Zero(Eigen::Index(c.x.size()));
  psi = Eigen::VectorXd::Zero(Eigen::Index(c.faces.size()));
  bool onCage = false;
  return evaluate(c, eta, phi.data(), psi.data(), 0.0, &onCage);
}

Embedding bindGreen(const std::vector<Vec3>& points, const mesh::TriangleMesh& cage,
                    const GreenOptions& options) {
  mesh::validateClosedSurface(cage, "cage");
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite())
      throw std::invalid_argument("green: point " + std::to_string(i) + " is not finite");
  const auto t0 = std::chrono::steady_clock::now();
  const PreparedCage c = prepare(cage);
  const int V = int(c.x.size()), F = int(c.faces.size());
  const int count = int(points.size());
  const double tol = 1e-12 * c.diagonal;
  Embedding::DenseD W = Embedding::DenseD::Zero(count, V + F);
  std::vector<double> winding(size_t(count), 0.0);
  std::vector<char> onCage(size_t(count), 0);
  const int threads =
      options.threads > 0 ? std::min(options.threads, threadCount()) : threadCount();
  // Each row is computed alone, in face order: the result does not depend on the split.
  parallelRanges(count, 64, threads, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      double* row = W.row(i).data();  // row-major: φ then ψ, contiguous
      bool on = false;
      winding[size_t(i)] = evaluate(c, points[size_t(i)], row, row + V, tol, &on);
      onCage[size_t(i)] = on;
    }
  });
  for (int i = 0; i < count; ++i) {
    if (onCage[size_t(i)])
      throw std::invalid_argument("green: point " + std::to_string(i) + " " +
                                  at(points[size_t(i)]) +
                                  " is on the cage (Green coordinates are defined inside only)");
    if (!(winding[size_t(i)] > 0.5) || !W.row(i).allFinite())
      throw std::invalid_argument("green: point " + std::to_string(i) + " " +
                                  at(points[size_t(i)]) +
                                  " is outside the cage (Green coordinates are defined inside "
                                  "only; the exterior extension is not implemented)");
  }

  // Statistics before the move: Σφ and the rest-pose reproduction with the extended controls.
  BindStats st;
  st.minWeight = count ? W.minCoeff() : 0.0;
  st.maxWeight = count ? W.maxCoeff() : 0.0;
  st.negativeCount = (W.array() < 0.0).count();
  st.nonZeros = std::int64_t(count) * (V + F);
  Eigen::Matrix<double, Eigen::Dynamic, 3> rest(V, 3);
  for (int v = 0; v < V; ++v) rest.row(v) = c.x[size_t(v)].transpose();
  const Eigen::Matrix<double, Eigen::Dynamic, 3> controls = greenControls(cage, rest);
  for (int i = 0; i < count; ++i) {
    st.maxSumError = std::max(st.maxSumError, std::abs(W.row(i).head(V).sum() - 1.0));
    const Vec3 p = (W.row(i) * controls).transpose();
    st.maxLinearError = std::max(st.maxLinearError, (p - points[size_t(i)]).norm() / c.diagonal);
  }
  st.unprunedLinearError = st.maxLinearError;
  st.threads = threads;

  Embedding e = Embedding::fromDense(std::move(W), options.keepDoublePrecision);
  e.setKind(EmbeddingKind::Green);
  e.attachGreenCage(std::make_shared<const mesh::TriangleMesh>(cage));
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  e.stats() = st;
  return e;
}

Eigen::Matrix<double, Eigen::Dynamic, 3> greenControls(
    const mesh::TriangleMesh& restCage, const Eigen::Matrix<double, Eigen::Dynamic, 3>& deformed) {
  const int V = int(restCage.vertices.size()), F = int(restCage.triangles.size());
  if (deformed.rows() != V)
    throw std::invalid_argument("greenControls: " + std::to_string(deformed.rows()) +
                                " deformed vertices for a cage of " + std::to_string(V));
  Eigen::Matrix<double, Eigen::Dynamic, 3> out(V + F, 3);
  out.topRows(V) = deformed;
  for (int j = 0; j < F; ++j) {
    const auto& t = restCage.triangles[size_t(j)];
    for (int k = 0; k < 3; ++k)
      if (t[size_t(k)] < 0 || t[size_t(k)] >= V)
        throw std::invalid_argument("greenControls: triangle " + std::to_string(j) +
                                    " has a vertex index out of range");
    const Vec3 &a = restCage.vertices[size_t(t[0])], &b = restCage.vertices[size_t(t[1])],
               &cc = restCage.vertices[size_t(t[2])];
    const Vec3 a2 = deformed.row(t[0]).transpose(), b2 = deformed.row(t[1]).transpose(),
               c2 = deformed.row(t[2]).transpose();
    const Vec3 u = b - a, v = cc - a, u2 = b2 - a2, v2 = c2 - a2;
    const Vec3 cr = u2.cross(v2);
    const double cn = cr.norm();
    // A deformed triangle crushed to a line or a point has no normal: its face term is left
    // out (a simulated cage can pass through such a pose; the map stays finite there).
    if (!(cn > 0.0)) {
      out.row(V + j).setZero();
      continue;
    }
    const double area = 0.5 * u.cross(v).norm();
    // The paper's 3-D stretch: 1 at rest, k under a uniform scale by k.
    const double q = u2.squaredNorm() * v.squaredNorm() - 2.0 * u2.dot(v2) * u.dot(v) +
                     v2.squaredNorm() * u.squaredNorm();
    const double s = std::sqrt(std::max(q, 0.0)) / (std::sqrt(8.0) * area);
    out.row(V + j) = (s / cn) * cr.transpose();
  }
  return out;
}

}  // namespace sb::cage
