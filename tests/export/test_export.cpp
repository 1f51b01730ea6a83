// Point caches and render-mesh OBJs: the bytes are read back here by parsers written from the
// format descriptions (not by softbody's own reader), and the atomic-write promises are checked
// on the folder's contents. Blender reads the same files in roundtrip.sh.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "sim/scene/frame_export.h"
#include "sim/scene/point_cache.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"
#include "tests/support/temp_dir_test.h"

namespace sb {
namespace {

namespace fs = std::filesystem;

class Export : public test_support::TempDirTest {
 protected:
  // Files in the test's folder (to see that nothing but the finished cache is left).
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(fs::path(path(""))))
      names.push_back(e.path().filename());
    return names;
  }
};

std::uint32_t readU32(const std::string& d, size_t at, bool bigEndian) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t byte = static_cast<unsigned char>(d[at + size_t(i)]);
    v |= byte << (bigEndian ? 8 * (3 - i) : 8 * i);
  }
  return v;
}
float readF32(const std::string& d, size_t at, bool bigEndian) {
  const std::uint32_t bits = readU32(d, at, bigEndian);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

// Three frames of five points given as two parts (2 + 3 rows); distinct, non-round values.
std::vector<std::vector<PointsRowMajor>> sampleFrames() {
  std::vector<std::vector<PointsRowMajor>> frames;
  for (int k = 0; k < 3; ++k) {
    PointsRowMajor a(2, 3), b(3, 3);
    for (int i = 0; i < 2; ++i)
      for (int c = 0; c < 3; ++c) a(i, c) = float(k) * 1.25f + float(i) * 0.1f - float(c) / 3.0f;
    for (int i = 0; i < 3; ++i)
      for (int c = 0; c < 3; ++c) b(i, c) = -float(k) * 0.5f + float(i) * 7.0f + float(c) / 7.0f;
    frames.push_back({a, b});
  }
  return frames;
}
float expectedPoint(const std::vector<PointsRowMajor>& parts, int point, int c) {
  return point < 2 ? parts[0](point, c) : parts[1](point - 2, c);
}

TEST_F(Export, Pc2HoldsItsHeaderAndEveryFrameLittleEndian) {
  const auto frames = sampleFrames();
  PointCacheWriter w(path("t.pc2"), PointCacheFormat::Pc2, 5, 3, 0.5, 0.25);
  for (const auto& f : frames) w.addFrame(f);
  w.finish();
  const std::string d = contents(path("t.pc2"));
  ASSERT_EQ(d.size(), 32u + 3 * 5 * 12);
  EXPECT_EQ(std::string(d.data(), 12), std::string("POINTCACHE2\0", 12));
  EXPECT_EQ(readU32(d, 12, false), 1u);    // version
  EXPECT_EQ(readU32(d, 16, false), 5u);    // points
  EXPECT_EQ(readF32(d, 20, false), 2.0f);  // start frame: 0.5 s / 0.25 s
  EXPECT_EQ(readF32(d, 24, false), 1.0f);  // a sample per frame
  EXPECT_EQ(readU32(d, 28, false), 3u);    // samples
  for (int k = 0; k < 3; ++k)
    for (int p = 0; p < 5; ++p)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(readF32(d, 32 + size_t(k * 5 + p) * 12 + size_t(c) * 4, false),
                  expectedPoint(frames[size_t(k)], p, c))
            << "frame " << k << " point " << p;
}

TEST_F(Export, MddHoldsCountsTimesAndEveryFrameBigEndian) {
  const auto frames = sampleFrames();
  PointCacheWriter w(path("t.mdd"), PointCacheFormat::Mdd, 5, 3, 0.5, 0.25);
  for (const auto& f : frames) w.addFrame(f);
  w.finish();
  const std::string d = contents(path("t.mdd"));
  ASSERT_EQ(d.size(), 8u + 3 * 4 + 3 * 5 * 12);
  EXPECT_EQ(readU32(d, 0, true), 3u);  // frames
  EXPECT_EQ(readU32(d, 4, true), 5u);  // points
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(readF32(d, 8 + size_t(k) * 4, true), 0.5f + 0.25f * float(k));
  const size_t data = 8 + 3 * 4;
  for (int k = 0; k < 3; ++k)
    for (int p = 0; p < 5; ++p)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(readF32(d, data + size_t(k * 5 + p) * 12 + size_t(c) * 4, true),
                  expectedPoint(frames[size_t(k)], p, c))
            << "frame " << k << " point " << p;
}

TEST_F(Export, NothingAppearsBeforeFinishAndAnAbandonedCacheLeavesNothing) {
  write("keep.pc2", "the previous take");
  const auto frames = sampleFrames();
  {
    PointCacheWriter w(path("keep.pc2"), PointCacheFormat::Pc2, 5, 3, 0, 1);
    w.addFrame(frames[0]);
    EXPECT_EQ(contents(path("keep.pc2")), "the previous take");  // untouched while writing
  }  // abandoned (a run that failed half-way)
  EXPECT_EQ(contents(path("keep.pc2")), "the previous take");
  EXPECT_EQ(files(), std::vector<std::string>{"keep.pc2"});  // no temporary file left

  PointCacheWriter w(path("keep.pc2"), PointCacheFormat::Pc2, 5, 3, 0, 1);
  w.addFrame(frames[0]);
  w.addFrame(frames[1]);
  EXPECT_THROW(w.finish(), std::logic_error);  // a frame short: not published
  EXPECT_EQ(contents(path("keep.pc2")), "the previous take");
  w.addFrame(frames[2]);
  w.finish();
  EXPECT_EQ(contents(path("keep.pc2")).size(), 32u + 3 * 5 * 12);
  EXPECT_EQ(files(), std::vector<std::string>{"keep.pc2"});
}

TEST_F(Export, WrongFramesAndLayoutsAreRefusedWithoutWriting) {
  const auto frames = sampleFrames();
  PointCacheWriter w(path("t.mdd"), PointCacheFormat::Mdd, 5, 1, 0, 1);
  EXPECT_THROW(w.addFrame({frames[0][0]}), std::invalid_argument);  // 2 points, not 5
  EXPECT_EQ(w.framesWritten(), 0);
  w.addFrame(frames[0]);
  EXPECT_THROW(w.addFrame(frames[1]), std::logic_error);  // past the declared count
  w.finish();
  EXPECT_EQ(contents(path("t.mdd")).size(), 8u + 4 + 5 * 12);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (auto bad :
       {std::tuple{0, 1, 0.0, 1.0}, std::tuple{5, 0, 0.0, 1.0}, std::tuple{5, 1, 0.0, 0.0},
        std::tuple{5, 1, 0.0, nan}, std::tuple{5, 1, nan, 1.0}}) {
    const auto [points, count, start, interval] = bad;
    EXPECT_THROW(
        PointCacheWriter(path("bad.pc2"), PointCacheFormat::Pc2, points, count, start, interval),
        std::invalid_argument);
  }
  EXPECT_EQ(files(), std::vector<std::string>{"t.mdd"});

  try {
    PointCacheWriter(path("no/such/folder/t.pc2"), PointCacheFormat::Pc2, 5, 1, 0, 1);
    FAIL() << "a cache in a missing folder was accepted";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(path("no/such/folder/t.pc2")), std::string::npos)
        << e.what();
  }
}

