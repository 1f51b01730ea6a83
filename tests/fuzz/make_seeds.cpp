// Writes the fuzz targets' seed corpora from the shipped files (assets/): the cage meshes in
// every format and encoding the readers take, the scenes, bind cache files of a real bind and
// frames of the default scene. Usage: make_fuzz_seeds OUTDIR (creates OUTDIR/<target>/).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "sim/cage/embedding.h"
#include "sim/mesh/mesh_io.h"
#include "sim/scene/frame_export.h"
#include "sim/scene/scene.h"
#include "tests/mesh/mesh_file_bytes.h"

namespace fs = std::filesystem;
using sb::mesh::TriangleMesh;
using namespace sb::mesh::testing;

namespace {

const std::string kAssets = SOFTBODY_ASSET_DIR;

void write(const fs::path& p, const std::string& bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << bytes;
}

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_fuzz_seeds OUTDIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  int files = 0;
  auto add = [&](const std::string& target, const std::string& name, const std::string& bytes) {
    write(out / target / name, bytes);
    ++files;
  };
  for (const char* name : {"bunny_cage", "suzanne_cage"}) {
    const TriangleMesh m = sb::mesh::readMesh(kAssets + "/meshes/" + name + ".obj");
    add("mesh_obj", std::string(name) + ".obj", readAll(kAssets + "/meshes/" + name + ".obj"));
    add("mesh_off", std::string(name) + ".off", offAscii(m));
    add("mesh_off", std::string(name) + "_binary.off", offBinary(m));
    add("mesh_ply", std::string(name) + ".ply", plyAscii(m));
    add("mesh_ply", std::string(name) + "_le.ply", plyBinary(m, false));
    add("mesh_ply", std::string(name) + "_be.ply", plyBinary(m, true));
    add("mesh_stl", std::string(name) + ".stl", stlAscii(m));
    add("mesh_stl", std::string(name) + "_binary.stl", stlBinary(m));
  }
  // Scenes without their render meshes: binding a 35k-vertex mesh would take seconds per run
  // under ASan; a render mesh that is a cage file keeps that code path in play cheaply.
  for (const auto& e : fs::directory_iterator(kAssets + "/scenes"))
    if (e.path().extension() == ".json") {
      nlohmann::json j = nlohmann::json::parse(readAll(e.path()));
      for (nlohmann::json& b : j["bodies"])
        if (b.contains("renderMesh")) b["renderMesh"] = b["mesh"];
      add("scene", e.path().filename().string(), j.dump(1));
    }

  // Bind caches: a dense and a sparse bind of part of the bunny to its cage.
  const TriangleMesh cage = sb::mesh::readMesh(kAssets + "/meshes/bunny_cage.obj");
  const TriangleMesh bunny = sb::mesh::readMesh(kAssets + "/meshes/bunny.obj");
  std::vector<Eigen::Vector3d> points(bunny.vertices.begin(), bunny.vertices.begin() + 40);
  for (auto storage : {sb::cage::WeightStorage::Dense, sb::cage::WeightStorage::Sparse}) {
    sb::cage::BindOptions o;
    o.storage = storage;
    const sb::cage::Embedding e = sb::cage::bindMeanValue(points, cage, o);
    const fs::path p = out / "bind_cache" /
                       (storage == sb::cage::WeightStorage::Dense ? "dense.sbw" : "sparse.sbw");
    fs::create_directories(p.parent_path());
    e.save(p.string(), {1, 2});
    ++files;
  }

  // Frames of the default scene (particles only: its render meshes are not needed here).
  sb::Scene scene = sb::loadScene(kAssets + "/scenes/default.json");
  for (int i = 0; i < 5; ++i) scene.world.step();
  fs::create_directories(out / "frame");
  sb::writeFrame(scene, (out / "frame" / "default.obj").string(), sb::FrameFormat::Obj);
  sb::writeFrame(scene, (out / "frame" / "default.bin").string(), sb::FrameFormat::Binary);
  files += 2;
  std::printf("wrote %d seed files to %s\n", files, out.c_str());
  return 0;
}
