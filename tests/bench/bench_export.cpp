// Export benchmarks (Google Benchmark): a take of 10 s at 30 frames per second (300 frames) of
// the large scene's render meshes (54 bodies, ≥ 50k vertices), written as each export format.
// Run a Release build:  build/release/tests/bench/bench_export
// The frames are ten distinct states of the scene, cycled: the simulation is not timed.
// Counters: ms per take, the bytes written per second, vertex-frames per second (items).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "sim/scene/frame_export.h"
#include "sim/scene/gltf_take.h"
#include "sim/scene/point_cache.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"

namespace sb {
namespace {

constexpr int kFrames = 300;

struct Take {
  Scene scene;
  std::vector<std::vector<PointsRowMajor>> states;  // ten frames of every body's render mesh
  long long vertices = 0;
};

const Take& take() {
  static const Take loaded = [] {
    Take t;
    t.scene = loadScene(std::string(SOFTBODY_ASSET_DIR) + "/scenes/large.json");
    SceneRunner runner(t.scene, /*deform=*/true);
    for (int k = 0; k < 10; ++k) {
      for (int s = 0; s < 8; ++s) runner.step();  // 1/30 s at the scene's 1/240 s steps
      t.states.push_back(runner.renderMeshes());
    }
    for (const PointsRowMajor& m : t.states[0]) t.vertices += m.rows();
    return t;
  }();
  return loaded;
}

std::filesystem::path outDir() {
  const auto dir = std::filesystem::temp_directory_path() / "softbody_bench_export";
  std::filesystem::create_directories(dir);
  return dir;
}

void report(benchmark::State& state, long long bytesPerTake) {
  const Take& t = take();
  state.SetBytesProcessed(state.iterations() * bytesPerTake);
  state.counters["vertices"] = double(t.vertices);
  state.SetItemsProcessed(state.iterations() * t.vertices * kFrames);  // vertex-frames
}

// Arg 0: PC2, 1: MDD. One cache file of the whole take, published atomically (with its fsync).
void BM_ExportPointCache(benchmark::State& state) {
  const Take& t = take();
  const auto format = state.range(0) == 0 ? PointCacheFormat::Pc2 : PointCacheFormat::Mdd;
  const std::string path = (outDir() / (format == PointCacheFormat::Pc2 ? "take.pc2" : "take.mdd"));
  for (auto _ : state) {
    PointCacheWriter cache(path, format, int(t.vertices), kFrames, 0.0, 1.0 / 30);
    for (int k = 0; k < kFrames; ++k) cache.addFrame(t.states[size_t(k % 10)]);
    cache.finish();
  }
  report(state, (long long)std::filesystem::file_size(path));
  state.SetLabel(format == PointCacheFormat::Pc2 ? "pc2" : "mdd");
}
BENCHMARK(BM_ExportPointCache)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// One glTF binary: a mesh per body, the frames as morph targets (softbody run --export-gltf).
void BM_ExportGltf(benchmark::State& state) {
  const Take& t = take();
  const std::string path = outDir() / "take.glb";
  std::vector<int> counts;
  for (const PointsRowMajor& m : t.states[0]) counts.push_back(int(m.rows()));
  for (auto _ : state) {
    GltfTakeWriter gltf(path, t.scene, counts, kFrames, 1.0 / 30);
    for (int k = 0; k < kFrames; ++k) gltf.addFrame(t.states[size_t(k % 10)]);
    gltf.finish();
  }
  report(state, (long long)std::filesystem::file_size(path));
}
BENCHMARK(BM_ExportGltf)->Unit(benchmark::kMillisecond)->UseRealTime();

// An OBJ per frame, an object per body (softbody run --export-meshes).
void BM_ExportObjSequence(benchmark::State& state) {
  const Take& t = take();
  const auto dir = outDir() / "seq";
  std::filesystem::create_directories(dir);
  long long bytes = 0;
  for (auto _ : state) {
    bytes = 0;
    for (int k = 0; k < kFrames; ++k) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%06d.obj", k);
      writeRenderMeshesObj(t.scene, t.states[size_t(k % 10)], (dir / name).string(),
                           ObjObjects::PerBody);
      bytes += (long long)std::filesystem::file_size(dir / name);
    }
  }
  report(state, bytes);
}
BENCHMARK(BM_ExportObjSequence)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
}  // namespace sb

BENCHMARK_MAIN();
