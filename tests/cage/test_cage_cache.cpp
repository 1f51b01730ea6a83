// The automatic-cage cache (sim/cage/cage_cache.h): a second request reads the cage the first
// one wrote (the same vertices and triangles, bit for bit); other options or another mesh make
// another cage; a damaged cache file is replaced; an unusable cache folder costs only time.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "sim/cage/cage_cache.h"
#include "sim/mesh/mesh_io.h"

namespace sb::cage {
namespace {

namespace fs = std::filesystem;

// A small input so every makeCage here is quick (also under the sanitizers): the bunny's
// hand-made cage (164 vertices), made coarser.
mesh::TriangleMesh input() {
  return mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny_cage.obj");
}

CageOptions coarse() {
  CageOptions o;
  o.vertexBudget = 60;
  o.tightness = 0.0;
  return o;
}

fs::path freshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("softbody_cage_cache_" + name);
  fs::remove_all(dir);
  return dir;
}

void expectSame(const mesh::TriangleMesh& a, const mesh::TriangleMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles, b.triangles);
  for (size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]) << i;
}

TEST(CageCache, SecondRequestReadsTheSameCage) {
  const fs::path dir = freshDir("reuse");
  const mesh::TriangleMesh m = input();
  const CachedCage first = cachedCage(m, coarse(), dir.string());
  EXPECT_FALSE(first.fromCache);
  EXPECT_LE(first.report.vertices, 60);
  const std::string path = cageCachePath(dir.string(), cageCacheKey(m, coarse()));
  ASSERT_TRUE(fs::is_regular_file(path));
  const CachedCage second = cachedCage(m, coarse(), dir.string());
  EXPECT_TRUE(second.fromCache);
  expectSame(first.cage, second.cage);
  // Equal to what makeCage gives now: the cache returns the cage, not an approximation.
  expectSame(makeCage(m, coarse()).cage, second.cage);
  fs::remove_all(dir);
}

TEST(CageCache, KeyFollowsTheMeshAndTheOptionsThatChangeTheCage) {
  const mesh::TriangleMesh m = input();
  const auto key = cageCacheKey(m, coarse());
  CageOptions o = coarse();
  o.threads = 1;  // same cage on any thread count
  EXPECT_EQ(cageCacheKey(m, o), key);
  o = coarse();
  o.vertexBudget = 61;
  EXPECT_NE(cageCacheKey(m, o), key);
  o = coarse();
  o.tightness = 0.25;
  EXPECT_NE(cageCacheKey(m, o), key);
  mesh::TriangleMesh moved = m;
  moved.vertices[7].x() += 1e-12;
  EXPECT_NE(cageCacheKey(moved, coarse()), key);
}

TEST(CageCache, DamagedFileIsReplaced) {
  const fs::path dir = freshDir("damaged");
  const mesh::TriangleMesh m = input();
  fs::create_directories(dir);
  const std::string path = cageCachePath(dir.string(), cageCacheKey(m, coarse()));
  std::ofstream(path) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";  // open: not a cage
  const CachedCage c = cachedCage(m, coarse(), dir.string());
  EXPECT_FALSE(c.fromCache);
  expectSame(makeCage(m, coarse()).cage, c.cage);
  expectSame(mesh::readMesh(path), c.cage);  // the file now holds the cage
  fs::remove_all(dir);
}

TEST(CageCache, UnusableFolderOnlyCostsTime) {
  const fs::path dir = freshDir("blocked");
  std::ofstream(dir.string()) << "a file where the folder should be";
  const CachedCage c = cachedCage(input(), coarse(), dir.string());
  EXPECT_FALSE(c.fromCache);
  EXPECT_GT(c.cage.vertices.size(), 3u);
  fs::remove_all(dir);
  const CachedCage none = cachedCage(input(), coarse(), "");  // no cache at all
  expectSame(c.cage, none.cage);
}

}  // namespace
}  // namespace sb::cage
