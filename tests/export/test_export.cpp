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

#include <nlohmann/json.hpp>

#include "sim/scene/frame_export.h"
#include "sim/scene/gltf_take.h"
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

  // A folder as the target is refused at once, not when a long export is done.
  fs::create_directories(path("folder.pc2"));
  EXPECT_THROW(PointCacheWriter(path("folder.pc2"), PointCacheFormat::Pc2, 5, 1, 0, 1), FileError);
  fs::remove(path("folder.pc2"));
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

// The glTF take read back by this test's own GLB reading (chunks per the glTF 2.0 spec): every
// accessor inside its view and the buffer, positions' min/max equal to the data, frame k =
// positions + morph target k − 1, the weights keying target k − 1 at frame k.
TEST_F(Export, GltfTakeHoldsEveryFrameAsMorphTargetsKeyedInTime) {
  Scene scene = loadScene(std::string(SOFTBODY_ASSET_DIR) + "/scenes/default.json");
  SceneRunner runner(scene, true);
  std::vector<int> counts;
  for (const PointsRowMajor& m : runner.renderMeshes()) counts.push_back(int(m.rows()));
  const int frames = 4;
  const double interval = 0.125;
  std::vector<std::vector<PointsRowMajor>> taken;
  {
    GltfTakeWriter take(path("t.glb"), scene, counts, frames, interval);
    for (int k = 0; k < frames; ++k) {
      if (k > 0)
        for (int s = 0; s < 10; ++s) runner.step();
      taken.push_back(runner.renderMeshes());
      take.addFrame(taken.back());
      EXPECT_FALSE(fs::exists(path("t.glb")));
    }
    take.finish();
  }
  const std::string d = contents(path("t.glb"));
  ASSERT_GE(d.size(), 28u);
  EXPECT_EQ(d.substr(0, 4), "glTF");
  EXPECT_EQ(readU32(d, 4, false), 2u);
  EXPECT_EQ(readU32(d, 8, false), d.size());
  const std::uint32_t jsonBytes = readU32(d, 12, false);
  EXPECT_EQ(d.substr(16, 4), "JSON");
  EXPECT_EQ(jsonBytes % 4, 0u);
  const nlohmann::json j = nlohmann::json::parse(d.substr(20, jsonBytes));
  const size_t binAt = 20 + jsonBytes;
  const std::uint32_t binBytes = readU32(d, binAt, false);
  EXPECT_EQ(d.substr(binAt + 4, 4), std::string("BIN\0", 4));
  ASSERT_EQ(binAt + 8 + binBytes, d.size());
  EXPECT_EQ(j["buffers"][0]["byteLength"], binBytes);
  const char* bin = d.data() + binAt + 8;

  // Every accessor's data lies inside its view, and every view inside the buffer.
  for (const auto& v : j["bufferViews"])
    EXPECT_LE(v["byteOffset"].get<size_t>() + v["byteLength"].get<size_t>(), binBytes);
  auto elementBytes = [](const nlohmann::json& a) { return a["type"] == "VEC3" ? 12u : 4u; };
  for (const auto& a : j["accessors"]) {
    const auto& v = j["bufferViews"][a["bufferView"].get<size_t>()];
    EXPECT_LE(a.value("byteOffset", size_t(0)) + a["count"].get<size_t>() * elementBytes(a),
              v["byteLength"].get<size_t>());
  }
  auto floats = [&](const nlohmann::json& a) {
    const auto& v = j["bufferViews"][a["bufferView"].get<size_t>()];
    const char* at = bin + v["byteOffset"].get<size_t>() + a.value("byteOffset", size_t(0));
    std::vector<float> out(a["count"].get<size_t>() * (a["type"] == "VEC3" ? 3 : 1));
    std::memcpy(out.data(), at, out.size() * 4);
    return out;
  };

  ASSERT_EQ(j["meshes"].size(), scene.bodies.size());
  for (size_t b = 0; b < scene.bodies.size(); ++b) {
    EXPECT_EQ(j["nodes"][b]["name"], scene.world.name(scene.bodies[b].handle));
    const auto& prim = j["meshes"][b]["primitives"][0];
    // Triangles as the scene draws them.
    const auto& ia = j["accessors"][prim["indices"].get<size_t>()];
    const auto& iv = j["bufferViews"][ia["bufferView"].get<size_t>()];
    const auto& tris = scene.renderTriangles(int(b));
    ASSERT_EQ(ia["count"].get<size_t>(), 3 * tris.size());
    for (size_t t = 0; t < tris.size(); ++t)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(readU32(d,
                          binAt + 8 + iv["byteOffset"].get<size_t>() +
                              ia.value("byteOffset", size_t(0)) + 12 * t + 4 * size_t(c),
                          false),
                  std::uint32_t(tris[t][size_t(c)]));
    // Frame k = positions + target k - 1; min/max are those of the accessor's data.
    const auto& base = j["accessors"][prim["attributes"]["POSITION"].get<size_t>()];
    const std::vector<float> x0 = floats(base);
    ASSERT_EQ(prim["targets"].size(), size_t(frames - 1));
    for (int k = 0; k < frames; ++k) {
      const auto& acc =
          k == 0 ? base : j["accessors"][prim["targets"][size_t(k - 1)]["POSITION"].get<size_t>()];
      const std::vector<float> data = floats(acc);
      for (int c = 0; c < 3; ++c) {
        float lo = data[size_t(c)], hi = lo;
        for (size_t i = size_t(c); i < data.size(); i += 3)
          lo = std::min(lo, data[i]), hi = std::max(hi, data[i]);
        EXPECT_EQ(acc["min"][size_t(c)].get<double>(), double(lo));
        EXPECT_EQ(acc["max"][size_t(c)].get<double>(), double(hi));
      }
      const PointsRowMajor& want = taken[size_t(k)][b];
      float worst = 0;
      for (Eigen::Index i = 0; i < want.rows(); ++i)
        for (int c = 0; c < 3; ++c) {
          const float got =
              k == 0 ? x0[size_t(3 * i + c)] : x0[size_t(3 * i + c)] + data[size_t(3 * i + c)];
          worst = std::max(worst, std::abs(got - want(i, c)));
        }
      // Exact for frame 0; later frames carry the round-off of one float subtraction and
      // addition (a few ulp of coordinates below 4 m).
      EXPECT_LE(worst, k == 0 ? 0.0f : 1e-6f) << "body " << b << " frame " << k;
    }
    // Its animation: key times k * interval, weight k - 1 at frame k.
    const auto& anim = j["animations"][0];
    const auto& channel = anim["channels"][b];
    EXPECT_EQ(channel["target"]["node"], b);
    EXPECT_EQ(channel["target"]["path"], "weights");
    const auto& sampler = anim["samplers"][channel["sampler"].get<size_t>()];
    EXPECT_EQ(sampler["interpolation"], "LINEAR");
    const std::vector<float> times = floats(j["accessors"][sampler["input"].get<size_t>()]);
    const std::vector<float> weights = floats(j["accessors"][sampler["output"].get<size_t>()]);
    ASSERT_EQ(times.size(), size_t(frames));
    ASSERT_EQ(weights.size(), size_t(frames * (frames - 1)));
    for (int k = 0; k < frames; ++k) {
      EXPECT_EQ(times[size_t(k)], float(interval * k));
      for (int t = 0; t < frames - 1; ++t)
        EXPECT_EQ(weights[size_t(k * (frames - 1) + t)], t == k - 1 ? 1.0f : 0.0f);
    }
  }
}

