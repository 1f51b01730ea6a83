#include "sim/mesh/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <limits>

#include "sim/base/file_io.h"
#include "sim/mesh/mesh_reading.h"

namespace sb::mesh {

using reading::ParseFail;

namespace {

std::string lowerExtension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

MeshFormat meshFormatOf(const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "stl") return MeshFormat::Stl;
  throw MeshError(path + ": unsupported mesh format '" + ext +
                  "' (expected .obj, .off, .ply or .stl)");
}

TriangleMesh parseMesh(const std::string& bytes, MeshFormat format, const std::string& name) {
  if (bytes.empty()) throw MeshError(name + ": empty file");
  TriangleMesh mesh;
  try {
    switch (format) {
      case MeshFormat::Obj:
        mesh = reading::parseObj(bytes);
        break;
      case MeshFormat::Off:
        mesh = reading::parseOff(bytes);
        break;
      case MeshFormat::Ply:
        mesh = reading::parsePly(bytes);
        break;
      case MeshFormat::Stl:
        mesh = reading::parseStl(bytes);
        break;
    }
  } catch (const ParseFail& f) {
    throw MeshError(name + ": " + f.reason);
  }
  if (mesh.vertices.empty()) throw MeshError(name + ": no vertices");
  if (mesh.vertices.size() > size_t(std::numeric_limits<int>::max()))
    throw MeshError(name + ": too many vertices");
  return mesh;
}

TriangleMesh readMesh(const std::string& path) {
  const MeshFormat format = meshFormatOf(path);
  std::string bytes;
  try {
    bytes = readFileBounded(path, kMaxMeshFileBytes);
  } catch (const FileError& e) {
    throw MeshError(e.what());
  }
  return parseMesh(bytes, format, path);
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
      // Polygons read from a file are written back as polygons (polygonFaces).
      for (const auto& face : polygonFaces(mesh)) {
        out << "f";
        for (const int c : face) out << " " << c + 1;
        out << "\n";
      }
    });
  } catch (const FileError& e) {
    throw MeshError(e.what());
  }
}

}  // namespace sb::mesh
