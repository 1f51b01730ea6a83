#include "sim/cage/ffd_lattice.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace sb::cage {

namespace {

using Vec3 = Eigen::Vector3d;

// Bernstein lattices are dense and of degree N − 1: beyond 32 nodes per axis the weight matrix
// is enormous and a B-spline lattice is the tool, so larger counts are refused.
constexpr int kMaxBernsteinNodes = 32;
// Nodes in one lattice at most (the flat index is an int).
constexpr std::int64_t kMaxNodes = std::int64_t(1) << 24;
// A point this far outside the box (relative to its size) is taken as on the box: the box of
// ffdLatticeAround(margin 0) is the bounding box up to the rounding of origin + size.
constexpr double kBoxTolerance = 1e-12;

std::string str(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string str(const Vec3& v) {
  return "(" + str(v.x()) + ", " + str(v.y()) + ", " + str(v.z()) + ")";
}

const char* axisName(int a) {
  return a == 0 ? "x" : a == 1 ? "y" : "z";
}

// Basis functions of one axis at one coordinate: count values (and d/dx) for the nodes
// first .. first + count − 1.
struct AxisBasis {
  int first = 0;
  int count = 0;
  double t = 0.0;     // local parameter in [0, 1] (span for BSpline, box for Bernstein)
  double dtdx = 0.0;  // 1/h or 1/size
  std::array<double, kMaxBernsteinNodes> v{};
  std::array<double, kMaxBernsteinNodes> d{};  // d/dx (already scaled by dtdx)
};

// The point's per-axis local parameters; throws when outside the box. index < 0: single point
// (no index in the message).
void axisParameters(const FfdLattice& L, const Vec3& p, std::int64_t index,
                    std::array<AxisBasis, 3>& ax) {
  if (!p.allFinite()) {
    throw std::invalid_argument((index >= 0 ? "point " + std::to_string(index) + " " : "point ") +
                                str(p) + " is not finite");
  }
  for (int a = 0; a < 3; ++a) {
    double u = (p[a] - L.origin[a]) / L.size[a];  // in [0, 1] inside the box
    if (u < -kBoxTolerance || u > 1.0 + kBoxTolerance) {
      throw std::invalid_argument((index >= 0 ? "point " + std::to_string(index) + " " : "point ") +
                                  str(p) + " is outside the lattice box [" + str(L.origin) + ", " +
                                  str(L.origin + L.size) + "] on axis " + axisName(a) + " (" +
                                  str(p[a]) + " not in [" + str(L.origin[a]) + ", " +
                                  str(L.origin[a] + L.size[a]) + "])");
    }
    u = std::clamp(u, 0.0, 1.0);
    AxisBasis& b = ax[a];
    const int n = L.nodes[a];
    if (L.basis == FfdBasis::BSpline) {
      const int spans = n - 3;
      const double us = u * spans;
      const int s = std::min(static_cast<int>(std::floor(us)), spans - 1);
      b.first = s;
      b.count = 4;
      b.t = us - s;
      b.dtdx = spans / L.size[a];
    } else {
      b.first = 0;
      b.count = n;
      b.t = u;
      b.dtdx = 1.0 / L.size[a];
    }
  }
}

void evaluateAxes(const FfdLattice& L, std::array<AxisBasis, 3>& ax, bool derivatives) {
  for (int a = 0; a < 3; ++a) {
    AxisBasis& b = ax[a];
    if (L.basis == FfdBasis::BSpline) {
      ffdCubicBSplineBasis(b.t, b.v.data(), derivatives ? b.d.data() : nullptr);
    } else {
      ffdBernsteinBasis(b.count - 1, b.t, b.v.data(), derivatives ? b.d.data() : nullptr);
    }
    if (derivatives)
      for (int i = 0; i < b.count; ++i) b.d[i] *= b.dtdx;
  }
}

void checkNodes(const FfdLattice& L, const FfdNodes& nodes) {
  if (nodes.rows() != L.nodeCount()) {
    throw std::invalid_argument("nodes: " + std::to_string(nodes.rows()) + " rows, the " +
                                std::to_string(L.nodes[0]) + "×" + std::to_string(L.nodes[1]) +
                                "×" + std::to_string(L.nodes[2]) + " lattice has " +
                                std::to_string(L.nodeCount()) + " nodes");
  }
  for (Eigen::Index r = 0; r < nodes.rows(); ++r) {
    if (!nodes.row(r).allFinite()) {
      throw std::invalid_argument("nodes: node " + std::to_string(r) + " " +
                                  str(Vec3(nodes.row(r).transpose())) + " is not finite");
    }
  }
}

// de Boor's algorithm on the 4 control values of one uniform cubic span (knots ..., −2, −1, 0,
// 1, 2, 3 relative to the span [0, 1]): three rounds of blends, α = (t + 3 − j) / (4 − r).
Vec3 deBoorSpan(Vec3 d[4], double t) {
  for (int r = 1; r <= 3; ++r) {
    for (int j = 3; j >= r; --j) {
      const double alpha = (t + 3.0 - j) / (4.0 - r);
      d[j] = (1.0 - alpha) * d[j - 1] + alpha * d[j];
    }
  }
  return d[3];
}

// de Casteljau's algorithm on n control values (the Bézier case of de Boor's).
Vec3 deCasteljau(Vec3* d, int n, double t) {
  for (int r = 1; r < n; ++r)
    for (int j = 0; j < n - r; ++j) d[j] = (1.0 - t) * d[j] + t * d[j + 1];
  return d[0];
}

Vec3 evaluateRecursive(const FfdLattice& L, const FfdNodes& nodes, const Vec3& p,
                       std::int64_t index) {
  std::array<AxisBasis, 3> ax;
  axisParameters(L, p, index, ax);
  const int cx = ax[0].count, cy = ax[1].count, cz = ax[2].count;
  std::array<Vec3, kMaxBernsteinNodes> row, col, dep;
  for (int k = 0; k < cz; ++k) {
    for (int j = 0; j < cy; ++j) {
      for (int i = 0; i < cx; ++i)
        row[i] =
            nodes.row(L.nodeIndex(ax[0].first + i, ax[1].first + j, ax[2].first + k)).transpose();
      col[j] = L.basis == FfdBasis::BSpline ? deBoorSpan(row.data(), ax[0].t)
                                            : deCasteljau(row.data(), cx, ax[0].t);
    }
    dep[k] = L.basis == FfdBasis::BSpline ? deBoorSpan(col.data(), ax[1].t)
                                          : deCasteljau(col.data(), cy, ax[1].t);
  }
  return L.basis == FfdBasis::BSpline ? deBoorSpan(dep.data(), ax[2].t)
                                      : deCasteljau(dep.data(), cz, ax[2].t);
}

// Weights of one point with the axis bases already evaluated, ascending node index.
template <class Fn>
void forEachWeight(const FfdLattice& L, const std::array<AxisBasis, 3>& ax, Fn&& fn) {
  for (int k = 0; k < ax[2].count; ++k) {
    for (int j = 0; j < ax[1].count; ++j) {
      const double wjk = ax[1].v[j] * ax[2].v[k];
      const int base = L.nodeIndex(ax[0].first, ax[1].first + j, ax[2].first + k);
      for (int i = 0; i < ax[0].count; ++i) fn(base + i, ax[0].v[i] * wjk);
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

void FfdLattice::validate() const {
  if (!origin.allFinite()) throw std::invalid_argument("origin: " + str(origin) + " is not finite");
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(size[a]) || !(size[a] > 0.0)) {
      throw std::invalid_argument("size: " + str(size) + " must be finite and > 0 on every axis (" +
                                  axisName(a) + " is " + str(size[a]) + ")");
    }
    if (!std::isfinite(origin[a] + size[a])) {
      throw std::invalid_argument("origin + size: the box " + str(origin) + " + " + str(size) +
                                  " overflows");
    }
  }
  const int minNodes = basis == FfdBasis::BSpline ? 4 : 2;
  for (int a = 0; a < 3; ++a) {
    if (nodes[a] < minNodes) {
      throw std::invalid_argument(
          std::string("nodes: ") + std::to_string(nodes[a]) + " on axis " + axisName(a) + ", a " +
          (basis == FfdBasis::BSpline ? "cubic B-spline" : "Bernstein") +
          " lattice needs at least " + std::to_string(minNodes) + " nodes per axis");
    }
    if (basis == FfdBasis::Bernstein && nodes[a] > kMaxBernsteinNodes) {
      throw std::invalid_argument("nodes: " + std::to_string(nodes[a]) + " on axis " + axisName(a) +
                                  ", a Bernstein lattice takes at most " +
                                  std::to_string(kMaxBernsteinNodes) +
                                  " per axis (use a B-spline lattice for finer control)");
    }
  }
  if (std::int64_t(nodes[0]) * nodes[1] * nodes[2] > kMaxNodes) {
    throw std::invalid_argument("nodes: " + std::to_string(nodes[0]) + "×" +
                                std::to_string(nodes[1]) + "×" + std::to_string(nodes[2]) +
                                " is more than " + std::to_string(kMaxNodes) + " nodes");
  }
}

Vec3 FfdLattice::spacing() const {
  Vec3 h;
  for (int a = 0; a < 3; ++a) h[a] = size[a] / (nodes[a] - (basis == FfdBasis::BSpline ? 3 : 1));
  return h;
}

Vec3 FfdLattice::restNode(int i, int j, int k) const {
  const std::array<int, 3> idx = {i, j, k};
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    if (basis == FfdBasis::BSpline) {
      // Spacing and offset written so that node 1 and node N − 2 are exactly the box corners.
      const int spans = nodes[a] - 3;
      p[a] = origin[a] + size[a] * (static_cast<double>(idx[a] - 1) / spans);
    } else {
      p[a] = origin[a] + size[a] * (static_cast<double>(idx[a]) / (nodes[a] - 1));
    }
  }
  return p;
}

FfdNodes FfdLattice::restNodes() const {
  validate();
  FfdNodes P(nodeCount(), 3);
  for (int k = 0; k < nodes[2]; ++k)
    for (int j = 0; j < nodes[1]; ++j)
      for (int i = 0; i < nodes[0]; ++i) P.row(nodeIndex(i, j, k)) = restNode(i, j, k).transpose();
  return P;
}

std::vector<std::vector<int>> FfdLattice::regions(int halfWidth) const {
  validate();
  if (halfWidth < 1)
    throw std::invalid_argument("ffd: region half-width must be at least 1, got " +
                                std::to_string(halfWidth));
  std::vector<std::vector<int>> out;
  out.reserve(size_t(nodeCount()));
  for (int k = 0; k < nodes[2]; ++k)
    for (int j = 0; j < nodes[1]; ++j)
      for (int i = 0; i < nodes[0]; ++i) {
        std::vector<int> region;
        // k, j, i ascending with x fastest: the indices come out sorted.
        for (int c = std::max(0, k - halfWidth); c <= std::min(nodes[2] - 1, k + halfWidth); ++c)
          for (int b = std::max(0, j - halfWidth); b <= std::min(nodes[1] - 1, j + halfWidth); ++b)
            for (int a = std::max(0, i - halfWidth); a <= std::min(nodes[0] - 1, i + halfWidth);
                 ++a)
              region.push_back(nodeIndex(a, b, c));
        out.push_back(std::move(region));
      }
  return out;
}

std::vector<std::array<int, 3>> FfdLattice::boundaryTriangles() const {
  validate();
  std::vector<std::array<int, 3>> out;
  for (int a = 0; a < 3; ++a) {
    // (u, v) = the other two axes in cyclic order, so û × v̂ = â: kept on the far side (outward
    // +â), reversed on the near side (outward −â).
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    for (const int side : {0, nodes[size_t(a)] - 1}) {
      for (int q = 0; q + 1 < nodes[size_t(v)]; ++q) {
        for (int p = 0; p + 1 < nodes[size_t(u)]; ++p) {
          auto at = [&](int pu, int qv) {
            std::array<int, 3> ijk{};
            ijk[size_t(a)] = side;
            ijk[size_t(u)] = pu;
            ijk[size_t(v)] = qv;
            return nodeIndex(ijk[0], ijk[1], ijk[2]);
          };
          const int c00 = at(p, q), c10 = at(p + 1, q), c11 = at(p + 1, q + 1), c01 = at(p, q + 1);
          if (side > 0) {
            out.push_back({c00, c10, c11});
            out.push_back({c00, c11, c01});
          } else {
            out.push_back({c00, c11, c10});
            out.push_back({c00, c01, c11});
          }
        }
      }
    }
  }
  return out;
}

FfdLattice ffdLatticeAround(const std::vector<Vec3>& points, std::array<int, 3> nodes,
                            FfdBasis basis, double margin) {
  if (points.empty()) throw std::invalid_argument("points: none given");
  if (!std::isfinite(margin) || margin < 0.0)
    throw std::invalid_argument("margin: " + str(margin) + " must be finite and ≥ 0");
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) + " " + str(points[i]) +
                                  " is not finite");
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  const double grow = margin * (hi - lo).norm();
  FfdLattice L;
  L.origin = lo - Vec3::Constant(grow);
  L.size = (hi - lo) + Vec3::Constant(2.0 * grow);
  // origin + size must not fall below hi by rounding: nudge size up by the rounding error.
  for (int a = 0; a < 3; ++a)
    if (L.size[a] > 0.0)
      while (L.origin[a] + L.size[a] < hi[a] + grow)
        L.size[a] = std::nextafter(L.size[a], std::numeric_limits<double>::infinity());
  L.nodes = nodes;
  L.basis = basis;
  for (int a = 0; a < 3; ++a) {
    if (!(L.size[a] > 0.0)) {
      throw std::invalid_argument(std::string("points: all have the same ") + axisName(a) +
                                  " coordinate (" + str(lo[a]) +
                                  ") and margin is 0: the box would have zero size on that axis");
    }
  }
  L.validate();
  return L;
}

