// A mesh embedded in a cage: the weight matrix W (#mesh vertices × #cage vertices) that maps
// cage positions to mesh positions, and the mean value coordinate bind that computes it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "sim/base/types.h"
#include "sim/cage/panel_weights.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

// Figures about a bind, filled by bindMeanValue (and kept in the cache file).
struct BindStats {
  double seconds = 0.0;  // wall time of the weight computation (0 when cached)
  int threads = 1;       // threads used
  bool fromCache = false;
  double minWeight = 0.0, maxWeight = 0.0;  // over the stored weights
  std::int64_t negativeCount = 0;           // stored weights < 0 (kept, never clamped)
  double maxSumError = 0.0;                 // max_i |Σ_j W_ij − 1| (stored weights)
  double maxLinearError = 0.0;  // max_i |Σ_j W_ij v_j − x_i| / cage diagonal (stored weights)
  double unprunedLinearError = 0.0;  // the same before pruning
  double pruningError = 0.0;  // max_i |Σ_j (W_pruned − W)_ij v_j| / cage diagonal (rest pose)
  double maxPrunedL1 = 0.0;   // max_i Σ_j |W_pruned − W|_ij: bound on the pruning error of a
                              // deformed pose relative to its largest non-affine cage motion
  std::int64_t nonZeros = 0;
  double worstConditioning = 1.0;  // max cancellation factor (see MvcInfo); error ≈ 1e-16 × this
  std::int64_t farPoints = 0;      // points farther than 4× the cage diagonal from the cage centre
  std::int64_t onCagePoints = 0;   // points evaluated as on a cage vertex/edge/face
};

enum class WeightStorage { Auto, Dense, Sparse };

// Which coordinates a weight matrix holds (metadata: every kind deforms the same way, W ·
// controls). The numbers are stored in weight files; never renumber.
enum class EmbeddingKind : std::uint8_t {
  MeanValue = 0,     // mvc.h: cage vertices (bindMeanValue)
  Harmonic = 1,      // harmonic.h: cage vertices
  Rbf = 2,           // rbf.h: any handles (a cage's vertices, or points)
  FfdBernstein = 3,  // ffd_lattice.h: lattice nodes
  FfdBSpline = 4,    // ffd_lattice.h: lattice nodes
  Green = 5,         // green.h: extended controls, cage vertices then faces (greenControls)
};
inline constexpr int kEmbeddingKindCount = 6;
// "mvc", "harmonic", "rbf", "ffd-bernstein", "ffd-bspline", "green": the names scenes and the CLI
// use.
const char* embeddingKindName(EmbeddingKind kind);
// The kind of a name above; false for anything else.
bool parseEmbeddingKind(const std::string& name, EmbeddingKind* kind);

struct BindOptions {
  int threads =
      0;  // threads for the bind, at most threadCount() (0 = threadCount(); sim/base/parallel.h)
  // Auto: dense when the cage has at most denseMaxCageVertices vertices; otherwise pruned and
  // sparse, unless pruning keeps more than half the entries on a sample of 64 points (then
  // dense, unpruned).
  WeightStorage storage = WeightStorage::Auto;
  int denseMaxCageVertices = 256;
  // Sparse pruning: in each row drop the smallest |w_j| as long as their sum stays within
  // pruneThreshold · Σ_k |w_k|, then add to the kept weights the minimum-norm correction
  // (weighted by |w_j|) that restores both Σw = 1 and linear precision Σ w_j v_j = x exactly
  // (see README.md).
  double pruneThreshold = 0.01;
  bool keepDoublePrecision =
      true;  // keep the double weights (rowWeights, deformDouble); float always
  // Memory the weights may take at most (bytes, estimated before binding: dense 12 bytes per
  // point × cage vertex, sparse about 52 bytes per kept weight at the peak). Auto storage
  // switches to sparse when dense would exceed it; a bind that still exceeds it is refused with
  // the figure (std::runtime_error) instead of exhausting memory.
  std::uint64_t maxWeightBytes = std::uint64_t(4) << 30;
  std::string cacheDir;  // empty = no cache
  // Called from the calling thread after each block of points: (points done, total).
  std::function<void(std::size_t, std::size_t)> progress;
  // Cache problems (corrupt file, cannot write). Default: print to stderr.
  std::function<void(const std::string&)> warning;
};

