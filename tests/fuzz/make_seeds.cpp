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

namespace fs = std::filesystem;
using sb::mesh::TriangleMesh;

namespace {

const std::string kAssets = SOFTBODY_ASSET_DIR;

template <typename T>
void put(std::string& s, T v, bool big) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big) std::reverse(b, b + sizeof(T));
  s.append(reinterpret_cast<const char*>(b), sizeof(T));
}

void write(const fs::path& p, const std::string& bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << bytes;
}

std::string offAscii(const TriangleMesh& m) {
  std::ostringstream f;
  f.precision(9);
  f << "OFF\n# seed\n" << m.vertices.size() << " " << m.triangles.size() << " 0\n";
  for (const auto& v : m.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& t : m.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return f.str();
}

std::string offBinary(const TriangleMesh& m) {
  std::string s = "OFF BINARY\n";
  put<std::int32_t>(s, int(m.vertices.size()), true);
  put<std::int32_t>(s, int(m.triangles.size()), true);
  put<std::int32_t>(s, 0, true);
  for (const auto& v : m.vertices)
    for (int a = 0; a < 3; ++a) put<float>(s, float(v[a]), true);
  for (const auto& t : m.triangles) {
    put<std::int32_t>(s, 3, true);
    for (int i : t) put<std::int32_t>(s, i, true);
    put<std::int32_t>(s, 0, true);
  }
  return s;
}

std::string plyHeader(const char* format, const TriangleMesh& m) {
  return std::string("ply\nformat ") + format + " 1.0\ncomment seed\nelement vertex " +
         std::to_string(m.vertices.size()) + "\nproperty float x\nproperty float y\nproperty float z\n" +
         "element face " + std::to_string(m.triangles.size()) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string plyAscii(const TriangleMesh& m) {
  std::ostringstream f;
  f.precision(9);
  f << plyHeader("ascii", m);
  for (const auto& v : m.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& t : m.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return f.str();
}

std::string plyBinary(const TriangleMesh& m, bool big) {
  std::string s = plyHeader(big ? "binary_big_endian" : "binary_little_endian", m);
  for (const auto& v : m.vertices)
    for (int a = 0; a < 3; ++a) put<float>(s, float(v[a]), big);
  for (const auto& t : m.triangles) {
    put<std::uint8_t>(s, 3, big);
    for (int i : t) put<std::int32_t>(s, i, big);
  }
  return s;
}

std::string stlAscii(const TriangleMesh& m) {
  std::ostringstream f;
  f.precision(9);
  f << "solid seed\n";
  for (const auto& t : m.triangles) {
    f << " facet normal 0 0 1\n  outer loop\n";
    for (int i : t) f << "   vertex " << m.vertices[size_t(i)].x() << " " << m.vertices[size_t(i)].y() << " " << m.vertices[size_t(i)].z() << "\n";
    f << "  endloop\n endfacet\n";
  }
  f << "endsolid seed\n";
  return f.str();
}

std::string stlBinary(const TriangleMesh& m) {
  std::string s(80, ' ');
  put<std::uint32_t>(s, std::uint32_t(m.triangles.size()), false);
  for (const auto& t : m.triangles) {
    for (int a = 0; a < 3; ++a) put<float>(s, 0.0f, false);
    for (int i : t)
      for (int a = 0; a < 3; ++a) put<float>(s, float(m.vertices[size_t(i)][a]), false);
    put<std::uint16_t>(s, 0, false);
  }
  return s;
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
    const fs::path p = out / "bind_cache" / (storage == sb::cage::WeightStorage::Dense ? "dense.sbw" : "sparse.sbw");
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