void ffdBernsteinBasis(int degree, double t, double* values, double* derivatives) {
  if (degree < 0) throw std::invalid_argument("degree: " + std::to_string(degree) + " < 0");
  const double s = 1.0 - t;
  // Triangle recurrence B_i^r = s B_i^{r−1} + t B_{i−1}^{r−1}, in place from the top index down.
  values[0] = 1.0;
  for (int r = 1; r <= degree; ++r) {
    if (r == degree && derivatives) {
      // d/dt B_i^n = n (B_{i−1}^{n−1} − B_i^{n−1}), from the degree n − 1 values in place now.
      for (int i = 0; i <= degree; ++i) {
        const double left = i > 0 ? values[i - 1] : 0.0;
        const double right = i < degree ? values[i] : 0.0;
        derivatives[i] = degree * (left - right);
      }
    }
    values[r] = t * values[r - 1];
    for (int i = r - 1; i >= 1; --i) values[i] = s * values[i] + t * values[i - 1];
    values[0] = s * values[0];
  }
  if (degree == 0 && derivatives) derivatives[0] = 0.0;
}

void ffdCubicBSplineBasis(double t, double values[4], double derivatives[4]) {
  const double s = 1.0 - t, t2 = t * t, t3 = t2 * t;
  values[0] = s * s * s / 6.0;
  values[1] = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
  values[2] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
  values[3] = t3 / 6.0;
  if (derivatives) {
    derivatives[0] = -0.5 * s * s;
    derivatives[1] = 0.5 * (3.0 * t2 - 4.0 * t);
    derivatives[2] = 0.5 * (-3.0 * t2 + 2.0 * t + 1.0);
    derivatives[3] = 0.5 * t2;
  }
}

