#include "sim/cage/embedding.h"

#include <sys/stat.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include "sim/base/file_io.h"
#include "sim/base/parallel_for.h"
#include "sim/cage/deform_kernels.h"
#include "sim/cage/green.h"
#include "sim/cage/mvc.h"
#include "sim/cage/polygon_mvc.h"
#include "sim/mesh/closed_surface.h"

namespace sb::cage {

using mesh::TriangleMesh;

namespace {

using Vec3 = Eigen::Vector3d;

// Prunes one row in place (see BindOptions::pruneThreshold). q_j = (v_j − x) / L.
// Returns the L1 norm of the change.
double pruneRow(std::vector<std::pair<int, double>>& row, const double* w, int m,
                const std::vector<Vec3>& q, double threshold) {
  // Drop the smallest |w_j| while their total stays within threshold · Σ|w| (ties: by index).
  std::vector<std::pair<double, int>> order;
  order.reserve(static_cast<std::size_t>(m));
  double total = 0.0;
  for (int j = 0; j < m; ++j) {
    order.emplace_back(std::abs(w[j]), j);
    total += std::abs(w[j]);
  }
  std::sort(order.begin(), order.end());
  const double budget = threshold * total;
  double droppedMass = 0.0;
  std::size_t nDrop = 0;
  while (nDrop < order.size() && droppedMass + order[nDrop].first <= budget)
    droppedMass += order[nDrop++].first;
  row.clear();
  std::vector<std::pair<double, int>> droppedList(
      order.begin(), order.begin() + static_cast<std::ptrdiff_t>(nDrop));
  for (std::size_t k = nDrop; k < order.size(); ++k)
    row.emplace_back(order[k].second, w[order[k].second]);
  std::sort(row.begin(), row.end());
  // Exact zeros carry nothing: drop them without counting.
  row.erase(std::remove_if(row.begin(), row.end(), [](const auto& e) { return e.second == 0.0; }),
            row.end());
  if (droppedList.empty()) return 0.0;
  auto column = [&](int j) { return Eigen::Vector4d(1.0, q[j].x(), q[j].y(), q[j].z()); };
  // The kept vertices must span 3D (well conditioned) for the correction to exist: if they do
  // not, keep the largest dropped weights too, one at a time.
  std::sort(droppedList.begin(), droppedList.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  std::size_t nextDropped = 0;
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  for (const auto& [j, wj] : row) M += std::abs(wj) * column(j) * column(j).transpose();
  Eigen::FullPivLU<Eigen::Matrix4d> lu;
  lu.setThreshold(1e-10);
  while (true) {
    lu.compute(M);
    if (lu.rank() == 4 || nextDropped == droppedList.size()) break;
    const int j = droppedList[nextDropped++].second;
    row.emplace_back(j, w[j]);
    M += std::abs(w[j]) * column(j) * column(j).transpose();
  }
  std::sort(row.begin(), row.end());
  Eigen::Vector4d r = Eigen::Vector4d::Zero();  // dropped mass and moment
  double change = 0.0;
  for (std::size_t k = nextDropped; k < droppedList.size(); ++k) {
    const int j = droppedList[k].second;
    r += w[j] * column(j);
    change += std::abs(w[j]);
  }
  if (change == 0.0) return 0.0;
  if (lu.rank() == 4) {
    // Weighted minimum-norm correction: δ = D Aᵀ (A D Aᵀ)⁻¹ r, D = diag|w_j|, A's columns (1, q_j).
    // Two refinement passes on the residual keep Σw and Σ w q exact when M is ill-conditioned.
    std::vector<double> scale(row.size());
    for (std::size_t k = 0; k < row.size(); ++k) scale[k] = std::abs(row[k].second);
    std::vector<double> delta(row.size(), 0.0);
    Eigen::Vector4d residual = r;
    for (int pass = 0; pass < 3; ++pass) {
      const Eigen::Vector4d lambda = lu.solve(residual);
      for (std::size_t k = 0; k < row.size(); ++k) {
        const double d = scale[k] * column(row[k].first).dot(lambda);
        delta[k] += d;
        residual -= d * column(row[k].first);
      }
    }
    for (std::size_t k = 0; k < row.size(); ++k) {
      row[k].second += delta[k];
      change += std::abs(delta[k]);
    }
  } else {
    // Cannot happen for a valid cage (all vertices span 3D); restore Σw = 1 only.
    double keptAbs = 0.0;
    for (const auto& e : row) keptAbs += std::abs(e.second);
    for (auto& [j, wj] : row) {
      const double delta = r[0] * std::abs(wj) / keptAbs;
      wj += delta;
      change += std::abs(delta);
    }
  }
  return change;
}

}  // namespace

namespace {

// The weights of one point: triangle MVC (mvc.h), or polygon MVC (polygon_mvc.h) when the cage
// has faces of more than three corners (mesh::hasPolygonFaces), so a quad cage's weights do not
// depend on the diagonal its file reader picked. A triangle cage takes the triangle path
// unchanged (same bits, same speed).
struct CageWeights {
  const MeanValueCage& triangles;
  const PolygonMeanValueCage* polygons;
  struct Scratch {
    MeanValueCage::Scratch triangles;
    PolygonMeanValueCage::Scratch polygons;
  };
  bool operator()(const Vec3& x, double* w, Scratch& s, MvcInfo* info = nullptr) const {
    return polygons ? polygons->weights(x, w, s.polygons, info)
                    : triangles.weights(x, w, s.triangles, info);
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Embedding

Embedding Embedding::fromDense(DenseD weights, bool keepDouble) {
  Embedding e;
  e.rows_ = static_cast<int>(weights.rows());
  e.cols_ = static_cast<int>(weights.cols());
  e.sparse_ = false;
  e.denseD_ = std::move(weights);
  e.hasDouble_ = true;
  e.makeFloat();
  if (!keepDouble) {
    e.denseD_ = DenseD();
    e.hasDouble_ = false;
  }
  e.stats_.nonZeros = static_cast<std::int64_t>(e.rows_) * e.cols_;
  return e;
}

void Embedding::swap(Embedding& other) noexcept {
  std::swap(rows_, other.rows_);
  std::swap(cols_, other.cols_);
  std::swap(kind_, other.kind_);
  std::swap(sparse_, other.sparse_);
  std::swap(hasDouble_, other.hasDouble_);
  denseD_.swap(other.denseD_);
  panelsF_.swap(other.panelsF_);
  sparseD_.swap(other.sparseD_);
  sparseF_.swap(other.sparseF_);
  std::swap(stats_, other.stats_);
  greenCage_.swap(other.greenCage_);
  std::swap(greenCageVertices_, other.greenCageVertices_);
}

void Embedding::attachGreenCage(std::shared_ptr<const mesh::TriangleMesh> restCage) {
  if (kind_ != EmbeddingKind::Green || !restCage)
    throw std::invalid_argument("Embedding::attachGreenCage: not a Green embedding, or no cage");
  const std::size_t controls = restCage->vertices.size() + restCage->triangles.size();
  if (controls != std::size_t(cols_))
    throw std::invalid_argument("Embedding::attachGreenCage: a cage of " +
                                std::to_string(restCage->vertices.size()) + " vertices and " +
                                std::to_string(restCage->triangles.size()) + " faces for " +
                                std::to_string(cols_) + " weight columns");
  greenCageVertices_ = static_cast<int>(restCage->vertices.size());
  greenCage_ = std::move(restCage);
}

Embedding Embedding::fromSparse(SparseD&& weights, bool keepDouble) {
  Embedding e;
  weights.makeCompressed();
  e.rows_ = static_cast<int>(weights.rows());
  e.cols_ = static_cast<int>(weights.cols());
  e.sparse_ = true;
  e.sparseD_.swap(weights);  // Eigen 3.4's sparse move-assignment copies
  e.hasDouble_ = true;
  e.makeFloat();
  if (!keepDouble) {
    e.sparseD_ = SparseD();
    e.hasDouble_ = false;
  }
  e.stats_.nonZeros = e.sparseF_.nonZeros();
  return e;
}

void Embedding::makeFloat() {
  if (sparse_) {
    // The same compressed structure with float values, filled in place: a cast<float>() builds
    // it through a generic sparse assignment that reallocates as it goes (most of an FFD bind's
    // time went there).
    const Eigen::Index nnz = sparseD_.nonZeros();
    sparseF_ = SparseF(rows_, cols_);
    sparseF_.resizeNonZeros(nnz);
    std::copy(sparseD_.outerIndexPtr(), sparseD_.outerIndexPtr() + rows_ + 1,
              sparseF_.outerIndexPtr());
    std::copy(sparseD_.innerIndexPtr(), sparseD_.innerIndexPtr() + nnz, sparseF_.innerIndexPtr());
    std::transform(sparseD_.valuePtr(), sparseD_.valuePtr() + nnz, sparseF_.valuePtr(),
                   [](double w) { return static_cast<float>(w); });
  } else {
    panelsF_ = PanelWeights(rows_, cols_);
    for (int i = 0; i < rows_; ++i)
      for (int j = 0; j < cols_; ++j) panelsF_.at(i, j) = static_cast<float>(denseD_(i, j));
  }
}

std::int64_t Embedding::nonZeros() const {
  return sparse_ ? static_cast<std::int64_t>(sparseF_.nonZeros())
                 : static_cast<std::int64_t>(rows_) * cols_;
}

void Embedding::deform(ConstPointsRef cagePositions, PointsRowMajor& out) const {
  deformMany({cagePositions}, {&out});
}

void Embedding::deformMany(const std::vector<ConstPointsRef>& cages,
                           const std::vector<PointsRowMajor*>& outs) const {
  if (!greenCage_) return deformWeights(cages, outs);
  // Green: the cage vertices and each face's stretch × outward normal, in double (the face
  // frames are a cross product of differences), then the float product like every kind.
  std::vector<PointsRowMajor> extended(cages.size());
  std::vector<ConstPointsRef> controls;
  for (std::size_t k = 0; k < cages.size(); ++k) {
    if (cages[k].rows() != greenCageVertices_)
      throw std::invalid_argument("Embedding::deform: got " + std::to_string(cages[k].rows()) +
                                  " cage positions, the Green cage has " +
                                  std::to_string(greenCageVertices_));
    extended[k] = greenControls(*greenCage_, cages[k].cast<double>()).cast<float>();
    controls.emplace_back(extended[k]);
  }
  deformWeights(controls, outs);
}

void Embedding::deformWeights(const std::vector<ConstPointsRef>& cages,
                              const std::vector<PointsRowMajor*>& outs) const {
  if (cages.size() != outs.size())
    throw std::invalid_argument("Embedding::deformMany: " + std::to_string(cages.size()) +
                                " cages but " + std::to_string(outs.size()) + " outputs");
  for (const ConstPointsRef& cage : cages)
    if (cage.rows() != cols_)
      throw std::invalid_argument("Embedding::deform: got " + std::to_string(cage.rows()) +
                                  " cage positions, the embedding has " + std::to_string(cols_));
  const int m = cols_;
  const size_t count = cages.size();
  // Each cage as three contiguous float arrays (dense) or (x, y, z, 0) quadruples (sparse: one
  // 16-byte load per nonzero; operator new aligns to 16 bytes): a few KB each, in L1.
  static_assert(__STDCPP_DEFAULT_NEW_ALIGNMENT__ >= 16);
  const size_t stride = sparse_ ? 4 * size_t(m) : 3 * size_t(m);
  std::vector<float> packed(count * stride, 0.0f);
  for (size_t k = 0; k < count; ++k) {
    float* c = packed.data() + k * stride;
    for (int j = 0; j < m; ++j)
      for (int a = 0; a < 3; ++a)
        c[sparse_ ? 4 * size_t(j) + size_t(a) : size_t(a) * size_t(m) + size_t(j)] = cages[k](j, a);
    outs[k]->resize(rows_, 3);
  }
  // W streams once, a block of rows at a time, against every cage: bound by the multiply-adds
  // once the block is in cache (deform_kernels.h). Blocks are independent: one range of them
  // per thread (sim/base/parallel_for.h); 256 rows of a 164-vertex cage are 168 KB. A row's
  // result does not depend on the block or on the other cages (deform_kernels.h), so deform and
  // deformMany agree bit for bit.
  const DeformIsa isa = deformKernelIsa();
  constexpr int kBlock = 256;
  static_assert(kBlock % PanelWeights::kPanelRows == 0);
  const int blocks = (rows_ + kBlock - 1) / kBlock;
  std::vector<const float*> cagePointers(count);
  std::vector<float*> outPointers(count);
  for (size_t k = 0; k < count; ++k) {
    cagePointers[k] = packed.data() + k * stride;
    outPointers[k] = outs[k]->data();
  }
  parallelFor(blocks, count > 1 ? 2 : 8, [&](int b) {
    const int begin = b * kBlock, end = std::min(rows_, begin + kBlock);
    if (sparse_) {
      for (size_t k = 0; k < count; ++k)
        sparseDeformRows(sparseF_.outerIndexPtr(), sparseF_.innerIndexPtr(), sparseF_.valuePtr(),
                         cagePointers[k], outPointers[k], begin, end, isa);
    } else {
      constexpr int kPanels = kBlock / PanelWeights::kPanelRows;
      panelDeformRows(panelsF_, cagePointers.data(), outPointers.data(), int(count), b * kPanels,
                      std::min(panelsF_.panels(), (b + 1) * kPanels), isa);
    }
  });
}

// The float weights as a row-major matrix (deformDouble without double weights).
Embedding::DenseD Embedding::floatWeights() const {
  DenseD W(rows_, cols_);
  for (int i = 0; i < rows_; ++i)
    for (int j = 0; j < cols_; ++j) W(i, j) = static_cast<double>(panelsF_.at(i, j));
  return W;
}

void Embedding::deformDouble(const Eigen::Matrix<double, Eigen::Dynamic, 3>& cagePositions,
                             Eigen::Matrix<double, Eigen::Dynamic, 3>& out) const {
  if (cagePositions.rows() != cageVertexCount())
    throw std::invalid_argument(
        "Embedding::deformDouble: got " + std::to_string(cagePositions.rows()) +
        " cage positions, the embedding takes " + std::to_string(cageVertexCount()));
  Eigen::Matrix<double, Eigen::Dynamic, 3> extended;
  if (greenCage_) extended = greenControls(*greenCage_, cagePositions);
  const Eigen::Matrix<double, Eigen::Dynamic, 3>& controls = greenCage_ ? extended : cagePositions;
  if (hasDouble_) {
    if (sparse_)
      out.noalias() = sparseD_ * controls;
    else
      out.noalias() = denseD_ * controls;
  } else {
    if (sparse_)
      out.noalias() = sparseF_.cast<double>() * controls;
    else
      out.noalias() = floatWeights() * controls;
  }
}

void Embedding::rowWeights(int i, std::vector<std::pair<int, double>>& out) const {
  out.clear();
  if (i < 0 || i >= rows_)
    throw std::out_of_range("Embedding::rowWeights: row " + std::to_string(i));
  if (sparse_) {
    if (hasDouble_) {
      for (SparseD::InnerIterator it(sparseD_, i); it; ++it) out.emplace_back(it.col(), it.value());
    } else {
      for (SparseF::InnerIterator it(sparseF_, i); it; ++it) out.emplace_back(it.col(), it.value());
    }
  } else {
    for (int j = 0; j < cols_; ++j) {
      const double v = hasDouble_ ? denseD_(i, j) : static_cast<double>(panelsF_.at(i, j));
      if (v != 0.0) out.emplace_back(j, v);
    }
  }
}

Embedding bindMeanValue(const std::vector<Vec3>& points, const TriangleMesh& cage,
                        const BindOptions& options) {
  mesh::validateClosedSurface(cage, "cage");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite())
      throw std::invalid_argument("bind: point " + std::to_string(i) + " is not finite");
  }
  std::array<std::uint64_t, 2> key{};
  std::string cachePath;
  if (!options.cacheDir.empty()) {
    key = bindCacheKey(points, cage, options);
    cachePath = bindCachePath(options.cacheDir, key);
    if (std::optional<Embedding> cached =
            loadCachedBind(cachePath, key, EmbeddingKind::MeanValue, int(points.size()),
                           int(cage.vertices.size()), options))
      return std::move(*cached);
  }

