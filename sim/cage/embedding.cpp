#include "sim/cage/embedding.h"


#include <algorithm>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <sys/stat.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include "sim/base/file_io.h"
#include "sim/base/parallel_for.h"
#include "sim/cage/mvc.h"
#include "sim/mesh/closed_surface.h"

namespace sb::cage {

using mesh::TriangleMesh;

namespace {

using Vec3 = Eigen::Vector3d;

constexpr char kMagic[8] = {'S', 'B', 'M', 'V', 'C', 'W', '0', '1'};
constexpr std::uint64_t kFormatVersion = 1;

// A 64-bit hash of a byte stream, 8 bytes at a time (not cryptographic; a cache key).
class Hasher {
 public:
  explicit Hasher(std::uint64_t seed) : h_(seed ^ 0x9E3779B97F4A7C15ull) {}
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, 8);
      mix(w);
    }
    std::uint64_t tail = 0;
    for (std::size_t k = 0; i < n; ++i, ++k) tail |= static_cast<std::uint64_t>(p[i]) << (8 * k);
    mix(tail ^ (static_cast<std::uint64_t>(n) << 56));
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof(T));
  }
  std::uint64_t digest() const {
    std::uint64_t z = h_ + 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }

 private:
  void mix(std::uint64_t w) {
    w *= 0x87C37B91114253D5ull;
    w = (w << 31) | (w >> 33);
    w *= 0x4CF5AD432745937Full;
    h_ ^= w;
    h_ = ((h_ << 27) | (h_ >> 37)) * 5 + 0x52DCE729;
  }
  std::uint64_t h_;
};

std::uint64_t checksum(const std::string& data) {
  Hasher h(0x5EEDu);
  h.bytes(data.data(), data.size());
  return h.digest();
}

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

struct Reader {
  const std::string& data;
  std::size_t pos = 0;
  const std::string& path;
  template <class T>
  T get() {
    if (pos + sizeof(T) > data.size()) throw std::runtime_error(path + ": truncated");
    T v;
    std::memcpy(&v, data.data() + pos, sizeof(T));
    pos += sizeof(T);
    return v;
  }
};

// Largest weight file load() reads (a dense bind of 1M mesh vertices to a 1,000-vertex cage in
// double precision is 8 GB): a bound on what a damaged or hostile cache entry can make it read.
constexpr std::uint64_t kMaxFileBytes = std::uint64_t(16) << 30;

// Stats are stored as a fixed list of doubles.
std::vector<double> statsToList(const BindStats& s) {
  return {s.seconds, static_cast<double>(s.threads), s.fromCache ? 1.0 : 0.0, s.minWeight, s.maxWeight,
          static_cast<double>(s.negativeCount), s.maxSumError, s.maxLinearError, s.unprunedLinearError,
          s.pruningError, s.maxPrunedL1, static_cast<double>(s.nonZeros), s.worstConditioning,
          static_cast<double>(s.farPoints), static_cast<double>(s.onCagePoints)};
}
BindStats statsFromList(const std::vector<double>& v) {
  BindStats s;
  s.seconds = v[0];
  s.threads = static_cast<int>(v[1]);
  s.fromCache = v[2] != 0.0;
  s.minWeight = v[3];
  s.maxWeight = v[4];
  s.negativeCount = static_cast<std::int64_t>(v[5]);
  s.maxSumError = v[6];
  s.maxLinearError = v[7];
  s.unprunedLinearError = v[8];
  s.pruningError = v[9];
  s.maxPrunedL1 = v[10];
  s.nonZeros = static_cast<std::int64_t>(v[11]);
  s.worstConditioning = v[12];
  s.farPoints = static_cast<std::int64_t>(v[13]);
  s.onCagePoints = static_cast<std::int64_t>(v[14]);
  return s;
}
constexpr std::size_t kStatsCount = 15;