// The render-mesh OBJs hold the deformed render vertices bit for bit (the shortest decimal of a
// float reads back as that float), in body order, with the render triangles.
TEST_F(Export, RenderMeshObjHoldsEveryBodysVerticesExactly) {
  Scene scene = loadScene(std::string(SOFTBODY_ASSET_DIR) + "/scenes/default.json");
  SceneRunner runner(scene, true);
  for (int s = 0; s < 20; ++s) runner.step();
  const std::vector<PointsRowMajor>& meshes = runner.renderMeshes();
  writeRenderMeshesObj(scene, meshes, path("bodies.obj"), ObjObjects::PerBody);
  writeRenderMeshesObj(scene, meshes, path("one.obj"), ObjObjects::One);

  const Frame perBody = readFrame(path("bodies.obj"));
  EXPECT_DOUBLE_EQ(perBody.time, scene.world.time());
  ASSERT_EQ(perBody.bodies.size(), scene.bodies.size());
  Eigen::Index total = 0;
  for (size_t b = 0; b < meshes.size(); ++b) {
    EXPECT_EQ(perBody.bodies[b].name, scene.world.name(scene.bodies[b].handle));
    ASSERT_EQ(perBody.bodies[b].positions.rows(), meshes[b].rows());
    EXPECT_TRUE(perBody.bodies[b].positions == meshes[b]) << "body " << b;
    EXPECT_EQ(perBody.bodies[b].triangles, scene.renderTriangles(int(b)));
    total += meshes[b].rows();
  }
  ASSERT_GT(total, 1000);

  const Frame one = readFrame(path("one.obj"));
  ASSERT_EQ(one.bodies.size(), 1u);
  ASSERT_EQ(one.bodies[0].positions.rows(), total);
  Eigen::Index row = 0;
  for (size_t b = 0; b < meshes.size(); ++b) {
    EXPECT_TRUE(one.bodies[0].positions.middleRows(row, meshes[b].rows()) == meshes[b]);
    row += meshes[b].rows();
  }

  EXPECT_THROW(writeRenderMeshesObj(scene, {meshes[0]}, path("short.obj"), ObjObjects::One),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(path("short.obj")));
}

}  // namespace
}  // namespace sb