void ffdWeights(const FfdLattice& lattice, const Vec3& point,
                std::vector<std::pair<int, double>>& out) {
  lattice.validate();
  std::array<AxisBasis, 3> ax;
  axisParameters(lattice, point, -1, ax);
  evaluateAxes(lattice, ax, false);
  out.clear();
  forEachWeight(lattice, ax, [&](int n, double w) { out.emplace_back(n, w); });
}

Embedding bindFfd(const std::vector<Vec3>& points, const FfdLattice& lattice,
                  const FfdBindOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  lattice.validate();
  const int rows = static_cast<int>(points.size());
  const int cols = lattice.nodeCount();
  // Storage estimate before anything is allocated (sparse: a 4-byte index and 8 + 4 bytes of
  // double and float weight per slot; dense: 8 + 4 bytes per entry). The sparse index is an int.
  const bool sparse = lattice.basis == FfdBasis::BSpline;
  const double perRow = sparse ? 64.0 * 16.0 : cols * 12.0;
  if (double(points.size()) * (sparse ? 64.0 : double(cols)) >
          double(std::numeric_limits<int>::max()) ||
      double(points.size()) * perRow > double(options.maxWeightBytes)) {
    throw std::invalid_argument(
        "points: " + std::to_string(points.size()) + " points × " +
        (sparse ? std::string("64") : std::to_string(cols)) + " weights need about " +
        str(double(points.size()) * perRow / 1e9) +
        " GB, more than maxWeightBytes or the 2^31 entries of an Embedding");
  }
  const FfdNodes rest = lattice.restNodes();
  const double diagonal = lattice.size.norm();

  BindStats st;
  st.minWeight = std::numeric_limits<double>::infinity();
  st.maxWeight = -std::numeric_limits<double>::infinity();
  std::array<AxisBasis, 3> ax;
  auto account = [&](const Vec3& x, double sum, const Vec3& image) {
    st.maxSumError = std::max(st.maxSumError, std::abs(sum - 1.0));
    st.maxLinearError = std::max(st.maxLinearError, (image - x).norm() / diagonal);
  };
  auto accountWeight = [&](double w) {
    st.minWeight = std::min(st.minWeight, w);
    st.maxWeight = std::max(st.maxWeight, w);
    if (w < 0.0) ++st.negativeCount;
  };

  // Eigen 3.4's SparseMatrix has no move constructor or assignment (a "move" copies), so the
  // Embedding is made in place (prvalues, guaranteed elision) rather than assigned.
  auto makeSparse = [&] {
    // Written straight into W's compressed arrays (64 slots per row, the exact zeros of span
    // borders skipped, the tail cut at the end): no triplets, no second copy.
    Embedding::SparseD W(rows, cols);
    W.resizeNonZeros(static_cast<Eigen::Index>(rows) * 64);
    int* start = W.outerIndexPtr();
    int* col = W.innerIndexPtr();
    double* val = W.valuePtr();
    int nnz = 0;
    start[0] = 0;
    for (int r = 0; r < rows; ++r) {
      axisParameters(lattice, points[r], r, ax);
      evaluateAxes(lattice, ax, false);
      double sum = 0.0;
      Vec3 image = Vec3::Zero();
      forEachWeight(lattice, ax, [&](int n, double w) {
        if (w == 0.0) return;  // a span border: the node does not act on this point
        col[nnz] = n;
        val[nnz] = w;
        ++nnz;
        sum += w;
        image += w * rest.row(n).transpose();
        accountWeight(w);
      });
      start[r + 1] = nnz;
      account(points[r], sum, image);
    }
    W.data().resize(nnz);
    return Embedding::fromSparse(std::move(W), options.keepDoublePrecision);
  };
  auto makeDense = [&] {
    Embedding::DenseD W(rows, cols);
    for (int r = 0; r < rows; ++r) {
      axisParameters(lattice, points[r], r, ax);
      evaluateAxes(lattice, ax, false);
      double sum = 0.0;
      Vec3 image = Vec3::Zero();
      forEachWeight(lattice, ax, [&](int n, double w) {
        W(r, n) = w;
        sum += w;
        image += w * rest.row(n).transpose();
        accountWeight(w);
      });
      account(points[r], sum, image);
    }
    return Embedding::fromDense(std::move(W), options.keepDoublePrecision);
  };
  Embedding e = sparse ? makeSparse() : makeDense();
  e.setKind(lattice.basis == FfdBasis::BSpline ? EmbeddingKind::FfdBSpline
                                               : EmbeddingKind::FfdBernstein);
  if (rows == 0) st.minWeight = st.maxWeight = 0.0;
  st.nonZeros = e.nonZeros();
  st.threads = 1;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  e.stats() = st;
  return e;
}

