#include "sim/cage/harmonic.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "sim/base/file_io.h"
#include "sim/base/parallel_for.h"
#include "sim/cage/auto_cage_geometry.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/closest_point.h"

namespace sb::cage {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Hat functions of the cage at its point closest to x: the closest triangle and the barycentric
// weights of its corners (brute force over all triangles; only for the few points that need it).
struct CagePoint {
  int triangle = -1;
  Vec3 bary = Vec3::Zero();
  double distance = std::numeric_limits<double>::infinity();
};
CagePoint closestCagePoint(const Vec3& x, const mesh::TriangleMesh& cage) {
  CagePoint best;
  for (int t = 0; t < static_cast<int>(cage.triangles.size()); ++t) {
    const auto& tri = cage.triangles[size_t(t)];
    const Vec3 &a = cage.vertices[size_t(tri[0])], &b = cage.vertices[size_t(tri[1])],
               &c = cage.vertices[size_t(tri[2])];
    const auto cp = mesh::closestPointOnTriangle<double>(x, a, b, c);
    const double d = (cp.weights[0] * a + cp.weights[1] * b + cp.weights[2] * c - x).norm();
    if (d < best.distance) best = {t, cp.weights, d};
  }
  return best;
}

// Where the grid lines along one axis cross the cage. Line numbering for axis a, with
// b = (a+1) mod 3 and c = (a+2) mod 3: index_b + dims_b · index_c. Each line is moved off its
// nodes by a tiny irrational fraction of h (≈1e-7) across the axis, so that it passes through no
// cage vertex or edge: a crossing is inside one triangle, counted once.
struct Crossing {
  std::int64_t line;
  double t;      // coordinate along the axis (the cage's units)
  int triangle;  // the triangle crossed
  Vec3 bary;     // barycentric weights of the crossing point in it
};
struct AxisCrossings {
  std::vector<Crossing> list;      // sorted by (line, t)
  std::vector<std::size_t> start;  // per line, its first crossing; lines + 1 entries
};
AxisCrossings axisCrossings(int a, const mesh::TriangleMesh& cage, const Vec3& origin, double h,
                            const std::array<int, 3>& dims) {
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const double db = h * 1.2345678e-7, dc = h * 0.8765432e-7;
  const auto& V = cage.vertices;
  AxisCrossings out;
  for (int t = 0; t < static_cast<int>(cage.triangles.size()); ++t) {
    const auto& tri = cage.triangles[size_t(t)];
    const Vec3 &p0 = V[size_t(tri[0])], &p1 = V[size_t(tri[1])], &p2 = V[size_t(tri[2])];
    const double blo = (std::min({p0[b], p1[b], p2[b]}) - origin[b] - db) / h;
    const double bhi = (std::max({p0[b], p1[b], p2[b]}) - origin[b] - db) / h;
    const double clo = (std::min({p0[c], p1[c], p2[c]}) - origin[c] - dc) / h;
    const double chi = (std::max({p0[c], p1[c], p2[c]}) - origin[c] - dc) / h;
    for (std::int64_t ic = std::max<std::int64_t>(0, std::int64_t(std::ceil(clo)));
         ic <= std::min<std::int64_t>(dims[size_t(c)] - 1, std::int64_t(std::floor(chi))); ++ic)
      for (std::int64_t ib = std::max<std::int64_t>(0, std::int64_t(std::ceil(blo)));
           ib <= std::min<std::int64_t>(dims[size_t(b)] - 1, std::int64_t(std::floor(bhi))); ++ib) {
        const double y = origin[b] + double(ib) * h + db, z = origin[c] + double(ic) * h + dc;
        // Signed areas of the sub-triangles in the (b, c) plane.
        auto orient = [&](const Vec3& p, const Vec3& q) {
          return (p[b] - y) * (q[c] - z) - (p[c] - z) * (q[b] - y);
        };
        const double e0 = orient(p1, p2), e1 = orient(p2, p0), e2 = orient(p0, p1);
        if (!((e0 > 0 && e1 > 0 && e2 > 0) || (e0 < 0 && e1 < 0 && e2 < 0))) continue;
        const Vec3 w = Vec3(e0, e1, e2) / (e0 + e1 + e2);
        out.list.push_back(
            {ib + dims[size_t(b)] * ic, w[0] * p0[a] + w[1] * p1[a] + w[2] * p2[a], t, w});
      }
  }
  std::sort(out.list.begin(), out.list.end(), [](const Crossing& x, const Crossing& y) {
    return x.line != y.line ? x.line < y.line : x.t < y.t;
  });
  const std::int64_t lines = std::int64_t(dims[size_t(b)]) * dims[size_t(c)];
  out.start.assign(size_t(lines) + 1, 0);
  for (const Crossing& x : out.list) ++out.start[size_t(x.line) + 1];
  for (std::int64_t l = 0; l < lines; ++l) out.start[size_t(l) + 1] += out.start[size_t(l)];
  return out;
}

// Nested dissection of a set of grid nodes (ids i + nx·(j + ny·k)) for the 7-point stencil:
// the plane through the middle of the set's box, across its longest side, separates the nodes
// on either side (no stencil couples them), so they are numbered first, each half recursively,
// and the plane last. The factor of the Laplacian then fills in only within the separators'
// blocks: O(n^{4/3}) non-zeros for n unknowns, against O(n^{5/3}) for a plain row order.
void nestedDissection(std::vector<std::int64_t>& nodes, std::int64_t nx, std::int64_t ny,
                      std::vector<std::int64_t>& order) {
  if (nodes.size() <= 64) {
    std::sort(nodes.begin(), nodes.end());
    order.insert(order.end(), nodes.begin(), nodes.end());
    return;
  }
  auto coord = [&](std::int64_t id, int a) {
    return a == 0 ? id % nx : a == 1 ? (id / nx) % ny : id / (nx * ny);
  };
  std::int64_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<std::int64_t>::max();
    hi[a] = std::numeric_limits<std::int64_t>::min();
  }
  for (const std::int64_t id : nodes)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], coord(id, a));
      hi[a] = std::max(hi[a], coord(id, a));
    }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  const std::int64_t cut = (lo[axis] + hi[axis]) / 2;
  std::vector<std::int64_t> left, right, separator;
  for (const std::int64_t id : nodes) {
    const std::int64_t c = coord(id, axis);
    (c < cut ? left : c > cut ? right : separator).push_back(id);
  }
  std::vector<std::int64_t>().swap(nodes);
  nestedDissection(left, nx, ny, order);
  nestedDissection(right, nx, ny, order);
  std::sort(separator.begin(), separator.end());
  order.insert(order.end(), separator.begin(), separator.end());
}