  const auto t0 = std::chrono::steady_clock::now();
  const MeanValueCage prepared(cage);
  std::optional<PolygonMeanValueCage> polygons;
  if (mesh::hasPolygonFaces(cage)) polygons.emplace(cage);
  const CageWeights weigh{prepared, polygons ? &*polygons : nullptr};
  const int n = static_cast<int>(points.size());
  const int m = prepared.vertexCount();
  const double L = prepared.diagonal();
  Eigen::AlignedBox3d box;
  for (const auto& v : cage.vertices) box.extend(v);
  const Vec3 centre = box.center();

  bool sparse = options.storage == WeightStorage::Sparse ||
                (options.storage == WeightStorage::Auto && m > options.denseMaxCageVertices);
  const int threads =
      options.threads > 0 ? std::min(options.threads, threadCount()) : threadCount();
  // Memory first (BindOptions::maxWeightBytes): dense keeps a double and a float copy.
  const double denseBytes = 12.0 * double(n) * double(m);
  const bool denseTooBig = denseBytes > double(options.maxWeightBytes);
  if (denseTooBig && options.storage == WeightStorage::Dense)
    throw std::runtime_error("bind: dense weights for " + std::to_string(n) + " points × " +
                             std::to_string(m) + " cage vertices need " +
                             formatBytes(std::uint64_t(denseBytes)) + ", more than the " +
                             formatBytes(options.maxWeightBytes) + " allowed; use sparse storage");
  if (denseTooBig) sparse = true;
  // Pruned weights kept per row, estimated on up to 64 evenly spaced points (a sparse bind's
  // size, and whether pruning pays at all).
  std::int64_t kept = 0;
  int samples = 0;
  if (sparse && n > 0) {
    samples = std::min(n, 64);
    CageWeights::Scratch scratch;
    std::vector<double> w(static_cast<std::size_t>(m));
    std::vector<Vec3> q(static_cast<std::size_t>(m));
    std::vector<std::pair<int, double>> row;
    for (int k = 0; k < samples; ++k) {
      const Vec3& x = points[static_cast<std::size_t>(static_cast<std::int64_t>(k) * n / samples)];
      if (!weigh(x, w.data(), scratch)) continue;
      for (int j = 0; j < m; ++j) q[j] = (cage.vertices[j] - x) / L;
      pruneRow(row, w.data(), m, q, options.pruneThreshold);
      kept += static_cast<std::int64_t>(row.size());
    }
    const double sparseBytes = 52.0 * double(kept) / double(samples) * double(n);
    if (sparseBytes > double(options.maxWeightBytes))
      throw std::runtime_error(
          "bind: the weights for " + std::to_string(n) + " points × " + std::to_string(m) +
          " cage vertices need about " + formatBytes(std::uint64_t(sparseBytes)) +
          " even sparse, more than the " + formatBytes(options.maxWeightBytes) +
          " allowed (BindOptions::maxWeightBytes)");
  }
  if (sparse && options.storage == WeightStorage::Auto && n > 0 && !denseTooBig) {
    // Auto: sparse only when pruning keeps at most half of the entries; otherwise store dense
    // and unpruned.
    sparse = 2 * kept <= static_cast<std::int64_t>(samples) * m;
  }