Vec3 ffdEvaluateDeBoor(const FfdLattice& lattice, const FfdNodes& nodes, const Vec3& point) {
  lattice.validate();
  checkNodes(lattice, nodes);
  return evaluateRecursive(lattice, nodes, point, -1);
}

void ffdDeformDeBoor(const FfdLattice& lattice, const FfdNodes& nodes,
                     const std::vector<Vec3>& points,
                     Eigen::Matrix<double, Eigen::Dynamic, 3>& out) {
  lattice.validate();
  checkNodes(lattice, nodes);
  out.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) =
        evaluateRecursive(lattice, nodes, points[i], static_cast<std::int64_t>(i)).transpose();
}

namespace {

Eigen::Matrix3d jacobianUnchecked(const FfdLattice& L, const FfdNodes& nodes, const Vec3& p,
                                  std::int64_t index) {
  std::array<AxisBasis, 3> ax;
  axisParameters(L, p, index, ax);
  evaluateAxes(L, ax, true);
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  for (int k = 0; k < ax[2].count; ++k) {
    for (int j = 0; j < ax[1].count; ++j) {
      for (int i = 0; i < ax[0].count; ++i) {
        const Vec3 grad(ax[0].d[i] * ax[1].v[j] * ax[2].v[k], ax[0].v[i] * ax[1].d[j] * ax[2].v[k],
                        ax[0].v[i] * ax[1].v[j] * ax[2].d[k]);
        const int n = L.nodeIndex(ax[0].first + i, ax[1].first + j, ax[2].first + k);
        J += nodes.row(n).transpose() * grad.transpose();
      }
    }
  }
  return J;
}

}  // namespace