// Multigrid preconditioner for conjugate gradients on the grid Laplacian A (full symmetric
// matrix, column-major: column i is row i). The unknowns of the next coarser level are this
// level's unknowns with even grid indices; an unknown takes the trilinear interpolation of the
// coarse nodes around it, those that are not unknowns counting as 0 like the boundary (P; every
// column of P has a 1 in its own node's row, so P has full rank and Pᵀ A P is positive
// definite). The coarse matrix is that Galerkin product, so the cut-cell arms (large diagonals
// near the cage) are inherited without a coarse-grid geometry. Levels are added until at most
// kDirectUnknowns remain, which are solved exactly (SimplicialLDLT). A V-cycle: forward
// Gauss-Seidel, coarse correction, backward Gauss-Seidel; symmetric, so CG may use it.
class Multigrid {
 public:
  using Sparse = Eigen::SparseMatrix<double>;
  static constexpr std::int64_t kDirectUnknowns = 2000;

  Multigrid(const Sparse& A, std::vector<std::int64_t> nodes, std::vector<int> unknown,
            std::int64_t nx, std::int64_t ny, std::int64_t nz) {
    levels_.emplace_back();
    levels_.back().A = A;
    while (levels_.back().A.rows() > kDirectUnknowns && nx > 2 && ny > 2 && nz > 2) {
      Level& L = levels_.back();
      const std::int64_t n = L.A.rows();
      L.invDiag.resize(n);
      for (std::int64_t i = 0; i < n; ++i) L.invDiag[i] = 1.0 / L.A.coeff(i, i);
      const std::int64_t cx = (nx + 1) / 2, cy = (ny + 1) / 2, cz = (nz + 1) / 2;
      std::vector<int> coarseUnknown(size_t(cx * cy * cz), -1);
      std::vector<std::int64_t> coarseNodes;
      for (std::int64_t r = 0; r < n; ++r) {
        const std::int64_t id = nodes[size_t(r)];
        const std::int64_t i = id % nx, j = (id / nx) % ny, k = id / (nx * ny);
        if (i % 2 == 0 && j % 2 == 0 && k % 2 == 0)
          coarseNodes.push_back(i / 2 + cx * (j / 2 + cy * (k / 2)));
      }
      // In grid order, whatever this level's numbering.
      std::sort(coarseNodes.begin(), coarseNodes.end());
      for (std::size_t c = 0; c < coarseNodes.size(); ++c)
        coarseUnknown[size_t(coarseNodes[c])] = int(c);
      std::vector<Eigen::Triplet<double>> pt;
      pt.reserve(size_t(n) * 8);
      for (std::int64_t r = 0; r < n; ++r) {
        const std::int64_t id = nodes[size_t(r)];
        const std::int64_t idx[3] = {id % nx, (id / nx) % ny, id / (nx * ny)};
        for (int corner = 0; corner < 8; ++corner) {
          std::int64_t c[3];
          double w = 1.0;
          bool used = true;
          for (int a = 0; a < 3; ++a) {
            const int bit = (corner >> a) & 1;
            if (idx[a] % 2 == 0) {
              used = used && bit == 0;  // on a coarse line: that coordinate only
              c[a] = idx[a] / 2;
            } else {
              c[a] = idx[a] / 2 + bit;
              w *= 0.5;
            }
          }
          if (!used || c[0] >= cx || c[1] >= cy || c[2] >= cz) continue;
          const int col = coarseUnknown[size_t(c[0] + cx * (c[1] + cy * c[2]))];
          if (col >= 0) pt.emplace_back(int(r), col, w);
        }
      }
      L.P.resize(n, std::int64_t(coarseNodes.size()));
      L.P.setFromTriplets(pt.begin(), pt.end());
      L.Pt = L.P.transpose();
      Sparse Ac = Sparse(L.Pt * L.A * L.P);
      levels_.emplace_back();
      levels_.back().A = std::move(Ac);
      nodes.swap(coarseNodes);
      unknown.swap(coarseUnknown);
      nx = cx;
      ny = cy;
      nz = cz;
    }
    coarsest_.compute(levels_.back().A);
    if (coarsest_.info() != Eigen::Success)
      throw std::runtime_error("bindHarmonic: the factorisation of the coarse Laplacian failed");
  }
  std::int64_t coarseFactorNonZeros() const {
    return coarsest_.matrixL().nestedExpression().nonZeros();
  }
  int levels() const { return int(levels_.size()); }

