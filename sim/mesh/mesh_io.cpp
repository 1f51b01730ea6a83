#include "sim/mesh/mesh_io.h"

#include "sim/base/file_io.h"


#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>

namespace sb::mesh {

namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

// An OpenMesh importer that records the raw vertex and face lists (no half-edge structure, so
// non-manifold or inconsistently oriented faces reach validateClosedSurface instead of being dropped).
class RawImporter : public OpenMesh::IO::BaseImporter {
 public:
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::vector<int>> faces;
  int badFaces = 0;

  VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    return add_vertex(OpenMesh::Vec3d(p[0], p[1], p[2]));
  }
  VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
    vertices.emplace_back(p[0], p[1], p[2]);
    return VertexHandle(static_cast<int>(vertices.size()) - 1);
  }
  VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3d(0, 0, 0)); }
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
  FaceHandle add_face(const VHandles& idx) override {
    std::vector<int> f;
    f.reserve(idx.size());
    for (const auto& h : idx) f.push_back(h.idx());
    if (f.size() < 3) {
      ++badFaces;
      return FaceHandle();
    }
    faces.push_back(std::move(f));
    return FaceHandle(static_cast<int>(faces.size()) - 1);
  }
  FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_point(VertexHandle vh, const OpenMesh::Vec3f& p) override {
    if (vh.idx() >= 0 && vh.idx() < static_cast<int>(vertices.size())) vertices[vh.idx()] = {p[0], p[1], p[2]};
  }
  void set_halfedge(VertexHandle, HalfedgeHandle) override {}
  void set_normal(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(VertexHandle, const OpenMesh::Vec3d&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec4f&) override {}
  void set_texcoord(VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(HalfedgeHandle, HalfedgeHandle) override {}
  void set_face(HalfedgeHandle, FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_status(EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec4f&) override {}
  void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}
  size_t n_vertices() const override { return vertices.size(); }
  size_t n_faces() const override { return faces.size(); }
  size_t n_edges() const override { return 0; }
};

std::string lowerExtension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// OpenMesh's OBJ reader skips malformed lines silently and reads coordinates as float: check
// the lines it will use first (errors with a line number) and keep the double coordinates.
std::vector<Eigen::Vector3d> precheckObj(const std::string& path) {
  std::vector<Eigen::Vector3d> coords;
  std::ifstream in(path);
  std::string line;
  int lineNo = 0;
  long vertexCount = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      double x, y, z;
      if (!(ls >> x >> y >> z))
        throw MeshError(path + ": line " + std::to_string(lineNo) + ": vertex needs three numbers: '" + line + "'");
      coords.emplace_back(x, y, z);
      ++vertexCount;
    } else if (tag == "f") {
      std::string item;
      int corners = 0;
      while (ls >> item) {
        char* end = nullptr;
        const long idx = std::strtol(item.c_str(), &end, 10);
        if (end == item.c_str() || idx == 0)
          throw MeshError(path + ": line " + std::to_string(lineNo) + ": bad face index '" + item + "'");
        const long resolved = idx > 0 ? idx : vertexCount + idx + 1;
        if (resolved < 1 || resolved > vertexCount)
          throw MeshError(path + ": line " + std::to_string(lineNo) + ": face index " + std::to_string(idx) +
                          " out of range (" + std::to_string(vertexCount) + " vertices so far)");
        ++corners;
      }
      if (corners < 3)
        throw MeshError(path + ": line " + std::to_string(lineNo) + ": face needs at least 3 vertices");
    }
  }
  return coords;
}

}  // namespace

TriangleMesh readMesh(const std::string& path) {
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw MeshError(path + ": cannot open: " + std::strerror(errno));
    probe.seekg(0, std::ios::end);
    if (probe.tellg() <= 0) throw MeshError(path + ": empty file");
  }
  const std::string ext = lowerExtension(path);
  if (ext != "obj" && ext != "off" && ext != "ply" && ext != "stl")
    throw MeshError(path + ": unsupported mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  std::vector<Eigen::Vector3d> objCoords;
  if (ext == "obj") objCoords = precheckObj(path);

  RawImporter importer;
  OpenMesh::IO::Options options;
  if (!OpenMesh::IO::IOManager().read(path, importer, options))
    throw MeshError(path + ": OpenMesh could not parse the file as " + ext);
  if (importer.vertices.empty()) throw MeshError(path + ": no vertices");

  TriangleMesh mesh;
  mesh.vertices = std::move(importer.vertices);
  // OBJ: the same vertices in the same order, in full double precision.
  if (ext == "obj" && objCoords.size() == mesh.vertices.size()) mesh.vertices = std::move(objCoords);
  std::vector<int> remap(mesh.vertices.size());
  for (std::size_t i = 0; i < remap.size(); ++i) remap[i] = static_cast<int>(i);
  if (ext == "stl") {
    // STL stores every facet's corners separately: merge exactly equal positions.
    std::map<std::array<double, 3>, int> unique;
    std::vector<Eigen::Vector3d> merged;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const auto& v = mesh.vertices[i];
      const std::array<double, 3> key{v.x(), v.y(), v.z()};
      auto it = unique.find(key);
      if (it == unique.end()) {
        it = unique.emplace(key, static_cast<int>(merged.size())).first;
        merged.push_back(v);
      }
      remap[i] = it->second;
    }
    mesh.vertices = std::move(merged);
  }
  const int nv = static_cast<int>(mesh.vertices.size());
  for (std::size_t f = 0; f < importer.faces.size(); ++f) {
    const auto& face = importer.faces[f];
    for (int idx : face) {
      if (idx < 0 || idx >= static_cast<int>(remap.size()))
        throw MeshError(path + ": face " + std::to_string(f) + " has vertex index " + std::to_string(idx) +
                        " out of range");
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      mesh.triangles.push_back({remap[face[0]], remap[face[k]], remap[face[k + 1]]});
  }
  for (int i = 0; i < nv; ++i) {
    if (!mesh.vertices[i].allFinite())
      throw MeshError(path + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
  }
  return mesh;
}

void writeObj(const std::string& path, const TriangleMesh& mesh) {
  try {
    writeFileAtomic(path, [&](std::ostream& out) {
      char line[96];
      out << "# written by softbody\n";
      for (const auto& v : mesh.vertices) {
        std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
        out << line;
      }
      for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    });
  } catch (const FileError& e) {
    throw MeshError(e.what());
  }
}

}  // namespace sb::mesh