TEST_F(Export, GltfTakeRefusesWrongFramesAndPublishesNothingUnfinished) {
  Scene scene = loadScene(std::string(SOFTBODY_ASSET_DIR) + "/scenes/default.json");
  SceneRunner runner(scene, true);
  std::vector<int> counts;
  for (const PointsRowMajor& m : runner.renderMeshes()) counts.push_back(int(m.rows()));
  EXPECT_THROW(GltfTakeWriter(path("a.glb"), scene, {1, 2}, 2, 0.1), std::invalid_argument);
  EXPECT_THROW(GltfTakeWriter(path("a.glb"), scene, counts, 0, 0.1), std::invalid_argument);
  EXPECT_THROW(GltfTakeWriter(path("a.glb"), scene, counts, 2, 0.0), std::invalid_argument);
  // Beyond what a GLB's 32-bit sizes hold: refused up front, before anything of that size is
  // built (100,000 frames of 5.5k vertices would be 6.7 GB; the weights alone 40 GB).
  try {
    GltfTakeWriter(path("a.glb"), scene, counts, 100000, 0.1);
    FAIL() << "a take beyond 4 GB was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("more than a glTF binary can hold"), std::string::npos)
        << e.what();
  }
  {
    GltfTakeWriter take(path("a.glb"), scene, counts, 2, 0.1);
    std::vector<PointsRowMajor> wrong = runner.renderMeshes();
    wrong[1].conservativeResize(wrong[1].rows() - 1, 3);
    EXPECT_THROW(take.addFrame(wrong), std::invalid_argument);
    take.addFrame(runner.renderMeshes());
    EXPECT_THROW(take.finish(), std::logic_error);  // one frame of two
  }
  EXPECT_TRUE(files().empty());
}

}  // namespace
}  // namespace sb
