// Issue #18: what the bind cache loader refuses although it passes the checksum, non-regular
// cache entries, and the bind's memory estimate.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "sim/cage/embedding.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::cage {
namespace {

namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;

class BindChecks : public sb::test_support::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    cage_ = mesh::testing::makeBox(1, 1, 1);
    for (int i = 0; i < 20; ++i)
      points_.emplace_back(0.1 + 0.04 * i, 0.3 + 0.01 * i, 0.7 - 0.02 * i);
    options_.cacheDir = dir_.string();
    options_.storage = WeightStorage::Dense;
    options_.warning = [this](const std::string& w) { warnings_.push_back(w); };
  }
  std::string cacheFile() const {
    return bindCachePath(dir_.string(), bindCacheKey(points_, cage_, options_));
  }
  std::string read(const std::string& p) const {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }
  void writeResealed(const std::string& p, std::string bytes) const {
    bytes.resize(bytes.size() - 8);
    const std::uint64_t sum = weightFileChecksum(bytes);
    bytes.append(reinterpret_cast<const char*>(&sum), 8);
    std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
  }
  // Layout of a dense file: magic, version, key[2], rows, cols, sparse, kind, stat count, 15 stats,
  // rows × cols weights, checksum (all 8-byte fields).
  static constexpr size_t kStats = 9 * 8, kWeights = kStats + 15 * 8;

  mesh::TriangleMesh cage_;
  std::vector<Vec3> points_;
  BindOptions options_;
  std::vector<std::string> warnings_;
};

TEST_F(BindChecks, ResealedScaledWeightsAreRefusedAndRebound) {
  const Embedding first = bindMeanValue(points_, cage_, options_);
  std::string bytes = read(cacheFile());
  ASSERT_EQ(bytes.size(), kWeights + 20 * 8 * 8 + 8);
  for (size_t k = 0; k < 20 * 8; ++k) {
    double w;
    std::memcpy(&w, &bytes[kWeights + 8 * k], 8);
    w *= 1.5;
    std::memcpy(&bytes[kWeights + 8 * k], &w, 8);
  }
  writeResealed(cacheFile(), bytes);
  try {
    Embedding::load(cacheFile());
    FAIL() << "scaled weights accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("sum to 1.5"), std::string::npos) << e.what();
  }
  const Embedding again = bindMeanValue(points_, cage_, options_);
  EXPECT_FALSE(again.stats().fromCache);
  ASSERT_EQ(warnings_.size(), 1u);
  EXPECT_NE(warnings_[0].find("not 1"), std::string::npos) << warnings_[0];
  EXPECT_TRUE(bindMeanValue(points_, cage_, options_).stats().fromCache);  // rewritten, good again
}

TEST_F(BindChecks, ImplausibleStatisticsAreRefused) {
  bindMeanValue(points_, cage_, options_);
  const std::string good = read(cacheFile());
  // threads = 1e300 (cast to int: float-cast overflow before), nonZeros = -1, a NaN error bound.
  const std::pair<int, double> cases[] = {{1, 1e300}, {11, -1.0}, {7, std::nan("")}, {13, 0.5}};
  for (const auto& [index, value] : cases) {
    std::string bytes = good;
    std::memcpy(&bytes[kStats + 8 * size_t(index)], &value, 8);
    writeResealed(cacheFile(), bytes);
    try {
      Embedding::load(cacheFile());
      ADD_FAILURE() << "statistic " << index << " = " << value << " accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("implausible statistic"), std::string::npos) << e.what();
    }
  }
}