Eigen::Matrix3d ffdJacobian(const FfdLattice& lattice, const FfdNodes& nodes, const Vec3& point) {
  lattice.validate();
  checkNodes(lattice, nodes);
  return jacobianUnchecked(lattice, nodes, point, -1);
}

FfdNodes ffdDragPoint(const FfdLattice& lattice, FfdNodes& nodes, const Vec3& point,
                      const Vec3& displacement) {
  lattice.validate();
  checkNodes(lattice, nodes);
  if (!displacement.allFinite())
    throw std::invalid_argument("displacement: " + str(displacement) + " is not finite");
  std::vector<std::pair<int, double>> w;
  ffdWeights(lattice, point, w);
  double s2 = 0.0;
  for (const auto& [n, wn] : w) s2 += wn * wn;  // ≥ 1/#weights > 0 (partition of unity)
  FfdNodes delta = FfdNodes::Zero(nodes.rows(), 3);
  for (const auto& [n, wn] : w) delta.row(n) = (wn / s2) * displacement.transpose();
  nodes += delta;
  return delta;
}

FfdDragReport ffdDragPoints(const FfdLattice& lattice, FfdNodes& nodes,
                            const std::vector<Vec3>& points,
                            const std::vector<Vec3>& displacements) {
  lattice.validate();
  checkNodes(lattice, nodes);
  if (points.size() != displacements.size()) {
    throw std::invalid_argument("displacements: " + std::to_string(displacements.size()) +
                                " given for " + std::to_string(points.size()) + " points");
  }
  for (std::size_t p = 0; p < displacements.size(); ++p)
    if (!displacements[p].allFinite())
      throw std::invalid_argument("displacement " + std::to_string(p) + " " +
                                  str(displacements[p]) + " is not finite");
  FfdDragReport rep;
  rep.delta = FfdNodes::Zero(nodes.rows(), 3);
  if (points.empty()) return rep;
  // Only the nodes some point touches can take part in the minimum-norm solution (any other
  // node's change would add norm and change no constraint), so B is #points × #touched.
  std::vector<std::vector<std::pair<int, double>>> rows(points.size());
  std::map<int, int> column;
  for (std::size_t p = 0; p < points.size(); ++p) {
    std::array<AxisBasis, 3> ax;
    axisParameters(lattice, points[p], static_cast<std::int64_t>(p), ax);
    evaluateAxes(lattice, ax, false);
    forEachWeight(lattice, ax, [&](int n, double w) {
      if (w == 0.0) return;
      rows[p].emplace_back(n, w);
      column.emplace(n, 0);
    });
  }
  int c = 0;
  for (auto& [n, j] : column) j = c++;
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(points.size()), c);
  Eigen::MatrixXd dQ(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t p = 0; p < points.size(); ++p) {
    for (const auto& [n, w] : rows[p]) B(static_cast<Eigen::Index>(p), column[n]) = w;
    dQ.row(static_cast<Eigen::Index>(p)) = displacements[p].transpose();
  }
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(B);
  const Eigen::MatrixXd X = cod.solve(dQ);  // minimum-norm least-squares solution, c × 3
  rep.rank = static_cast<int>(cod.rank());
  rep.maxResidual = (B * X - dQ).rowwise().norm().maxCoeff();
  for (const auto& [n, j] : column) rep.delta.row(n) = X.row(j);
  nodes += rep.delta;
  return rep;
}