  Embedding::DenseD dense;
  std::vector<std::vector<std::pair<int, double>>> rows;
  if (sparse)
    rows.resize(static_cast<std::size_t>(n));
  else
    dense.resize(n, m);

  // Per-point figures, reduced serially afterwards (deterministic).
  std::vector<double> linErr(n, 0.0), linErr0(n, 0.0), pruneErr(n, 0.0), prunedL1(n, 0.0),
      cond(n, 1.0);
  std::vector<char> onCage(n, 0), failed(n, 0);

  const int block = 256;
  for (int start = 0; start < n; start += block) {
    const int end = std::min(n, start + block);
    parallelRanges(end - start, 2, threads, [&](int rangeBegin, int rangeEnd) {
      CageWeights::Scratch scratch;
      std::vector<double> w(static_cast<std::size_t>(m));
      std::vector<Vec3> q;
      for (int i = start + rangeBegin; i < start + rangeEnd; ++i) {
        const Vec3& x = points[static_cast<std::size_t>(i)];
        MvcInfo info;
        if (!weigh(x, w.data(), scratch, &info)) failed[i] = 1;
        cond[i] = info.conditioning;
        onCage[i] = info.kind != MvcCase::General;
        Vec3 p = Vec3::Zero();
        for (int j = 0; j < m; ++j) p += w[j] * cage.vertices[j];
        linErr0[i] = (p - x).norm() / L;
        if (sparse) {
          q.resize(static_cast<std::size_t>(m));
          for (int j = 0; j < m; ++j) q[j] = (cage.vertices[j] - x) / L;
          auto& row = rows[static_cast<std::size_t>(i)];
          prunedL1[i] = pruneRow(row, w.data(), m, q, options.pruneThreshold);
          Vec3 pp = Vec3::Zero();
          for (const auto& [j, wj] : row) pp += wj * cage.vertices[j];
          linErr[i] = (pp - x).norm() / L;
          pruneErr[i] = (pp - p).norm() / L;
        } else {
          for (int j = 0; j < m; ++j) dense(i, j) = w[j];
          linErr[i] = linErr0[i];
        }
      }
    });
    if (options.progress)
      options.progress(static_cast<std::size_t>(end), static_cast<std::size_t>(n));
  }
  for (int i = 0; i < n; ++i) {
    if (failed[i]) {
      std::ostringstream s;
      s.precision(17);
      s << "bind: mean value coordinates of point " << i << " (" << points[i].transpose()
        << ") cannot be normalised (weight sum 0 or not finite)";
      throw std::runtime_error(s.str());
    }
  }

