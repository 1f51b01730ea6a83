// The bytes of a triangle mesh in each file format the readers accept (OFF ASCII/binary, PLY
// ASCII/binary either endianness, STL ASCII/binary): written independently of sim/mesh, so reader
// tests and the fuzz seed generator compare the readers against a second implementation.
// ASCII coordinates are printed with 17 significant digits (exact round trip of doubles).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh::testing {

using Vec3 = Eigen::Vector3d;

// Appends v's bytes to s, big-endian if `big`, else little-endian (the host is little-endian).
template <typename T>
void put(std::string& s, T v, bool big) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big) std::reverse(b, b + sizeof(T));
  s.append(reinterpret_cast<const char*>(b), sizeof(T));
}

inline std::string offAscii(const TriangleMesh& m) {
  std::ostringstream f;
  f.precision(17);
  f << "OFF\n" << m.vertices.size() << " " << m.triangles.size() << " 0\n";
  for (const auto& v : m.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& t : m.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return f.str();
}

// OFF BINARY is big-endian: counts, float32 vertices, then per face "3 i j k 0" (no colour).
inline std::string offBinary(const TriangleMesh& m) {
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

// format: "ascii", "binary_little_endian" or "binary_big_endian"; nv vertices, nf faces.
inline std::string plyHeader(const char* format, size_t nv, size_t nf) {
  return std::string("ply\nformat ") + format + " 1.0\ncomment test\nelement vertex " +
         std::to_string(nv) + "\nproperty float x\nproperty float y\nproperty float z\n" +
         "element face " + std::to_string(nf) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

inline std::string plyAscii(const TriangleMesh& m) {
  std::ostringstream f;
  f.precision(17);
  f << plyHeader("ascii", m.vertices.size(), m.triangles.size());
  for (const auto& v : m.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& t : m.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return f.str();
}

inline std::string plyBinary(const TriangleMesh& m, bool big) {
  std::string s = plyHeader(big ? "binary_big_endian" : "binary_little_endian", m.vertices.size(),
                            m.triangles.size());
  for (const auto& v : m.vertices)
    for (int a = 0; a < 3; ++a) put<float>(s, float(v[a]), big);
  for (const auto& t : m.triangles) {
    put<std::uint8_t>(s, 3, big);
    for (int i : t) put<std::int32_t>(s, i, big);
  }
  return s;
}

// ASCII STL of loose facets (three corners each; the reader merges equal corners).
inline std::string stlAscii(const std::vector<std::array<Vec3, 3>>& facets) {
  std::ostringstream f;
  f.precision(17);
  f << "solid t\n";
  for (const auto& t : facets) {
    f << "facet normal 0 0 1\nouter loop\n";
    for (const Vec3& v : t) f << "vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    f << "endloop\nendfacet\n";
  }
  f << "endsolid t\n";
  return f.str();
}

inline std::string stlAscii(const TriangleMesh& m) {
  std::vector<std::array<Vec3, 3>> facets;
  for (const auto& t : m.triangles)
    facets.push_back(
        {m.vertices[size_t(t[0])], m.vertices[size_t(t[1])], m.vertices[size_t(t[2])]});
  return stlAscii(facets);
}

// Binary STL: 80-byte header, little-endian count, per facet a zero normal, float32 corners
// and a zero attribute word.
inline std::string stlBinary(const TriangleMesh& m) {
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

}  // namespace sb::mesh::testing