// What passed the checksum is still checked before use (a file re-sealed by hand, a bug in an
// older writer): every statistic finite and in its range — the counts whole numbers that fit
// before they are cast — ...
BindStats checkedStats(const std::vector<double>& v, std::int64_t rows, std::int64_t cols,
                       const std::string& path) {
  auto bad = [&](const char* what) {
    throw std::runtime_error(path + ": implausible statistic " + what + " (file not written by this program)");
  };
  for (double x : v)
    if (!std::isfinite(x)) bad("(not finite)");
  auto count = [&](double x, double hi, const char* what) {
    if (!(x >= 0.0 && x <= hi && x == std::floor(x))) bad(what);
  };
  const double entries = double(rows) * double(cols);
  if (!(v[0] >= 0.0 && v[0] <= 1e9)) bad("seconds");
  count(v[1], 65536, "threads");
  if (v[2] != 0.0 && v[2] != 1.0) bad("fromCache");
  if (!(v[3] <= v[4])) bad("minWeight > maxWeight");
  count(v[5], entries, "negativeCount");
  for (int i = 6; i <= 10; ++i)
    if (!(v[size_t(i)] >= 0.0 && v[size_t(i)] <= 1e6)) bad("error bound");
  count(v[11], entries, "nonZeros");
  if (!(v[12] >= 0.0)) bad("worstConditioning");
  count(v[13], double(rows), "farPoints");
  count(v[14], double(rows), "onCagePoints");
  return statsFromList(v);
}

// ... and every row of weights sums to 1 (mean value coordinates are a partition of unity,
// and pruning restores the sum exactly): a file with scaled or shuffled weights is refused.
void checkRowSums(const Embedding& e, const std::string& path) {
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < e.meshVertexCount(); ++i) {
    e.rowWeights(i, row);
    double sum = 0.0, magnitude = 0.0;
    for (const auto& [j, w] : row) {
      sum += w;
      magnitude += std::abs(w);
    }
    if (!(std::abs(sum - 1.0) <= 1e-5 * std::max(1.0, magnitude)))
      throw std::runtime_error(path + ": weights of point " + std::to_string(i) + " sum to " +
                               std::to_string(sum) + ", not 1 (file not written by this program)");
  }
}

// The bind cache's folder may not exist yet (a fresh cache directory).
void writeCacheFile(const std::string& path, const std::string& data) {
  std::error_code ec;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);  // failures surface below
  writeFileAtomic(path, [&](std::ostream& out) {
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
  });
}

// Prunes one row in place (see BindOptions::pruneThreshold). q_j = (v_j − x) / L.
// Returns the L1 norm of the change.
double pruneRow(std::vector<std::pair<int, double>>& row, const double* w, int m, const std::vector<Vec3>& q,
                double threshold) {
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
  while (nDrop < order.size() && droppedMass + order[nDrop].first <= budget) droppedMass += order[nDrop++].first;
  row.clear();
  std::vector<std::pair<double, int>> droppedList(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(nDrop));
  for (std::size_t k = nDrop; k < order.size(); ++k) row.emplace_back(order[k].second, w[order[k].second]);
  std::sort(row.begin(), row.end());
  // Exact zeros carry nothing: drop them without counting.
  row.erase(std::remove_if(row.begin(), row.end(), [](const auto& e) { return e.second == 0.0; }), row.end());
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

Embedding Embedding::fromSparse(SparseD weights, bool keepDouble) {
  Embedding e;
  weights.makeCompressed();
  e.rows_ = static_cast<int>(weights.rows());
  e.cols_ = static_cast<int>(weights.cols());
  e.sparse_ = true;
  e.sparseD_ = std::move(weights);
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
    sparseF_ = sparseD_.cast<float>();
    sparseF_.makeCompressed();
  } else {
    denseF_ = denseD_.cast<float>();
  }
}

std::int64_t Embedding::nonZeros() const {
  return sparse_ ? static_cast<std::int64_t>(sparseF_.nonZeros()) : static_cast<std::int64_t>(rows_) * cols_;
}