  Embedding e;
  std::int64_t totalNnz = 0;
  if (sparse) {
    for (const auto& r : rows) totalNnz += static_cast<std::int64_t>(r.size());
  }
  if (sparse) {
    std::vector<Eigen::Triplet<double>> trips;
    trips.reserve(static_cast<std::size_t>(totalNnz));
    for (int i = 0; i < n; ++i)
      for (const auto& [j, wj] : rows[static_cast<std::size_t>(i)]) trips.emplace_back(i, j, wj);
    Embedding::SparseD W(n, m);
    W.setFromTriplets(trips.begin(), trips.end());
    rows.clear();
    rows.shrink_to_fit();
    e = Embedding::fromSparse(std::move(W), options.keepDoublePrecision);
  } else {
    e = Embedding::fromDense(std::move(dense), options.keepDoublePrecision);
  }

  BindStats& st = e.stats();
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.threads = threads;
  st.fromCache = false;
  st.nonZeros = e.nonZeros();
  st.minWeight = std::numeric_limits<double>::infinity();
  st.maxWeight = -std::numeric_limits<double>::infinity();
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < n; ++i) {
    e.rowWeights(i, row);
    double sum = 0.0;
    for (const auto& [j, wj] : row) {
      sum += wj;
      st.minWeight = std::min(st.minWeight, wj);
      st.maxWeight = std::max(st.maxWeight, wj);
      if (wj < 0.0) ++st.negativeCount;
    }
    st.maxSumError = std::max(st.maxSumError, std::abs(sum - 1.0));
    st.maxLinearError = std::max(st.maxLinearError, linErr[i]);
    st.unprunedLinearError = std::max(st.unprunedLinearError, linErr0[i]);
    st.pruningError = std::max(st.pruningError, pruneErr[i]);
    st.maxPrunedL1 = std::max(st.maxPrunedL1, prunedL1[i]);
    st.worstConditioning = std::max(st.worstConditioning, cond[i]);
    if ((points[i] - centre).norm() > 4.0 * L) ++st.farPoints;
    if (onCage[i]) ++st.onCagePoints;
  }
  if (n == 0) st.minWeight = st.maxWeight = 0.0;