class Embedding {
 public:
  using SparseD = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
  using SparseF = Eigen::SparseMatrix<float, Eigen::RowMajor, int>;
  using DenseD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  Embedding() = default;
  Embedding(const Embedding&) = default;
  Embedding& operator=(const Embedding&) = default;
  // Moves swap: Eigen 3.4's SparseMatrix has no move constructor, so the implicit moves copied
  // the sparse weights (77 MB for 100k points in a B-spline lattice) at every return.
  Embedding(Embedding&& other) noexcept { swap(other); }
  Embedding& operator=(Embedding&& other) noexcept {
    swap(other);
    return *this;
  }
  void swap(Embedding& other) noexcept;
  // Any linear embedding (e.g. other coordinate types) can be wrapped.
  static Embedding fromDense(DenseD weights, bool keepDouble = true);
  static Embedding fromSparse(SparseD&& weights, bool keepDouble = true);  // takes weights' storage

  // What the weights are (set by the bind that made them; fromDense/fromSparse: MeanValue).
  EmbeddingKind kind() const { return kind_; }
  void setKind(EmbeddingKind kind) { kind_ = kind; }

  int meshVertexCount() const { return rows_; }
  // The rows deform() takes: the columns of W, or, with a Green rest cage attached, its vertices.
  int cageVertexCount() const { return greenCage_ ? greenCageVertices_ : cols_; }
  int weightColumns() const { return cols_; }  // columns of W
  // Green coordinates (green.h) weigh the cage's vertices and its faces' scaled normals: W has
  // V + F columns. Attaching the rest cage they were bound to (vertices in the bind's
  // coordinates, outward triangles) makes deform, deformMany and deformDouble take the V cage
  // vertices like every other kind and extend them with greenControls themselves; bindGreen and
  // bindToCage attach it. Without it (a Green weight file loaded alone) they take the V + F
  // extended controls. Throws std::invalid_argument unless the kind is Green and the cage has
  // V + F = weightColumns().
  void attachGreenCage(std::shared_ptr<const mesh::TriangleMesh> restCage);
  const mesh::TriangleMesh* greenCage() const { return greenCage_.get(); }
  bool isSparse() const { return sparse_; }
  std::int64_t nonZeros() const;
  bool hasDoubleWeights() const { return hasDouble_; }

  // out = W · cagePositions (#mesh × 3, cagePositions cageVertexCount() × 3), float, one matrix
  // product (a Green embedding with its cage extends the positions first: attachGreenCage).
  void deform(ConstPointsRef cagePositions, PointsRowMajor& out) const;
  // deform for several cages at once (bodies sharing this embedding): *outs[k] = W · cages[k],
  // each bit-identical to deform(cages[k], *outs[k]). Each block of W's rows serves every cage
  // while it is in cache, so W streams from memory once instead of once per cage (the
  // seed-scale scene's 160 bunnies share one 1.2 MB W). Same sizes; every out distinct.
  void deformMany(const std::vector<ConstPointsRef>& cages,
                  const std::vector<PointsRowMajor*>& outs) const;
  // The same in double (uses the double weights when kept, else the float ones).
  void deformDouble(const Eigen::Matrix<double, Eigen::Dynamic, 3>& cagePositions,
                    Eigen::Matrix<double, Eigen::Dynamic, 3>& out) const;
  // Nonzeros (cage vertex, weight) of row meshVertex, ascending cage index.
  void rowWeights(int meshVertex, std::vector<std::pair<int, double>>& out) const;

  const BindStats& stats() const { return stats_; }
  BindStats& stats() { return stats_; }
  double pruningError() const { return stats_.pruningError; }