void Embedding::deform(ConstPointsRef cagePositions, PointsRowMajor& out) const {
  if (cagePositions.rows() != cols_)
    throw std::invalid_argument("Embedding::deform: got " + std::to_string(cagePositions.rows()) +
                                " cage positions, the embedding has " + std::to_string(cols_));
  out.resize(rows_, 3);
  // Memory-bound: stream W once, row by row, against the cage coordinates as three contiguous
  // float arrays (a few KB, in L1). Rows are independent: one range per thread (sim/base/parallel_for.h).
  const int m = cols_;
  std::vector<float> cx(static_cast<std::size_t>(m)), cy(static_cast<std::size_t>(m)), cz(static_cast<std::size_t>(m));
  for (int j = 0; j < m; ++j) {
    cx[j] = cagePositions(j, 0);
    cy[j] = cagePositions(j, 1);
    cz[j] = cagePositions(j, 2);
  }
  const float* X = cx.data();
  const float* Y = cy.data();
  const float* Z = cz.data();
  float* o = out.data();
  const int n = rows_;
  if (sparse_) {
    // One 16-byte load per nonzero: cage positions as (x, y, z, 0) quadruples.
    typedef float v4sf __attribute__((vector_size(16)));
    std::vector<v4sf> c4(static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) c4[j] = v4sf{X[j], Y[j], Z[j], 0.0f};
    const v4sf* C = c4.data();
    const int* outer = sparseF_.outerIndexPtr();
    const int* inner = sparseF_.innerIndexPtr();
    const float* val = sparseF_.valuePtr();
    parallelFor(n, 2001, [&](int i) {
      // Four independent accumulators hide the add latency.
      v4sf a0 = {0.0f, 0.0f, 0.0f, 0.0f}, a1 = a0, a2 = a0, a3 = a0;
      int k = outer[i];
      const int end = outer[i + 1];
      for (; k + 4 <= end; k += 4) {
        a0 += val[k] * C[inner[k]];
        a1 += val[k + 1] * C[inner[k + 1]];
        a2 += val[k + 2] * C[inner[k + 2]];
        a3 += val[k + 3] * C[inner[k + 3]];
      }
      for (; k < end; ++k) a0 += val[k] * C[inner[k]];
      const v4sf acc = (a0 + a1) + (a2 + a3);
      o[3 * static_cast<std::size_t>(i)] = acc[0];
      o[3 * static_cast<std::size_t>(i) + 1] = acc[1];
      o[3 * static_cast<std::size_t>(i) + 2] = acc[2];
    });
  } else {
    const float* W = denseF_.data();
    parallelFor(n, 2001, [&](int i) {
      const float* w = W + static_cast<std::size_t>(i) * static_cast<std::size_t>(m);
      float sx = 0.0f, sy = 0.0f, sz = 0.0f;
#pragma omp simd reduction(+ : sx, sy, sz)
      for (int j = 0; j < m; ++j) {
        sx += w[j] * X[j];
        sy += w[j] * Y[j];
        sz += w[j] * Z[j];
      }
      o[3 * static_cast<std::size_t>(i)] = sx;
      o[3 * static_cast<std::size_t>(i) + 1] = sy;
      o[3 * static_cast<std::size_t>(i) + 2] = sz;
    });
  }
}

void Embedding::deformDouble(const Eigen::Matrix<double, Eigen::Dynamic, 3>& cagePositions,
                             Eigen::Matrix<double, Eigen::Dynamic, 3>& out) const {
  if (cagePositions.rows() != cols_)
    throw std::invalid_argument("Embedding::deformDouble: wrong number of cage positions");
  if (hasDouble_) {
    if (sparse_) out.noalias() = sparseD_ * cagePositions;
    else out.noalias() = denseD_ * cagePositions;
  } else {
    if (sparse_) out.noalias() = sparseF_.cast<double>() * cagePositions;
    else out.noalias() = denseF_.cast<double>() * cagePositions;
  }
}

void Embedding::rowWeights(int i, std::vector<std::pair<int, double>>& out) const {
  out.clear();
  if (i < 0 || i >= rows_) throw std::out_of_range("Embedding::rowWeights: row " + std::to_string(i));
  if (sparse_) {
    if (hasDouble_) {
      for (SparseD::InnerIterator it(sparseD_, i); it; ++it) out.emplace_back(it.col(), it.value());
    } else {
      for (SparseF::InnerIterator it(sparseF_, i); it; ++it) out.emplace_back(it.col(), it.value());
    }
  } else {
    for (int j = 0; j < cols_; ++j) {
      const double v = hasDouble_ ? denseD_(i, j) : static_cast<double>(denseF_(i, j));
      if (v != 0.0) out.emplace_back(j, v);
    }
  }
}