  // One row per unknown, one column per right-hand side: a sweep over the matrix serves all the
  // columns of a block at once.
  // The width is fixed at compile time so that the sweeps' inner loops vectorise; a block with
  // fewer right-hand sides is padded with zero columns (which CG leaves alone).
  static constexpr int kColumns = 8;
  using Block = Eigen::Matrix<double, Eigen::Dynamic, kColumns, Eigen::RowMajor>;

  // Z = M⁻¹ R (one V-cycle from Z = 0), column by column.
  void apply(const Block& R, Block& Z) const { cycle(0, R, Z); }

 private:
  struct Level {
    Sparse A, P, Pt;  // P: from the next coarser level to this one
    Eigen::VectorXd invDiag;
  };
  void cycle(std::size_t l, const Block& R, Block& Z) const {
    if (l + 1 == levels_.size()) {
      Z = coarsest_.solve(Eigen::MatrixXd(R));
      return;
    }
    const Level& L = levels_[l];
    const std::int64_t n = L.A.rows();
    constexpr std::int64_t K = kColumns;
    const double* val = L.A.valuePtr();
    const int* inner = L.A.innerIndexPtr();
    const int* outer = L.A.outerIndexPtr();
    Z.setZero(n, K);
    double* z = Z.data();
    const double* r = R.data();
    double s[K];
    auto relax = [&](std::int64_t i) {
      for (std::int64_t c = 0; c < K; ++c) s[c] = r[i * K + c];
      for (int k = outer[i]; k < outer[i + 1]; ++k) {
        const double a = val[k];
        const double* zq = z + std::int64_t(inner[k]) * K;
        for (std::int64_t c = 0; c < K; ++c) s[c] -= a * zq[c];
      }
      // s includes the diagonal term A_ii·z_i.
      for (std::int64_t c = 0; c < K; ++c) z[i * K + c] += s[c] * L.invDiag[i];
    };
    for (std::int64_t i = 0; i < n; ++i) relax(i);
    Block residual = R;
    residual.noalias() -= L.A * Z;
    const Block rc = L.Pt * residual;
    Block ec;
    cycle(l + 1, rc, ec);
    Z.noalias() += L.P * ec;
    for (std::int64_t i = n - 1; i >= 0; --i) relax(i);
  }
  std::vector<Level> levels_;
  Eigen::SimplicialLDLT<Sparse, Eigen::Lower, Eigen::AMDOrdering<int>> coarsest_;
};

// Preconditioned conjugate gradients for A X = B from X = 0, each column until
// |r| ≤ tol·|b| (a converged column is left alone while the others go on, so its result does
// not depend on them). Writes each column's iteration count to iterations[c].
void multigridCg(const Eigen::SparseMatrix<double>& A, const Multigrid& M,
                 const Multigrid::Block& B, double tol, Multigrid::Block& X, int* iterations) {
  const std::int64_t n = A.rows();
  constexpr std::int64_t K = Multigrid::kColumns;
  X.setZero(n, K);
  std::vector<double> bnorm(static_cast<std::size_t>(K)), rz(static_cast<std::size_t>(K));
  std::vector<char> active(static_cast<std::size_t>(K));
  int activeCount = 0;
  for (std::int64_t c = 0; c < K; ++c) {
    bnorm[size_t(c)] = B.col(c).norm();
    active[size_t(c)] = bnorm[size_t(c)] > 0.0;
    activeCount += active[size_t(c)];
    iterations[c] = 0;
  }
  if (activeCount == 0) return;
  Multigrid::Block R = B, Z, P, AP;
  M.apply(R, Z);
  P = Z;
  for (std::int64_t c = 0; c < K; ++c) rz[size_t(c)] = R.col(c).dot(Z.col(c));
  constexpr int kMaxIterations = 1000;
  for (int it = 1; it <= kMaxIterations; ++it) {
    AP.noalias() = A * P;
    for (std::int64_t c = 0; c < K; ++c) {
      if (!active[size_t(c)]) continue;
      const double alpha = rz[size_t(c)] / P.col(c).dot(AP.col(c));
      X.col(c) += alpha * P.col(c);
      R.col(c) -= alpha * AP.col(c);
      if (R.col(c).norm() <= tol * bnorm[size_t(c)]) {
        active[size_t(c)] = 0;
        --activeCount;
        iterations[c] = it;
      }
    }
    if (activeCount == 0) return;
    M.apply(R, Z);
    for (std::int64_t c = 0; c < K; ++c) {
      if (!active[size_t(c)]) continue;
      const double rzNew = R.col(c).dot(Z.col(c));
      P.col(c) = Z.col(c) + (rzNew / rz[size_t(c)]) * P.col(c);
      rz[size_t(c)] = rzNew;
    }
  }
  throw std::runtime_error("bindHarmonic: conjugate gradients did not converge in " +
                           std::to_string(kMaxIterations) + " iterations");
}

}  // namespace

