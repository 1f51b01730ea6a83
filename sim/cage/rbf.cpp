#include "sim/cage/rbf.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "sim/base/parallel_for.h"

namespace sb::cage {
namespace {

std::string at(const Vec3& p) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

// Mean distance from each handle to its nearest other handle (O(n²): n ≤ kMaxRbfHandles).
// Refuses coincident handles: their rows of M would be equal.
double meanNearestDistance(const std::vector<Vec3>& handles, double diagonal) {
  const int n = static_cast<int>(handles.size());
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    double best = std::numeric_limits<double>::infinity();
    int bestJ = -1;
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      const double d = (handles[size_t(i)] - handles[size_t(j)]).norm();
      if (d < best) best = d, bestJ = j;
    }
    if (!(best > 1e-12 * diagonal))
      throw std::invalid_argument("rbf: handles " + std::to_string(std::min(i, bestJ)) + " and " +
                                  std::to_string(std::max(i, bestJ)) + " are at the same place " +
                                  at(handles[size_t(i)]));
    sum += best;
  }
  return sum / n;
}

}  // namespace

Embedding bindRbf(const std::vector<Vec3>& points, const std::vector<Vec3>& handles,
                  const RbfOptions& options) {
  const int n = static_cast<int>(handles.size());
  if (n < 4)
    throw std::invalid_argument(
        "rbf: needs at least 4 handles (the affine part has 4 unknowns)"
        ", got " +
        std::to_string(n));
  if (n > kMaxRbfHandles)
    throw std::invalid_argument("rbf: " + std::to_string(n) + " handles, more than the " +
                                std::to_string(kMaxRbfHandles) +
                                " accepted (the dense solve grows like n³)");
  if (!(options.shape >= 0.0 && options.shape <= 10.0))
    throw std::invalid_argument("rbf: shape must be in [0, 10], got " +
                                std::to_string(options.shape));
  for (int i = 0; i < n; ++i)
    if (!handles[size_t(i)].allFinite())
      throw std::invalid_argument("rbf: handle " + std::to_string(i) + " is not finite");
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite())
      throw std::invalid_argument("rbf: point " + std::to_string(i) + " is not finite");

  const auto t0 = std::chrono::steady_clock::now();
  Eigen::AlignedBox3d box;
  for (const Vec3& c : handles) box.extend(c);
  const double diagonal = box.diagonal().norm();
  if (!(diagonal > 0.0)) throw std::invalid_argument("rbf: all handles are at the same place");
  const double s = options.shape * meanNearestDistance(handles, diagonal);
  const double s2 = s * s;

  // Affine part in coordinates centred and scaled by the handles' box: the same space of
  // functions, but P's columns are of size 1 instead of |x| (M's conditioning then does not
  // depend on where the handles are in the world).
  const Vec3 centre = box.center();
  const double scale = 2.0 / diagonal;
  Eigen::MatrixXd P(n, 4);
  for (int i = 0; i < n; ++i) {
    P(i, 0) = 1.0;
    P.block<1, 3>(i, 1) = ((handles[size_t(i)] - centre) * scale).transpose();
  }
  Eigen::FullPivLU<Eigen::MatrixXd> affine(P);
  affine.setThreshold(1e-9);
  if (affine.rank() < 4)
    throw std::invalid_argument(
        "rbf: the handles lie in one plane (or on a line); the affine part needs 4 handles "
        "that are not coplanar");

  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 4, n + 4);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      M(i, j) = std::sqrt((handles[size_t(i)] - handles[size_t(j)]).squaredNorm() + s2);
  M.topRightCorner(n, 4) = P;
  M.bottomLeftCorner(4, n) = P.transpose();
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(M);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n + 4, n);
  rhs.topRows(n).setIdentity();
  // B = M⁻¹[I; 0]: row k of W(x) is [φ(x), 1, x̂ᵀ] · B. Checked by its residual: a system too
  // ill-conditioned for the shape chosen gives weights that are not what the formulas say.
  const Eigen::MatrixXd B = lu.solve(rhs);
  const double residual = (M * B - rhs).cwiseAbs().maxCoeff();
  if (!(residual < 1e-6))
    throw std::runtime_error("rbf: the system is too ill-conditioned to solve (residual " +
                             std::to_string(residual) + "); use a smaller shape than " +
                             std::to_string(options.shape));

  const int count = static_cast<int>(points.size());
  Embedding::DenseD W(count, n);
  const int threads =
      options.threads > 0 ? std::min(options.threads, threadCount()) : threadCount();
  // Rows in blocks: each block is one matrix product [Φ_x, P_x] · B, fixed in size and order
  // whatever the thread count (bit-identical results).
  constexpr int kBlock = 512;
  const int blocks = (count + kBlock - 1) / kBlock;
  parallelRanges(blocks, 2, threads, [&](int blockBegin, int blockEnd) {
    Eigen::MatrixXd A(kBlock, n + 4);
    for (int b = blockBegin; b < blockEnd; ++b) {
      const int first = b * kBlock, rows = std::min(kBlock, count - first);
      for (int r = 0; r < rows; ++r) {
        const Vec3& x = points[size_t(first + r)];
        for (int j = 0; j < n; ++j)
          A(r, j) = std::sqrt((x - handles[size_t(j)]).squaredNorm() + s2);
        A(r, n) = 1.0;
        A.block<1, 3>(r, n + 1) = ((x - centre) * scale).transpose();
      }
      W.middleRows(first, rows).noalias() = A.topRows(rows) * B;
    }
  });

  Embedding e = Embedding::fromDense(std::move(W));
  e.setKind(EmbeddingKind::Rbf);
  measureWeights(e, points, handles);
  BindStats& st = e.stats();
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.threads = threads;
  return e;
}

}  // namespace sb::cage