void Embedding::save(const std::string& path, const std::array<std::uint64_t, 2>& key) const {
  std::string data;
  data.append(kMagic, 8);
  put(data, kFormatVersion);
  put(data, key[0]);
  put(data, key[1]);
  put(data, static_cast<std::int64_t>(rows_));
  put(data, static_cast<std::int64_t>(cols_));
  put(data, static_cast<std::uint64_t>(sparse_ ? 1 : 0));
  const auto st = statsToList(stats_);
  put(data, static_cast<std::uint64_t>(st.size()));
  for (double v : st) put(data, v);
  if (sparse_) {
    const std::int64_t nnz = sparseF_.nonZeros();
    put(data, nnz);
    const int* outer = hasDouble_ ? sparseD_.outerIndexPtr() : sparseF_.outerIndexPtr();
    const int* inner = hasDouble_ ? sparseD_.innerIndexPtr() : sparseF_.innerIndexPtr();
    for (int r = 0; r <= rows_; ++r) put(data, static_cast<std::int64_t>(outer[r]));
    data.append(reinterpret_cast<const char*>(inner), sizeof(int) * static_cast<std::size_t>(nnz));
    for (std::int64_t k = 0; k < nnz; ++k)
      put(data, hasDouble_ ? sparseD_.valuePtr()[k] : static_cast<double>(sparseF_.valuePtr()[k]));
  } else {
    if (hasDouble_) {
      data.append(reinterpret_cast<const char*>(denseD_.data()), sizeof(double) * static_cast<std::size_t>(denseD_.size()));
    } else {
      for (Eigen::Index k = 0; k < denseF_.size(); ++k) put(data, static_cast<double>(denseF_.data()[k]));
    }
  }
  put(data, checksum(data));
  writeCacheFile(path, data);
}

Embedding Embedding::load(const std::string& path, std::array<std::uint64_t, 2>* key) {
  std::string data;
  try {
    data = readFileBounded(path, kMaxFileBytes);
  } catch (const FileError& e) {
    throw std::runtime_error(e.what());
  }
  return fromBytes(data, path, key);
}

Embedding Embedding::fromBytes(const std::string& data, const std::string& path,
                               std::array<std::uint64_t, 2>* key) {
  if (data.size() < 8 + 8 * 8 || std::memcmp(data.data(), kMagic, 8) != 0)
    throw std::runtime_error(path + ": not a softbody weight file (bad magic)");
  std::uint64_t stored;
  std::memcpy(&stored, data.data() + data.size() - 8, 8);
  const std::string body = data.substr(0, data.size() - 8);
  if (checksum(body) != stored) throw std::runtime_error(path + ": checksum mismatch (corrupt file)");
  Reader rd{body, 8, path};
  if (rd.get<std::uint64_t>() != kFormatVersion) throw std::runtime_error(path + ": unsupported version");
  std::array<std::uint64_t, 2> k;
  k[0] = rd.get<std::uint64_t>();
  k[1] = rd.get<std::uint64_t>();
  if (key) *key = k;
  const auto rows = rd.get<std::int64_t>();
  const auto cols = rd.get<std::int64_t>();
  const auto sparse = rd.get<std::uint64_t>();
  if (rows < 0 || cols <= 0 || rows > (1 << 30) || cols > (1 << 30) || sparse > 1)
    throw std::runtime_error(path + ": bad header");
  const auto nstats = rd.get<std::uint64_t>();
  if (nstats != kStatsCount) throw std::runtime_error(path + ": bad statistics block");
  std::vector<double> st(nstats);
  for (auto& v : st) v = rd.get<double>();
  Embedding e;
  if (sparse) {
    const auto nnz = rd.get<std::int64_t>();
    if (nnz < 0 || nnz > rows * cols) throw std::runtime_error(path + ": bad nonzero count");
    const std::size_t need = static_cast<std::size_t>(rows + 1) * 8 + static_cast<std::size_t>(nnz) * (4 + 8);
    if (rd.pos + need != body.size()) throw std::runtime_error(path + ": size does not match the header");
    std::vector<std::int64_t> outer(static_cast<std::size_t>(rows) + 1);
    for (auto& o : outer) o = rd.get<std::int64_t>();
    std::vector<int> inner(static_cast<std::size_t>(nnz));
    for (auto& v : inner) v = rd.get<int>();
    std::vector<Eigen::Triplet<double>> trips;
    trips.reserve(static_cast<std::size_t>(nnz));
    if (outer[0] != 0 || outer[static_cast<std::size_t>(rows)] != nnz) throw std::runtime_error(path + ": bad row offsets");
    // All offsets checked before any is used: non-decreasing from 0 to nnz keeps every one in
    // [0, nnz] (checked row by row inside the loop below, a large offset early on read past
    // `inner` before the later, smaller one was seen).
    for (std::int64_t r = 0; r < rows; ++r)
      if (outer[r + 1] < outer[r]) throw std::runtime_error(path + ": bad row offsets");
    for (std::int64_t r = 0; r < rows; ++r) {
      for (std::int64_t q = outer[r]; q < outer[r + 1]; ++q) {
        const int c = inner[static_cast<std::size_t>(q)];
        if (c < 0 || c >= cols) throw std::runtime_error(path + ": column index out of range");
        trips.emplace_back(static_cast<int>(r), c, 0.0);
      }
    }
    for (auto& t : trips) {
      const double v = rd.get<double>();
      if (!std::isfinite(v)) throw std::runtime_error(path + ": non-finite weight");
      t = Eigen::Triplet<double>(t.row(), t.col(), v);
    }
    SparseD W(rows, cols);
    W.setFromTriplets(trips.begin(), trips.end());
    e = fromSparse(std::move(W));
  } else {
    const std::size_t need = static_cast<std::size_t>(rows * cols) * 8;
    if (rd.pos + need != body.size()) throw std::runtime_error(path + ": size does not match the header");
    DenseD W(rows, cols);
    std::memcpy(W.data(), body.data() + rd.pos, need);
    if (!W.allFinite()) throw std::runtime_error(path + ": non-finite weight");
    e = fromDense(std::move(W));
  }
  e.stats_ = checkedStats(st, rows, cols, path);
  checkRowSums(e, path);
  return e;
}