FfdInjectivityReport ffdInjectivityBound(const FfdLattice& lattice, const FfdNodes& nodes,
                                         double bound) {
  lattice.validate();
  checkNodes(lattice, nodes);
  if (!std::isfinite(bound) || !(bound > 0.0))
    throw std::invalid_argument("bound: " + str(bound) + " must be finite and > 0");
  FfdInjectivityReport rep;
  rep.bound = bound;
  rep.applicable = lattice.basis == FfdBasis::BSpline;
  const FfdNodes rest = lattice.restNodes();
  const Vec3 h = lattice.spacing();
  for (int a = 0; a < 3; ++a)
    rep.maxDisplacementRatio[a] = (nodes.col(a) - rest.col(a)).cwiseAbs().maxCoeff() / h[a];
  rep.guaranteedInjective = rep.applicable && rep.maxDisplacementRatio.maxCoeff() < bound;
  return rep;
}

FfdJacobianReport ffdJacobianCheck(const FfdLattice& lattice, const FfdNodes& nodes,
                                   const std::vector<Vec3>& samples) {
  lattice.validate();
  checkNodes(lattice, nodes);
  FfdJacobianReport rep;
  rep.minDeterminant = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const double det =
        jacobianUnchecked(lattice, nodes, samples[i], static_cast<std::int64_t>(i)).determinant();
    if (det < rep.minDeterminant) {
      rep.minDeterminant = det;
      rep.argMin = samples[i];
    }
    if (!(det > 0.0)) ++rep.nonPositiveCount;
  }
  rep.samples = static_cast<std::int64_t>(samples.size());
  if (samples.empty()) rep.minDeterminant = 0.0;
  return rep;
}

}  // namespace sb::cage