Embedding bindHarmonic(const std::vector<Vec3>& points, const mesh::TriangleMesh& cage,
                       const HarmonicOptions& options, HarmonicReport* reportOut) {
  const auto t0 = Clock::now();
  mesh::validateClosedSurface(cage, "cage");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite())
      throw std::invalid_argument("bindHarmonic: point " + std::to_string(i) + " is not finite");
  }
  if (!(options.cgTolerance > 0.0 && options.cgTolerance < 1.0))
    throw std::invalid_argument("bindHarmonic: cgTolerance must be in (0, 1), got " +
                                std::to_string(options.cgTolerance));
  if (options.resolution < 4)
    throw std::invalid_argument("bindHarmonic: resolution must be at least 4 cells, got " +
                                std::to_string(options.resolution));
  const int threads =
      options.threads > 0 ? std::min(options.threads, threadCount()) : threadCount();
  const int n = static_cast<int>(points.size());
  const int m = static_cast<int>(cage.vertices.size());
  const auto& V = cage.vertices;
  const auto& T = cage.triangles;

  // Grid: cubic cells of size h, `margin` cells beyond the cage's box on every side (so every
  // node within √3·h of the cage is a grid node), centred on the box.
  constexpr int kMargin = 2;
  Eigen::AlignedBox3d box;
  for (const Vec3& v : V) box.extend(v);
  const Vec3 extent = box.sizes();
  const double diagonal = extent.norm();
  const double h = extent.maxCoeff() / options.resolution;
  std::array<int, 3> dims{};
  double nodeCount = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil(extent[a] / h - 1e-9);
    nodeCount *= cells + 1.0 + 2.0 * kMargin;
    dims[size_t(a)] = static_cast<int>(std::min(cells + 1.0 + 2.0 * kMargin, 1e9));
  }
  // Memory: per node the distance, closest triangle, barycentrics, unknown index and flags (~48
  // bytes); the solutions, right-hand side blocks and factor of the interior nodes (bounded by
  // the node count until they are known); the dense weights (double + float).
  auto refuse = [&](double bytes, const std::string& what) {
    throw std::runtime_error("bindHarmonic: " + what + " about " +
                             formatBytes(std::uint64_t(bytes)) + ", more than the " +
                             formatBytes(options.maxBytes) + " allowed");
  };
  const double weightBytes = 12.0 * double(n) * double(m);
  const double gridBytes = 48.0 * nodeCount;
  if (nodeCount > 2e9 || gridBytes + weightBytes > double(options.maxBytes))
    refuse(gridBytes + weightBytes, "a grid of " + std::to_string(dims[0]) + "×" +
                                        std::to_string(dims[1]) + "×" + std::to_string(dims[2]) +
                                        " nodes (resolution " + std::to_string(options.resolution) +
                                        ") and " + std::to_string(n) + "×" + std::to_string(m) +
                                        " dense weights need");
  const Vec3 origin = box.center() - 0.5 * h * Vec3(dims[0] - 1, dims[1] - 1, dims[2] - 1);
  const std::int64_t nx = dims[0], ny = dims[1], nz = dims[2];
  const std::int64_t N = nx * ny * nz;
  auto nodePos = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return Vec3(origin.x() + double(i) * h, origin.y() + double(j) * h, origin.z() + double(k) * h);
  };

  // 1. Distance to the cage and its closest point, for the nodes within R = √3·h of a triangle
  //    (per triangle, over the nodes of its box grown by R).
  const double R = std::sqrt(3.0) * h * (1.0 + 1e-9);
  std::vector<double> dist(size_t(N), std::numeric_limits<double>::infinity());
  std::vector<int> closestTri(size_t(N), -1);
  std::vector<Vec3> bary(static_cast<std::size_t>(N));
  for (int t = 0; t < static_cast<int>(T.size()); ++t) {
    const Vec3 &a = V[size_t(T[size_t(t)][0])], &b = V[size_t(T[size_t(t)][1])],
               &c = V[size_t(T[size_t(t)][2])];
    const Vec3 lo = (a.cwiseMin(b).cwiseMin(c) - origin).array() - R;
    const Vec3 hi = (a.cwiseMax(b).cwiseMax(c) - origin).array() + R;
    std::array<std::int64_t, 3> i0{}, i1{};
    for (int d = 0; d < 3; ++d) {
      i0[size_t(d)] = std::max<std::int64_t>(0, std::int64_t(std::ceil(lo[d] / h)));
      i1[size_t(d)] = std::min<std::int64_t>(dims[size_t(d)] - 1, std::int64_t(hi[d] / h));
    }
    for (std::int64_t k = i0[2]; k <= i1[2]; ++k)
      for (std::int64_t j = i0[1]; j <= i1[1]; ++j)
        for (std::int64_t i = i0[0]; i <= i1[0]; ++i) {
          const Vec3 p = nodePos(i, j, k);
          const auto cp = mesh::closestPointOnTriangle<double>(p, a, b, c);
          const double d = (cp.weights[0] * a + cp.weights[1] * b + cp.weights[2] * c - p).norm();
          const std::int64_t id = i + nx * (j + ny * k);
          if (d < dist[size_t(id)]) {
            dist[size_t(id)] = d;
            closestTri[size_t(id)] = t;
            bary[size_t(id)] = cp.weights;
          }
        }
  }

  // 2. Inside / outside by the parity of the crossings of the grid lines along x (moved off the
  //    nodes by ~1e-7·h, see axisCrossings: that changes the answer only for nodes within that
  //    distance of the cage). A line with an odd crossing count (a degenerate hit after all)
  //    falls back to the winding number per node.
  AxisCrossings cross[3];
  cross[0] = axisCrossings(0, cage, origin, h, dims);
  const auto& crossings = cross[0].list;
  std::vector<unsigned char> inside(size_t(N), 0);
  for (std::size_t c0 = 0; c0 < crossings.size();) {
    std::size_t c1 = c0;
    while (c1 < crossings.size() && crossings[c1].line == crossings[c0].line) ++c1;
    const std::int64_t row = crossings[c0].line;
    const std::int64_t base = nx * row;
    if ((c1 - c0) % 2 == 0) {
      std::size_t c = c0;
      for (std::int64_t i = 0; i < nx; ++i) {
        const double x = origin.x() + double(i) * h;
        while (c < c1 && crossings[c].t < x) ++c;
        inside[size_t(base + i)] = static_cast<unsigned char>((c - c0) % 2);
      }
    } else {
      const std::int64_t j = row % ny, k = row / ny;
      for (std::int64_t i = 0; i < nx; ++i) {
        const Vec3 p = nodePos(i, j, k);
        double angles = 0.0;
        for (const auto& tri : T)
          angles += detail::solidAngle(p, V[size_t(tri[0])], V[size_t(tri[1])], V[size_t(tri[2])]);
        inside[size_t(base + i)] = angles > 2.0 * M_PI ? 1 : 0;
      }
    }
    c0 = c1;
  }

  // 3. Unknowns. CutCell: every inside node; a stencil arm from an unknown to an outside node
  //    ends at the cage, where the lines along y and z are crossed too (step 4). ClosestPoint:
  //    inside nodes farther than h from the cage; each of their 6 neighbours is then an unknown
  //    or lies within h of the cage (a segment of length h from an inside node to an outside one
  //    crosses the cage), so it carries boundary values. Boundary nodes (both): every other node
  //    within R = √3·h; with them every grid cell that meets the inside of the cage has values at
  //    all 8 corners.
  const bool cutCell = options.boundary == HarmonicBoundary::CutCell;
  if (cutCell) {
    cross[1] = axisCrossings(1, cage, origin, h, dims);
    cross[2] = axisCrossings(2, cage, origin, h, dims);
  }
  const double unknownMinDistance = cutCell ? -1.0 : h;
  std::vector<int> unknown(size_t(N), -1);
  std::int64_t nB = 0;
  std::vector<std::int64_t> unknownNodes;
  for (std::int64_t id = 0; id < N; ++id) {
    if (inside[size_t(id)] && dist[size_t(id)] > unknownMinDistance)
      unknownNodes.push_back(id);
    else if (closestTri[size_t(id)] >= 0)
      ++nB;
  }
  std::vector<unsigned char>().swap(inside);
  const std::int64_t nI = static_cast<std::int64_t>(unknownNodes.size());
  if (nI >= std::numeric_limits<int>::max())
    throw std::runtime_error("bindHarmonic: " + std::to_string(nI) + " unknowns, too many");
  {
    std::vector<std::int64_t> order;
    order.reserve(size_t(nI));
    if (options.ordering == HarmonicOrdering::NestedDissection)
      nestedDissection(unknownNodes, nx, ny, order);
    else
      order.swap(unknownNodes);
    for (std::int64_t r = 0; r < nI; ++r) unknown[size_t(order[size_t(r)])] = static_cast<int>(r);
    unknownNodes.swap(order);  // unknownNodes[r] = grid node of unknown r
  }
  // The solution (8 bytes per unknown and cage vertex), the right-hand-side blocks (16 columns
  // per thread) and the factor: both orderings fill a 3-D grid with O(n^{4/3}) entries, measured
  // 8.2·n^{4/3} (AMD) and 9.4·n^{4/3} (nested dissection) for the bunny cage at resolution 64;
  // counted as 10·n^{4/3} entries of 12 bytes (value and row index) plus the matrix.
  const double factorBytes = 120.0 * std::pow(double(nI), 4.0 / 3.0) + 100.0 * double(nI);
  const double solveBytes = 8.0 * double(nI) * (double(m) + 16.0 * threads) + factorBytes;
  if (gridBytes + weightBytes + solveBytes > double(options.maxBytes))
    refuse(gridBytes + weightBytes + solveBytes, "the solve for " + std::to_string(nI) +
                                                     " interior nodes × " + std::to_string(m) +
                                                     " cage vertices needs");
  const double classifySeconds = since(t0);

  // 4. The 7-point Laplacian on the unknowns (its rows scaled by h²) and its right-hand sides.
  //    An arm to an unknown neighbour: u_i − u_q. An arm to a boundary node q (ClosestPoint, or
  //    CutCell when no crossing is found on the arm, which only an inconsistent inside test
  //    can cause): u_i − g_q, g_q = the hat values of q's closest cage point. CutCell: an arm
  //    that leaves the cage at the fraction θ of its length ends at the crossing point, whose
  //    hat values g are exact: the ghost value u_q = (g + (θ − 1)·u_i)/θ (linear extrapolation;
  //    Gibou et al. 2002) gives (u_i − g)/θ. Either way the matrix is symmetric, positive
  //    definite and an M-matrix (discrete maximum principle: w ≥ 0); CutCell reproduces linear
  //    functions exactly (linear precision at the nodes) and converges like O(h²). θ is taken at
  //    least kMinTheta, which moves a crossing closer than that by at most kMinTheta·h.
  constexpr double kMinTheta = 1e-6;
  const auto tf = Clock::now();
  struct RhsEntry {
    int column, row;
    double value;
  };
  std::vector<RhsEntry> rhs;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(size_t(nI) * 4);
  const std::int64_t step[3] = {1, nx, nx * ny};
  std::int64_t cutArms = 0;
  auto addHat = [&](int row, int t, const Vec3& w, double scale) {
    for (int k = 0; k < 3; ++k)
      if (w[k] != 0.0) rhs.push_back({T[size_t(t)][size_t(k)], row, scale * w[k]});
  };
  for (std::int64_t id = 0; id < N; ++id) {
    const int r = unknown[size_t(id)];
    if (r < 0) continue;
    const std::int64_t idx[3] = {id % nx, (id / nx) % ny, id / (nx * ny)};
    double diag = 0.0;
    for (int a = 0; a < 3; ++a)
      for (int s = -1; s <= 1; s += 2) {
        const std::int64_t q = id + s * step[a];
        const int c = unknown[size_t(q)];
        if (c >= 0) {
          diag += 1.0;
          if (c < r) triplets.emplace_back(r, c, -1.0);  // lower triangle only
          continue;
        }
        if (cutCell) {
          const AxisCrossings& X = cross[a];
          const std::int64_t line = idx[(a + 1) % 3] + dims[size_t((a + 1) % 3)] * idx[(a + 2) % 3];
          const double ti = origin[a] + double(idx[a]) * h;
          const auto first = X.list.begin() + std::ptrdiff_t(X.start[size_t(line)]);
          const auto last = X.list.begin() + std::ptrdiff_t(X.start[size_t(line) + 1]);
          auto byT = [](const Crossing& x, double t) { return x.t < t; };
          auto it = std::lower_bound(first, last, ti, byT);  // first crossing at or after ti
          const Crossing* hit = nullptr;
          if (s > 0 && it != last && it->t <= ti + h * (1.0 + 1e-9)) hit = &*it;
          if (s < 0) {
            // The last crossing at or before ti.
            auto jt = std::upper_bound(first, last, ti,
                                       [](double t, const Crossing& x) { return t < x.t; });
            if (jt != first && std::prev(jt)->t >= ti - h * (1.0 + 1e-9)) hit = &*std::prev(jt);
          }
          if (hit) {
            const double theta = std::max(std::abs(hit->t - ti) / h, kMinTheta);
            diag += 1.0 / theta;
            addHat(r, hit->triangle, hit->bary, 1.0 / theta);
            ++cutArms;
            continue;
          }
        }
        diag += 1.0;
        if (closestTri[size_t(q)] >= 0) {
          addHat(r, closestTri[size_t(q)], bary[size_t(q)], 1.0);
        } else {
          // Only reachable through an inconsistent inside test (CutCell): q is farther than
          // √3·h from the cage, so its closest point was not recorded.
          const CagePoint cp =
              closestCagePoint(nodePos(q % nx, (q / nx) % ny, q / (nx * ny)), cage);
          addHat(r, cp.triangle, cp.bary, 1.0);
        }
      }
    triplets.emplace_back(r, r, diag);
  }
  std::stable_sort(rhs.begin(), rhs.end(),
                   [](const RhsEntry& x, const RhsEntry& y) { return x.column < y.column; });
  const bool cg = options.solver == HarmonicSolver::MultigridCg ||
                  (options.solver == HarmonicSolver::Auto && options.resolution > 32);
  if (cg) {
    // The Gauss-Seidel sweeps and products want the whole matrix: mirror the lower triangle.
    const std::size_t lower = triplets.size();
    for (std::size_t k = 0; k < lower; ++k)
      if (triplets[k].row() != triplets[k].col())
        triplets.emplace_back(triplets[k].col(), triplets[k].row(), triplets[k].value());
  }
  Eigen::SparseMatrix<double> A(nI, nI);
  A.setFromTriplets(triplets.begin(), triplets.end());
  std::vector<Eigen::Triplet<double>>().swap(triplets);
  // With NestedDissection the unknowns are already numbered in elimination order.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>>
      ldltNatural;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldltAmd;
  std::unique_ptr<Multigrid> multigrid;
  const bool amd = options.ordering == HarmonicOrdering::Amd;
  if (nI > 0 && cg) {
    multigrid = std::make_unique<Multigrid>(A, unknownNodes, unknown, nx, ny, nz);
  } else if (nI > 0) {
    if (amd)
      ldltAmd.compute(A);
    else
      ldltNatural.compute(A);
    if ((amd ? ldltAmd.info() : ldltNatural.info()) != Eigen::Success)
      throw std::runtime_error("bindHarmonic: the factorisation of the Laplacian failed");
  }
  const double factorSeconds = since(tf);

  // 5. One solve per cage vertex (column), blocks of 16 columns per call, the columns split
  //    across threads. Each column is solved the same way whatever the split.
  const auto ts = Clock::now();
  Embedding::DenseD X(nI, m);  // row = unknown, column = cage vertex
  std::vector<std::size_t> colStart(size_t(m) + 1, 0);
  for (const RhsEntry& e : rhs) ++colStart[size_t(e.column) + 1];
  for (int j = 0; j < m; ++j) colStart[size_t(j) + 1] += colStart[size_t(j)];
  std::vector<int> cgIterations(size_t(m), 0);
  if (nI > 0 && cg) {
    // Fixed blocks of kColumns columns, split across threads whole: a column's operations
    // depend only on its own data, so W is the same whatever the split.
    constexpr int kColumns = Multigrid::kColumns;
    const int blocks = (m + kColumns - 1) / kColumns;
    parallelRanges(blocks, 2, threads, [&](int k0, int k1) {
      Multigrid::Block B, Xb;
      int iterations[kColumns];
      for (int k = k0; k < k1; ++k) {
        const int j0 = k * kColumns, cols = std::min(kColumns, m - j0);
        B.setZero(nI, kColumns);
        for (int j = j0; j < j0 + cols; ++j)
          for (std::size_t e = colStart[size_t(j)]; e < colStart[size_t(j) + 1]; ++e)
            B(rhs[e].row, j - j0) += rhs[e].value;
        multigridCg(A, *multigrid, B, options.cgTolerance, Xb, iterations);
        X.middleCols(j0, cols) = Xb.leftCols(cols);
        for (int c = 0; c < cols; ++c) cgIterations[size_t(j0 + c)] = iterations[c];
      }
    });
  } else if (nI > 0) {
    parallelRanges(m, 2, threads, [&](int j0, int j1) {
      constexpr int kBlock = 16;
      Eigen::MatrixXd B;
      for (int b0 = j0; b0 < j1; b0 += kBlock) {
        const int cols = std::min(kBlock, j1 - b0);
        B.setZero(nI, cols);
        for (int j = b0; j < b0 + cols; ++j)
          for (std::size_t e = colStart[size_t(j)]; e < colStart[size_t(j) + 1]; ++e)
            B(rhs[e].row, j - b0) += rhs[e].value;
        if (amd)
          X.middleCols(b0, cols) = ldltAmd.solve(B);
        else
          X.middleCols(b0, cols) = ldltNatural.solve(B);
      }
    });
  }
  const double solveSeconds = since(ts);

  // 6. Trilinear lookup. A point whose cell has values at all 8 corners interpolates them (the
  //    unknowns' solutions, the boundary nodes' hat values); any other point (outside the cage
  //    by more than about a cell, or off the grid) takes the hat values of its closest cage
  //    point, i.e. the boundary values continued outward along the normal.
  const auto tl = Clock::now();
  Embedding::DenseD W = Embedding::DenseD::Zero(n, m);
  std::vector<unsigned char> usedClosest(size_t(n), 0);
  parallelRanges(n, 256, threads, [&](int p0, int p1) {
    for (int p = p0; p < p1; ++p) {
      const Vec3 u = (points[size_t(p)] - origin) / h;
      std::array<std::int64_t, 3> c{};
      bool onGrid = true;
      for (int a = 0; a < 3; ++a) {
        const double f = std::floor(u[a]);
        if (!(f >= 0.0 && f <= double(dims[size_t(a)] - 2))) onGrid = false;
        c[size_t(a)] = onGrid ? std::int64_t(f) : 0;
      }
      const std::int64_t id0 = c[0] + nx * (c[1] + ny * c[2]);
      bool valued = onGrid;
      for (int corner = 0; valued && corner < 8; ++corner) {
        const std::int64_t id = id0 + (corner & 1) * step[0] + ((corner >> 1) & 1) * step[1] +
                                ((corner >> 2) & 1) * step[2];
        valued = unknown[size_t(id)] >= 0 || closestTri[size_t(id)] >= 0;
      }
      auto row = W.row(p);
      if (!valued) {
        const CagePoint cp = closestCagePoint(points[size_t(p)], cage);
        for (int k = 0; k < 3; ++k) row[T[size_t(cp.triangle)][size_t(k)]] += cp.bary[k];
        usedClosest[size_t(p)] = 1;
        continue;
      }
      const Vec3 f(u[0] - double(c[0]), u[1] - double(c[1]), u[2] - double(c[2]));
      for (int corner = 0; corner < 8; ++corner) {
        const std::int64_t id = id0 + (corner & 1) * step[0] + ((corner >> 1) & 1) * step[1] +
                                ((corner >> 2) & 1) * step[2];
        const double t = ((corner & 1) ? f[0] : 1.0 - f[0]) *
                         (((corner >> 1) & 1) ? f[1] : 1.0 - f[1]) *
                         (((corner >> 2) & 1) ? f[2] : 1.0 - f[2]);
        if (t == 0.0) continue;
        const int r = unknown[size_t(id)];
        if (r >= 0) {
          row += t * X.row(r);
        } else {
          const int tri = closestTri[size_t(id)];
          for (int k = 0; k < 3; ++k) row[T[size_t(tri)][size_t(k)]] += t * bary[size_t(id)][k];
        }
      }
    }
  });
  if (cg) {
    // The exact weights sum to 1; CG stops short of that by about its tolerance, so the rows are
    // rescaled to keep the partition of unity to round-off (w ≥ 0 is unchanged by it).
    for (int p = 0; p < n; ++p) {
      const double sum = W.row(p).sum();
      if (sum > 0.0) W.row(p) /= sum;
    }
  }
  const double lookupSeconds = since(tl);

  HarmonicReport rep;
  rep.gridNodes = dims;
  rep.cellSize = h;
  rep.interiorNodes = nI;
  rep.boundaryNodes = nB;
  rep.cutArms = cutArms;
  rep.factorNonZeros = nI == 0 ? 0
                       : cg    ? multigrid->coarseFactorNonZeros()
                       : amd   ? ldltAmd.matrixL().nestedExpression().nonZeros()
                               : ldltNatural.matrixL().nestedExpression().nonZeros();
  for (const int its : cgIterations) rep.maxCgIterations = std::max(rep.maxCgIterations, its);
  rep.classifySeconds = classifySeconds;
  rep.factorSeconds = factorSeconds;
  rep.solveSeconds = solveSeconds;
  rep.lookupSeconds = lookupSeconds;
  rep.minWeight = n > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  double maxWeight = n > 0 ? -std::numeric_limits<double>::infinity() : 0.0;
  std::int64_t negatives = 0;
  Eigen::Matrix<double, Eigen::Dynamic, 3> cageMat(m, 3);
  for (int j = 0; j < m; ++j) cageMat.row(j) = V[size_t(j)].transpose();
  for (int p = 0; p < n; ++p) {
    rep.closestPointPoints += usedClosest[size_t(p)];
    rep.maxSumError = std::max(rep.maxSumError, std::abs(W.row(p).sum() - 1.0));
    rep.minWeight = std::min(rep.minWeight, W.row(p).minCoeff());
    maxWeight = std::max(maxWeight, W.row(p).maxCoeff());
    negatives += (W.row(p).array() < 0.0).count();
    const Vec3 x = (W.row(p) * cageMat).transpose();
    rep.maxLinearError = std::max(rep.maxLinearError, (x - points[size_t(p)]).norm() / diagonal);
  }

  Embedding e = Embedding::fromDense(std::move(W), options.keepDoublePrecision);
  e.setKind(EmbeddingKind::Harmonic);
  rep.totalSeconds = since(t0);
  BindStats& st = e.stats();
  st.seconds = rep.totalSeconds;
  st.threads = threads;
  st.minWeight = rep.minWeight;
  st.maxWeight = maxWeight;
  st.negativeCount = negatives;
  st.maxSumError = rep.maxSumError;
  st.maxLinearError = rep.maxLinearError;
  st.unprunedLinearError = rep.maxLinearError;
  if (reportOut) *reportOut = rep;
  return e;
}

}  // namespace sb::cage