std::uint64_t weightFileChecksum(const std::string& bytesBeforeChecksum) {
  return checksum(bytesBeforeChecksum);
}

// ---------------------------------------------------------------------------------------------
// Bind

std::array<std::uint64_t, 2> bindCacheKey(const std::vector<Vec3>& points, const TriangleMesh& cage,
                                          const BindOptions& options) {
  std::array<std::uint64_t, 2> key{};
  for (int s = 0; s < 2; ++s) {
    Hasher h(s == 0 ? 0x1234567ull : 0xABCDEF01ull);
    h.value(kFormatVersion);
    h.value(static_cast<std::uint64_t>(points.size()));
    if (!points.empty()) h.bytes(points.data(), points.size() * sizeof(Vec3));
    h.value(static_cast<std::uint64_t>(cage.vertices.size()));
    if (!cage.vertices.empty()) h.bytes(cage.vertices.data(), cage.vertices.size() * sizeof(Vec3));
    h.value(static_cast<std::uint64_t>(cage.triangles.size()));
    if (!cage.triangles.empty()) h.bytes(cage.triangles.data(), cage.triangles.size() * sizeof(std::array<int, 3>));
    h.value(static_cast<std::uint64_t>(options.storage));
    h.value(static_cast<std::int64_t>(options.denseMaxCageVertices));
    h.value(options.pruneThreshold);
    h.value(static_cast<std::uint64_t>(options.keepDoublePrecision ? 1 : 0));
    h.value(options.maxWeightBytes);  // can switch the storage
    key[s] = h.digest();
  }
  return key;
}

std::string bindCachePath(const std::string& cacheDir, const std::array<std::uint64_t, 2>& key) {
  char name[64];
  std::snprintf(name, sizeof(name), "mvc-%016llx%016llx.sbw", static_cast<unsigned long long>(key[0]),
                static_cast<unsigned long long>(key[1]));
  std::string dir = cacheDir;
  if (!dir.empty() && dir.back() != '/') dir += '/';
  return dir + name;
}

