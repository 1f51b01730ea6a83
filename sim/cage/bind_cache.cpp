// The bind cache: the weight file format (Embedding::save / load / fromBytes), its checksum and
// the checks on what passes it, and the cache key and file name of a bind.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "sim/base/file_io.h"
#include "sim/base/hasher.h"
#include "sim/cage/embedding.h"

namespace sb::cage {

using mesh::TriangleMesh;

namespace {

using Vec3 = Eigen::Vector3d;

constexpr char kMagic[8] = {'S', 'B', 'M', 'V', 'C', 'W', '0', '1'};
// 2: the embedding's kind after the storage flag (EmbeddingKind).
constexpr std::uint64_t kFormatVersion = 2;

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
  return {s.seconds,
          static_cast<double>(s.threads),
          s.fromCache ? 1.0 : 0.0,
          s.minWeight,
          s.maxWeight,
          static_cast<double>(s.negativeCount),
          s.maxSumError,
          s.maxLinearError,
          s.unprunedLinearError,
          s.pruningError,
          s.maxPrunedL1,
          static_cast<double>(s.nonZeros),
          s.worstConditioning,
          static_cast<double>(s.farPoints),
          static_cast<double>(s.onCagePoints)};
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
    throw std::runtime_error(path + ": implausible statistic " + what +
                             " (file not written by this program)");
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

}  // namespace

void Embedding::save(const std::string& path, const std::array<std::uint64_t, 2>& key) const {
  std::string data;
  data.append(kMagic, 8);
  put(data, kFormatVersion);
  put(data, key[0]);
  put(data, key[1]);
  put(data, static_cast<std::int64_t>(rows_));
  put(data, static_cast<std::int64_t>(cols_));
  put(data, static_cast<std::uint64_t>(sparse_ ? 1 : 0));
  put(data, static_cast<std::uint64_t>(kind_));
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
      data.append(reinterpret_cast<const char*>(denseD_.data()),
                  sizeof(double) * static_cast<std::size_t>(denseD_.size()));
    } else {
      for (int i = 0; i < rows_; ++i)
        for (int j = 0; j < cols_; ++j) put(data, static_cast<double>(panelsF_.at(i, j)));
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
  if (checksum(body) != stored)
    throw std::runtime_error(path + ": checksum mismatch (corrupt file)");
  Reader rd{body, 8, path};
  if (rd.get<std::uint64_t>() != kFormatVersion)
    throw std::runtime_error(path + ": unsupported version");
  std::array<std::uint64_t, 2> k;
  k[0] = rd.get<std::uint64_t>();
  k[1] = rd.get<std::uint64_t>();
  if (key) *key = k;
  const auto rows = rd.get<std::int64_t>();
  const auto cols = rd.get<std::int64_t>();
  const auto sparse = rd.get<std::uint64_t>();
  const auto kind = rd.get<std::uint64_t>();
  if (rows < 0 || cols <= 0 || rows > (1 << 30) || cols > (1 << 30) || sparse > 1)
    throw std::runtime_error(path + ": bad header");
  if (kind >= kEmbeddingKindCount)
    throw std::runtime_error(path + ": unknown embedding kind " + std::to_string(kind));
  const auto nstats = rd.get<std::uint64_t>();
  if (nstats != kStatsCount) throw std::runtime_error(path + ": bad statistics block");
  std::vector<double> st(nstats);
  for (auto& v : st) v = rd.get<double>();
  Embedding e;
  if (sparse) {
    const auto nnz = rd.get<std::int64_t>();
    if (nnz < 0 || nnz > rows * cols || nnz > std::numeric_limits<int>::max())
      throw std::runtime_error(path + ": bad nonzero count");
    const std::size_t need =
        static_cast<std::size_t>(rows + 1) * 8 + static_cast<std::size_t>(nnz) * (4 + 8);
    if (rd.pos + need != body.size())
      throw std::runtime_error(path + ": size does not match the header");
    std::vector<std::int64_t> outer(static_cast<std::size_t>(rows) + 1);
    for (auto& o : outer) o = rd.get<std::int64_t>();
    std::vector<int> inner(static_cast<std::size_t>(nnz));
    for (auto& v : inner) v = rd.get<int>();
    if (outer[0] != 0 || outer[static_cast<std::size_t>(rows)] != nnz)
      throw std::runtime_error(path + ": bad row offsets");
    // All offsets checked before any is used: non-decreasing from 0 to nnz keeps every one in
    // [0, nnz] (checked row by row inside the loop below, a large offset early on read past
    // `inner` before the later, smaller one was seen).
    for (std::int64_t r = 0; r < rows; ++r)
      if (outer[r + 1] < outer[r]) throw std::runtime_error(path + ": bad row offsets");
    // Columns strictly ascending within a row, as save writes them: the arrays then are the
    // compressed row storage itself and are copied into place. (Building from triplets cost
    // time and memory in proportion to the header's column count, which a 100-byte file can set
    // to 2^30: the fuzzer timed out on one.)
    for (std::int64_t r = 0; r < rows; ++r) {
      int previous = -1;
      for (std::int64_t q = outer[r]; q < outer[r + 1]; ++q) {
        const int c = inner[static_cast<std::size_t>(q)];
        if (c < 0 || c >= cols) throw std::runtime_error(path + ": column index out of range");
        if (c <= previous)
          throw std::runtime_error(path + ": columns of row " + std::to_string(r) +
                                   " not strictly ascending");
        previous = c;
      }
    }
    SparseD W(rows, cols);
    W.resizeNonZeros(static_cast<Eigen::Index>(nnz));
    for (std::int64_t r = 0; r <= rows; ++r)
      W.outerIndexPtr()[r] = static_cast<int>(outer[static_cast<std::size_t>(r)]);
    std::copy(inner.begin(), inner.end(), W.innerIndexPtr());
    for (std::int64_t q = 0; q < nnz; ++q) {
      const double v = rd.get<double>();
      if (!std::isfinite(v)) throw std::runtime_error(path + ": non-finite weight");
      W.valuePtr()[q] = v;
    }
    e = fromSparse(std::move(W));
  } else {
    const std::size_t need = static_cast<std::size_t>(rows * cols) * 8;
    if (rd.pos + need != body.size())
      throw std::runtime_error(path + ": size does not match the header");
    DenseD W(rows, cols);
    // A mesh without vertices has no storage (data() is null, which memcpy may not be given).
    if (need != 0) std::memcpy(W.data(), body.data() + rd.pos, need);
    if (!W.allFinite()) throw std::runtime_error(path + ": non-finite weight");
    e = fromDense(std::move(W));
  }
  e.kind_ = static_cast<EmbeddingKind>(kind);
  e.stats_ = checkedStats(st, rows, cols, path);
  // Green rows are [φ | ψ]: only the φ part sums to 1, and the file does not record where it
  // ends, so their sums are not checked.
  if (e.kind_ != EmbeddingKind::Green) checkRowSums(e, path);
  return e;
}

std::uint64_t weightFileChecksum(const std::string& bytesBeforeChecksum) {
  return checksum(bytesBeforeChecksum);
}

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
    if (!cage.triangles.empty())
      h.bytes(cage.triangles.data(), cage.triangles.size() * sizeof(std::array<int, 3>));
    // Polygon faces change the weights (polygon MVC): a triangle bind of the same triangles is
    // not reused. A triangle-only cage (polygonOf empty) keeps its old key.
    if (!cage.polygonOf.empty()) {
      h.value(static_cast<std::uint64_t>(0x706f6c79ull));  // "poly"
      h.bytes(cage.polygonOf.data(), cage.polygonOf.size() * sizeof(int));
    }
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
  return keyedCachePath(cacheDir, "mvc-", key, ".sbw");
}

}  // namespace sb::cage