  if (!cachePath.empty()) saveCachedBind(e, cachePath, key, options);
  return e;
}

namespace {
void warnOf(const BindOptions& options, const std::string& msg) {
  if (options.warning)
    options.warning(msg);
  else
    std::cerr << "warning: " << msg << "\n";
}
}  // namespace

std::optional<Embedding> loadCachedBind(const std::string& path,
                                        const std::array<std::uint64_t, 2>& key, EmbeddingKind kind,
                                        int rows, int cols, const BindOptions& options) {
  struct stat sb;
  if (::stat(path.c_str(), &sb) != 0) return std::nullopt;
  try {
    std::array<std::uint64_t, 2> stored{};
    Embedding e = Embedding::load(path, &stored);
    if (stored != key || e.kind() != kind || e.meshVertexCount() != rows ||
        e.weightColumns() != cols)
      throw std::runtime_error(path + ": key, kind or size mismatch");
    e.stats().fromCache = true;
    e.stats().seconds = 0.0;
    return e;
  } catch (const std::exception& ex) {
    warnOf(options, std::string("ignoring bind cache: ") + ex.what() + "; binding again");
  }
  return std::nullopt;
}

void saveCachedBind(const Embedding& e, const std::string& path,
                    const std::array<std::uint64_t, 2>& key, const BindOptions& options) {
  try {
    e.save(path, key);
  } catch (const std::exception& ex) {
    warnOf(options, std::string("could not write bind cache: ") + ex.what());
  }
}

void measureWeights(Embedding& e, const std::vector<Vec3>& points,
                    const std::vector<Vec3>& controls) {
  const int n = e.meshVertexCount();
  if (static_cast<int>(points.size()) != n ||
      static_cast<int>(controls.size()) != e.weightColumns())
    throw std::invalid_argument("measureWeights: " + std::to_string(points.size()) +
                                " points and " + std::to_string(controls.size()) +
                                " controls for a " + std::to_string(n) + " × " +
                                std::to_string(e.cageVertexCount()) + " weight matrix");
  Eigen::AlignedBox3d box;
  for (const Vec3& c : controls) box.extend(c);
  const double L = box.diagonal().norm() > 0.0 ? box.diagonal().norm() : 1.0;
  BindStats& st = e.stats();
  st.nonZeros = e.nonZeros();
  st.minWeight = n > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  st.maxWeight = n > 0 ? -std::numeric_limits<double>::infinity() : 0.0;
  st.negativeCount = 0;
  st.maxSumError = st.maxLinearError = 0.0;
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < n; ++i) {
    e.rowWeights(i, row);
    double sum = 0.0;
    Vec3 p = Vec3::Zero();
    for (const auto& [j, wj] : row) {
      if (!std::isfinite(wj))
        throw std::runtime_error("bind: weight (" + std::to_string(i) + ", " + std::to_string(j) +
                                 ") is not finite");
      sum += wj;
      p += wj * controls[size_t(j)];
      st.minWeight = std::min(st.minWeight, wj);
      st.maxWeight = std::max(st.maxWeight, wj);
      if (wj < 0.0) ++st.negativeCount;
    }
    st.maxSumError = std::max(st.maxSumError, std::abs(sum - 1.0));
    st.maxLinearError = std::max(st.maxLinearError, (p - points[size_t(i)]).norm() / L);
  }
  st.unprunedLinearError = st.maxLinearError;
}

const char* embeddingKindName(EmbeddingKind kind) {
  switch (kind) {
    case EmbeddingKind::MeanValue:
      return "mvc";
    case EmbeddingKind::Harmonic:
      return "harmonic";
    case EmbeddingKind::Rbf:
      return "rbf";
    case EmbeddingKind::FfdBernstein:
      return "ffd-bernstein";
    case EmbeddingKind::FfdBSpline:
      return "ffd-bspline";
    case EmbeddingKind::Green:
      return "green";
  }
  return "?";
}

bool parseEmbeddingKind(const std::string& name, EmbeddingKind* kind) {
  for (int k = 0; k < kEmbeddingKindCount; ++k) {
    if (name == embeddingKindName(static_cast<EmbeddingKind>(k))) {
      *kind = static_cast<EmbeddingKind>(k);
      return true;
    }
  }
  return false;
}

}  // namespace sb::cage