Embedding bindMeanValue(const std::vector<Vec3>& points, const TriangleMesh& cage, const BindOptions& options) {
  mesh::validateClosedSurface(cage, "cage");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) throw std::invalid_argument("bind: point " + std::to_string(i) + " is not finite");
  }
  auto warn = [&](const std::string& msg) {
    if (options.warning) options.warning(msg);
    else std::cerr << "warning: " << msg << "\n";
  };

  std::array<std::uint64_t, 2> key{};
  std::string cachePath;
  if (!options.cacheDir.empty()) {
    key = bindCacheKey(points, cage, options);
    cachePath = bindCachePath(options.cacheDir, key);
    struct stat sb;
    if (::stat(cachePath.c_str(), &sb) == 0) {
      try {
        std::array<std::uint64_t, 2> stored{};
        Embedding e = Embedding::load(cachePath, &stored);
        if (stored != key || e.meshVertexCount() != static_cast<int>(points.size()) ||
            e.cageVertexCount() != static_cast<int>(cage.vertices.size()))
          throw std::runtime_error(cachePath + ": key or size mismatch");
        e.stats().fromCache = true;
        e.stats().seconds = 0.0;
        return e;
      } catch (const std::exception& ex) {
        warn(std::string("ignoring bind cache: ") + ex.what() + "; binding again");
      }
    }
  }

  const auto t0 = std::chrono::steady_clock::now();
  const MeanValueCage prepared(cage);
  const int n = static_cast<int>(points.size());
  const int m = prepared.vertexCount();
  const double L = prepared.diagonal();
  Eigen::AlignedBox3d box;
  for (const auto& v : cage.vertices) box.extend(v);
  const Vec3 centre = box.center();

  bool sparse = options.storage == WeightStorage::Sparse ||
                (options.storage == WeightStorage::Auto && m > options.denseMaxCageVertices);
  const int threads = options.threads > 0 ? std::min(options.threads, threadCount()) : threadCount();
  // Memory first (BindOptions::maxWeightBytes): dense keeps a double and a float copy.
  const double denseBytes = 12.0 * double(n) * double(m);
  const bool denseTooBig = denseBytes > double(options.maxWeightBytes);
  if (denseTooBig && options.storage == WeightStorage::Dense)
    throw std::runtime_error("bind: dense weights for " + std::to_string(n) + " points × " + std::to_string(m) +
                             " cage vertices need " + formatBytes(std::uint64_t(denseBytes)) + ", more than the " +
                             formatBytes(options.maxWeightBytes) + " allowed; use sparse storage");
  if (denseTooBig) sparse = true;
  // Pruned weights kept per row, estimated on up to 64 evenly spaced points (a sparse bind's
  // size, and whether pruning pays at all).
  std::int64_t kept = 0;
  int samples = 0;
  if (sparse && n > 0) {
    samples = std::min(n, 64);
    MeanValueCage::Scratch scratch;
    std::vector<double> w(static_cast<std::size_t>(m));
    std::vector<Vec3> q(static_cast<std::size_t>(m));
    std::vector<std::pair<int, double>> row;
    for (int k = 0; k < samples; ++k) {
      const Vec3& x = points[static_cast<std::size_t>(static_cast<std::int64_t>(k) * n / samples)];
      if (!prepared.weights(x, w.data(), scratch)) continue;
      for (int j = 0; j < m; ++j) q[j] = (cage.vertices[j] - x) / L;
      pruneRow(row, w.data(), m, q, options.pruneThreshold);
      kept += static_cast<std::int64_t>(row.size());
    }
    const double sparseBytes = 52.0 * double(kept) / double(samples) * double(n);
    if (sparseBytes > double(options.maxWeightBytes))
      throw std::runtime_error("bind: the weights for " + std::to_string(n) + " points × " + std::to_string(m) +
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
  if (sparse) rows.resize(static_cast<std::size_t>(n));
  else dense.resize(n, m);

  // Per-point figures, reduced serially afterwards (deterministic).
  std::vector<double> linErr(n, 0.0), linErr0(n, 0.0), pruneErr(n, 0.0), prunedL1(n, 0.0), cond(n, 1.0);
  std::vector<char> onCage(n, 0), failed(n, 0);

  const int block = 256;
  for (int start = 0; start < n; start += block) {
    const int end = std::min(n, start + block);
    parallelRanges(end - start, 2, threads, [&](int rangeBegin, int rangeEnd) {
      MeanValueCage::Scratch scratch;
      std::vector<double> w(static_cast<std::size_t>(m));
      std::vector<Vec3> q;
      for (int i = start + rangeBegin; i < start + rangeEnd; ++i) {
        const Vec3& x = points[static_cast<std::size_t>(i)];
        MvcInfo info;
        if (!prepared.weights(x, w.data(), scratch, &info)) failed[i] = 1;
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
    if (options.progress) options.progress(static_cast<std::size_t>(end), static_cast<std::size_t>(n));
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

  if (!cachePath.empty()) {
    try {
      e.save(cachePath, key);
    } catch (const std::exception& ex) {
      warn(std::string("could not write bind cache: ") + ex.what());
    }
  }
  return e;
}

}  // namespace sb::cage
