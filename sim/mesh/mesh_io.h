// Mesh files <-> TriangleMesh. Our own small readers for OBJ, OFF (ASCII and the standard
// big-endian binary), PLY (ASCII, binary little- and big-endian) and STL (ASCII and binary),
// parsing bytes in memory: every file is read whole with readFileBounded (sim/base/file_io.h),
// so FIFOs, devices and folders are refused and no file larger than kMaxMeshFileBytes is read.
//
// One rule set for every format:
// - the body must match the header exactly (OFF, PLY, binary STL): a count that promises more
//   than the file holds, or data left over after what the header declares, is an error; nothing
//   is invented and nothing is allocated beyond what the bytes can hold;
// - every face has at least three corners, each a valid vertex index (named in the file's own
//   numbering: 1-based in OBJ, 0-based in OFF and PLY); larger faces are fan-triangulated;
// - every coordinate is finite and within float range (|c| ≤ 3.4e38: the simulation and the
//   renderer store float32), checked before STL's corners are merged;
// - STL's per-facet corners are merged when their positions are exactly equal, so a closed
//   surface comes back closed.
// Files with vertices only are accepted (triangles empty). Memory: at most about 3 bytes of
// vertices and triangles per byte of file.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh {

// what() = "PATH: reason" (with "line N" / "vertex N" / "face N" where it is known).
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Largest mesh file read: 512 MB (a 64 MB OBJ is already a multi-million-triangle mesh).
inline constexpr std::uint64_t kMaxMeshFileBytes = 512ull * 1000 * 1000;

enum class MeshFormat { Obj, Off, Ply, Stl };

// By the file name's extension (case-insensitive); throws MeshError for others.
MeshFormat meshFormatOf(const std::string& path);

// Reads a regular file of at most kMaxMeshFileBytes bytes (format by extension).
TriangleMesh readMesh(const std::string& path);

// Parses a whole file's bytes; `name` prefixes the messages. Bounded by bytes.size() in time and
// memory whatever the bytes say (the fuzz targets call this).
TriangleMesh parseMesh(const std::string& bytes, MeshFormat format, const std::string& name);

// Writes "v x y z" (17 significant digits, exact round trip) and "f a b c" (1-based) lines.
// Atomic (sim/base/file_io.h): PATH is replaced whole or not at all.
void writeObj(const std::string& path, const TriangleMesh& mesh);

}  // namespace sb::mesh