  // Binary file (format in README.md) with a checksum; save is atomic (temp file + rename).
  // load throws std::runtime_error on any inconsistency (bad magic, size, checksum, index), and
  // on content that passed the checksum but is not what a bind writes (a statistic out of its
  // range, a row of weights not summing to 1); it reads only regular files of at most 16 GB
  // (sim/base/file_io.h). fromBytes does the same on bytes in memory (`name` in messages).
  void save(const std::string& path, const std::array<std::uint64_t, 2>& key = {0, 0}) const;
  static Embedding load(const std::string& path, std::array<std::uint64_t, 2>* key = nullptr);
  static Embedding fromBytes(const std::string& data, const std::string& name,
                             std::array<std::uint64_t, 2>* key = nullptr);

 private:
  void makeFloat();
  DenseD floatWeights() const;
  // deformMany on positions with one row per column of W.
  void deformWeights(const std::vector<ConstPointsRef>& controls,
                     const std::vector<PointsRowMajor*>& outs) const;

  int rows_ = 0, cols_ = 0;
  std::shared_ptr<const mesh::TriangleMesh> greenCage_;  // attachGreenCage
  int greenCageVertices_ = 0;
  EmbeddingKind kind_ = EmbeddingKind::MeanValue;
  bool sparse_ = false;
  bool hasDouble_ = false;
  DenseD denseD_;
  PanelWeights panelsF_;  // the float W when dense, in the deform kernels' layout
  SparseD sparseD_;
  SparseF sparseF_;
  BindStats stats_;
};

// Fills e's statistics that W alone determines, for binds that do not measure while binding:
// nonZeros, the weight range and negative count, max |Σ_j W_ij − 1| and the linear error
// max_i |Σ_j W_ij c_j − x_i| / (diagonal of the controls' box), also as unprunedLinearError.
// points: the bound points (#rows); controls: the controls' rest positions (one per column of
// W).
// Throws std::runtime_error on a non-finite weight (a bind that failed silently).
void measureWeights(Embedding& e, const std::vector<Eigen::Vector3d>& points,
                    const std::vector<Eigen::Vector3d>& controls);

// The checksum a weight file ends with, over all bytes before it (tools and tests that build
// or re-seal files; the fuzz target re-seals its inputs to reach the checks behind it).
std::uint64_t weightFileChecksum(const std::string& bytesBeforeChecksum);

// The cache key: a 128-bit hash of the points, the cage vertices and triangles (and polygon ids,
// TriangleMesh::polygonOf, when present) and the options that change the result (storage rule,
// threshold, precision), plus the file format version.
std::array<std::uint64_t, 2> bindCacheKey(const std::vector<Eigen::Vector3d>& points,
                                          const mesh::TriangleMesh& cage,
                                          const BindOptions& options);
std::string bindCachePath(const std::string& cacheDir, const std::array<std::uint64_t, 2>& key);

// The bind cache's two halves, for every kind of bind: the weights stored at path when the file
// is intact and its key, kind and size (rows × cols, the columns of W) match (else nothing, with a
// warning through options.warning when a file was there but unusable), and the store (atomic; a
// failure is only a warning).
std::optional<Embedding> loadCachedBind(const std::string& path,
                                        const std::array<std::uint64_t, 2>& key, EmbeddingKind kind,
                                        int rows, int cols, const BindOptions& options);
void saveCachedBind(const Embedding& e, const std::string& path,
                    const std::array<std::uint64_t, 2>& key, const BindOptions& options);

// Validates the cage (throws mesh::SurfaceError), then computes mean value coordinates of every
// point: triangle MVC (mvc.h), or polygon MVC (polygon_mvc.h) when the cage has faces of more
// than three corners (mesh::hasPolygonFaces), so a quad cage does not depend on its diagonals. With
// options.cacheDir set, reuses a cached bind with the same key, else binds and writes it.
Embedding bindMeanValue(const std::vector<Eigen::Vector3d>& points, const mesh::TriangleMesh& cage,
                        const BindOptions& options = {});

}  // namespace sb::cage