// A sparse file: magic, version, key[2], rows, cols, sparse, kind, stat count, 15 stats, nonzero
// count, rows + 1 row offsets (8 bytes), column indices (4 bytes), weights (8 bytes), checksum.
TEST_F(BindChecks, SparseColumnsMustAscendAndTheColumnCountCostsNothing) {
  options_.storage = WeightStorage::Sparse;
  const Embedding first = bindMeanValue(points_, cage_, options_);
  ASSERT_TRUE(first.isSparse());
  const std::string good = read(cacheFile());
  const size_t kCols = 5 * 8, kNnz = kWeights, kInner = kNnz + 8 + (20 + 1) * 8;
  std::int64_t nnz;
  std::memcpy(&nnz, &good[kNnz], 8);
  ASSERT_EQ(nnz, 20 * 8);  // no weight pruned inside a box: rows of 8 ascending columns

  std::string bytes = good;  // row 0's second column made equal to its first
  std::memcpy(&bytes[kInner + 4], &bytes[kInner], 4);
  writeResealed(cacheFile(), bytes);
  try {
    Embedding::load(cacheFile());
    FAIL() << "repeated column accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("columns of row 0 not strictly ascending"),
              std::string::npos)
        << e.what();
  }

  // A header claiming 2^30 cage vertices: loaded in time and memory proportional to the file
  // (the triplet build before allocated 4 bytes per claimed column twice, 8 GB; the fuzzer's
  // timeout), and the weights read back are the ones written.
  bytes = good;
  const std::int64_t huge = std::int64_t(1) << 30;
  std::memcpy(&bytes[kCols], &huge, 8);
  writeResealed(cacheFile(), bytes);
  const Embedding wide = Embedding::load(cacheFile());
  EXPECT_EQ(wide.cageVertexCount(), huge);
  EXPECT_EQ(wide.meshVertexCount(), 20);
  std::vector<std::pair<int, double>> a, b;
  for (int i = 0; i < 20; ++i) {
    first.rowWeights(i, a);
    wide.rowWeights(i, b);
    EXPECT_EQ(a, b) << "row " << i;
  }
}

TEST_F(BindChecks, NonRegularCacheEntriesAreRefusedNotRead) {
  bindMeanValue(points_, cage_, options_);
  fs::remove(cacheFile());
  ASSERT_EQ(::mkfifo(cacheFile().c_str(), 0600), 0);
  Embedding e = bindMeanValue(points_, cage_, options_);  // neither blocks nor reads for ever
  EXPECT_FALSE(e.stats().fromCache);
  ASSERT_FALSE(warnings_.empty());
  EXPECT_NE(warnings_.back().find("not a regular file"), std::string::npos) << warnings_.back();
  fs::remove(cacheFile());
  fs::create_symlink("/dev/zero", cacheFile());
  e = bindMeanValue(points_, cage_, options_);
  EXPECT_FALSE(e.stats().fromCache);
  EXPECT_NE(warnings_.back().find("not a regular file"), std::string::npos) << warnings_.back();
  fs::remove(cacheFile());
  fs::create_directories(cacheFile());
  warnings_.clear();
  e = bindMeanValue(points_, cage_, options_);
  EXPECT_FALSE(e.stats().fromCache);
  ASSERT_FALSE(warnings_.empty());  // then the write fails too: a folder cannot be replaced
  EXPECT_NE(warnings_.front().find("is a directory"), std::string::npos) << warnings_.front();
}

TEST_F(BindChecks, MemoryIsEstimatedBeforeBinding) {
  BindOptions o;
  o.maxWeightBytes = 12 * 20 * 8 - 1;  // dense would need 12 bytes × 20 points × 8 cage vertices
  o.storage = WeightStorage::Dense;
  try {
    bindMeanValue(points_, cage_, o);
    FAIL() << "over-budget dense bind accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("need 1.9 KB"), std::string::npos) << e.what();
  }
  // A finer cage (642 vertices; Auto told to store up to 1000 dense) and points near its
  // surface, where pruning keeps few weights per point: over a budget dense cannot meet, Auto
  // goes sparse.
  const mesh::TriangleMesh sphere = mesh::testing::makeIcosphere(3, 1.0);
  o.denseMaxCageVertices = 1000;
  o.pruneThreshold = 0.3;  // coarse pruning: few weights kept per point
  std::vector<Vec3> near;
  for (int i = 0; i < 20; ++i) near.push_back(0.96 * sphere.vertices[size_t(31 * i)]);
  o.storage = WeightStorage::Sparse;
  o.maxWeightBytes = BindOptions().maxWeightBytes;
  const std::int64_t kept = bindMeanValue(near, sphere, o).nonZeros();
  const std::uint64_t dense = 12ull * near.size() * sphere.vertices.size();
  ASSERT_LT(52 * kept, std::int64_t(dense)) << "points not near enough the surface for this test";
  o.storage = WeightStorage::Auto;
  EXPECT_FALSE(bindMeanValue(near, sphere, o).isSparse());  // within the default budget: dense
  o.maxWeightBytes = dense - 1;
  EXPECT_TRUE(bindMeanValue(near, sphere, o).isSparse());
  o.maxWeightBytes = std::uint64_t(52 * kept) / 2;  // not even sparse fits: refused with the figure
  try {
    bindMeanValue(near, sphere, o);
    FAIL() << "over-budget sparse bind accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("even sparse"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sb::cage
