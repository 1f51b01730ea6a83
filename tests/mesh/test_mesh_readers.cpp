// The bounded mesh readers (issue #18): every finding as a reproducer, binary formats round
// trip, non-regular files are refused, and byte-flipped files never crash a reader.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "tests/mesh/mesh_file_bytes.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::mesh {
namespace {

namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;
using namespace sb::mesh::testing;  // the file encoders

// The message of parsing `bytes`, or "" when it parses.
std::string errorOf(const std::string& bytes, MeshFormat format) {
  try {
    parseMesh(bytes, format, "m");
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_ERROR(bytes, format, part)                                     \
  do {                                                                        \
    const std::string e_ = errorOf(bytes, format);                            \
    EXPECT_NE(e_.find(part), std::string::npos) << "message: '" << e_ << "'"; \
  } while (0)

const TriangleMesh& cube() {
  static const TriangleMesh c = testing::makeBox(1, 1, 1, Vec3(2, 1, 0.5), Vec3(-1, 0.25, 3));
  return c;
}

void expectCube(const TriangleMesh& r) {
  ASSERT_EQ(r.vertices.size(), cube().vertices.size());
  ASSERT_EQ(r.triangles.size(), cube().triangles.size());
  // Same vertex set (STL renumbers by first use) and a closed surface.
  for (const auto& v : cube().vertices) {
    bool found = false;
    for (const auto& w : r.vertices) found = found || v == w;
    EXPECT_TRUE(found) << v.transpose();
  }
  EXPECT_NO_THROW(validateClosedSurface(r, "cube"));
}

TEST(MeshReaders, BinaryFormatsRoundTrip) {
  expectCube(parseMesh(offBinary(cube()), MeshFormat::Off, "m"));  // standard big-endian OFF
  expectCube(parseMesh(plyBinary(cube(), false), MeshFormat::Ply, "m"));
  expectCube(parseMesh(plyBinary(cube(), true), MeshFormat::Ply, "m"));
  expectCube(parseMesh(plyAscii(cube()), MeshFormat::Ply, "m"));
  expectCube(parseMesh(stlBinary(cube()), MeshFormat::Stl, "m"));
  expectCube(parseMesh(offAscii(cube()), MeshFormat::Off, "m"));
}

TEST(MeshReaders, BinaryOffIsBigEndian) {
  // Read as little-endian, the counts of this file would be 2^24 and 2^24·12: refused, not guessed.
  const TriangleMesh r = parseMesh(offBinary(cube()), MeshFormat::Off, "m");
  EXPECT_EQ(r.vertices[1], cube().vertices[1]);
  std::string little = "OFF BINARY\n";
  put<std::int32_t>(little, 8, false);
  put<std::int32_t>(little, 12, false);
  put<std::int32_t>(little, 0, false);
  little += offBinary(cube()).substr(11 + 12);
  EXPECT_NE(errorOf(little, MeshFormat::Off), "");
}

TEST(MeshReaders, PlyPropertyBeforeElementIsRefused) {
  EXPECT_ERROR("ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\nend_header\n1\n",
               MeshFormat::Ply, "line 3: a property before any element");
}

TEST(MeshReaders, HeaderCountsMustMatchTheBody) {
  // OFF: one vertex more than the body holds.
  std::string off = offAscii(cube());
  off.replace(off.find("\n8 ") + 1, 1, "9");
  EXPECT_ERROR(off, MeshFormat::Off, "");
  EXPECT_NE(errorOf(off, MeshFormat::Off), "");
  // OFF: one face more declared than given.
  off = offAscii(cube());
  off.replace(off.find(" 12 "), 4, " 13 ");
  EXPECT_ERROR(off, MeshFormat::Off, "declares 13 faces, the file ends after 12");
  // OFF: truncated in the middle of the vertices (no duplicated vertex invented).
  off = offAscii(cube());
  EXPECT_ERROR(off.substr(0, off.find("3 0 ")), MeshFormat::Off, "the file ends after 0");
  // OFF: data after what the header declares.
  EXPECT_ERROR(offAscii(cube()) + "3 0 1 2\n", MeshFormat::Off, "data after");
  // PLY: header cut after "element vertex".
  const std::string ply = plyAscii(cube());
  EXPECT_ERROR(ply.substr(0, ply.find("element vertex") + 14), MeshFormat::Ply, "");
  EXPECT_NE(errorOf(ply.substr(0, ply.find("element vertex") + 14), MeshFormat::Ply), "");
  // PLY: one vertex more declared; one face more declared; truncated binary.
  std::string more = ply;
  more.replace(more.find("vertex 8"), 8, "vertex 9");
  EXPECT_NE(errorOf(more, MeshFormat::Ply), "");
  more = ply;
  more.replace(more.find("face 12"), 7, "face 13");
  EXPECT_NE(errorOf(more, MeshFormat::Ply), "");
  const std::string bin = plyBinary(cube(), false);
  EXPECT_ERROR(bin.substr(0, bin.size() - 1), MeshFormat::Ply, "ends");
  EXPECT_ERROR(bin + "x", MeshFormat::Ply, "data after");
  // Binary OFF and STL: truncated, and one byte too many.
  const std::string boff = offBinary(cube());
  EXPECT_NE(errorOf(boff.substr(0, boff.size() - 4), MeshFormat::Off), "");
  EXPECT_ERROR(boff + "x", MeshFormat::Off, "bytes after");
  const std::string stl = stlBinary(cube());
  EXPECT_NE(errorOf(stl.substr(0, stl.size() - 1), MeshFormat::Stl), "");
}

TEST(MeshReaders, HugeDeclaredCountsFailFastWithoutAllocating) {
  const std::string offSmall = "OFF\n999999 1 0\n0 0 0\n";  // 21 bytes
  const std::string plySmall =
      "ply\nformat ascii 1.0\nelement vertex 999999\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n";
  std::string boff = "OFF BINARY\n";
  put<std::int32_t>(boff, 999999, true);
  put<std::int32_t>(boff, 0, true);
  put<std::int32_t>(boff, 0, true);
  std::string bply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2147483647\nproperty double x\n"
      "property double y\nproperty double z\nelement face 2147483647\n"
      "property list uint int vertex_indices\nend_header\n";
  std::string stl(80, ' ');
  put<std::uint32_t>(stl, 0xffffffffu, false);
  EXPECT_ERROR(offSmall, MeshFormat::Off, "declares 999999 vertices");
  EXPECT_NE(errorOf(plySmall, MeshFormat::Ply), "");
  EXPECT_ERROR(boff, MeshFormat::Off, "declares 999999 vertices");
  EXPECT_ERROR(bply, MeshFormat::Ply, "more than the");
  EXPECT_NE(errorOf(stl, MeshFormat::Stl), "");
  EXPECT_NE(
      errorOf("ply\nformat ascii 1.0\nelement junk 2000000000\nend_header\n", MeshFormat::Ply), "");
}

TEST(MeshReaders, NonFiniteAndOutOfFloatRangeCoordinatesAreRefused) {
  EXPECT_ERROR("OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", MeshFormat::Off,
               "line 4: coordinate nan is not finite");
  EXPECT_ERROR("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::Obj, "line 2: coordinate inf");
  // 1e39 passes a double parse but not float: refused in every format alike.
  EXPECT_ERROR("v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::Obj,
               "line 2: coordinate 1e+39 is beyond float range");
  EXPECT_ERROR("OFF\n3 1 0\n0 0 0\n1e39 0 0\n0 1 0\n3 0 1 2\n", MeshFormat::Off,
               "beyond float range");
  std::string ply = plyAscii(cube());
  const size_t first = ply.find("end_header\n") + 11;
  ply.replace(first, ply.find(' ', first) - first, "nan");
  EXPECT_ERROR(ply, MeshFormat::Ply, "vertex 0: coordinate nan");
  std::string bply = plyBinary(cube(), false);
  const size_t data = bply.find("end_header\n") + 11;
  const float nan = std::nanf("");
  std::memcpy(&bply[data + 4], &nan, 4);
  EXPECT_ERROR(bply, MeshFormat::Ply, "not finite");
}

TEST(MeshReaders, StlNanCornerIsRefusedBeforeMerging) {
  // The NaN corner must not be merged into the real vertex at (0, 0, 0) nor be accepted.
  const double n = std::nan("");
  const std::vector<std::array<Vec3, 3>> facets = {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
                                                   {Vec3(0, 0, 0), Vec3(n, 0, 0), Vec3(0, 0, 1)}};
  EXPECT_ERROR(stlAscii(facets), MeshFormat::Stl, "line 12: coordinate nan is not finite");
  TriangleMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(n, 0, 0)};
  m.triangles = {{0, 1, 2}, {0, 3, 2}};
  EXPECT_ERROR(stlBinary(m), MeshFormat::Stl, "triangle 1: coordinate nan is not finite");
}

TEST(MeshReaders, ObjMessagesNameTheFilesOwnIndex) {
  // 4 vertices, face index 5 (1-based): the message shows 5 and the line, not a 0-based 4.
  EXPECT_ERROR("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 5\n", MeshFormat::Obj,
               "line 5: face index 5 out of range (4 vertices so far)");
  EXPECT_ERROR("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 4\n", MeshFormat::Off,
               "line 7: vertex index 4 out of range (4 vertices)");
}

TEST(MeshReaders, TwoCornerFacesAreRefusedInEveryFormat) {
  EXPECT_ERROR("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", MeshFormat::Obj, "at least 3 vertices");
  EXPECT_ERROR("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", MeshFormat::Off, "at least 3 vertices");
  EXPECT_ERROR(plyHeader("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", MeshFormat::Ply,
               "at least 3 vertices");
  EXPECT_ERROR(
      "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 "
      "0\nendloop\nendfacet\nendsolid a\n",
      MeshFormat::Stl, "exactly 3 vertices");
}

TEST(MeshReaders, ByteFlipsNeverCrash) {
  // Every single-byte change of small valid files (flipped bits, 0x00, 0xff): each either parses
  // or is refused with a MeshError; nothing else (ASan/UBSan check the memory side).
  const std::pair<std::string, MeshFormat> files[] = {
      {plyBinary(cube(), false), MeshFormat::Ply}, {plyBinary(cube(), true), MeshFormat::Ply},
      {plyAscii(cube()), MeshFormat::Ply},         {offBinary(cube()), MeshFormat::Off},
      {offAscii(cube()), MeshFormat::Off},         {stlBinary(cube()), MeshFormat::Stl}};
  int parsed = 0, refused = 0;
  for (const auto& [file, format] : files)
    for (size_t i = 0; i < file.size(); ++i)
      for (unsigned char mask : {0x01, 0x80, 0xff}) {
        std::string bad = file;
        bad[i] = char(static_cast<unsigned char>(bad[i]) ^ mask);
        try {
          const TriangleMesh m = parseMesh(bad, format, "m");
          for (const auto& t : m.triangles)
            for (int v : t) ASSERT_TRUE(v >= 0 && size_t(v) < m.vertices.size());
          for (const auto& v : m.vertices) ASSERT_TRUE(v.allFinite());
          ++parsed;
        } catch (const MeshError&) {
          ++refused;
        }
      }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(refused, 0);
}

using MeshReaderFiles = sb::test_support::TempDirTest;

TEST_F(MeshReaderFiles, NonRegularFilesAreRefusedAtOnce) {
  const std::string fifo = path("fifo.obj");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    readMesh(fifo);
    FAIL() << "FIFO accepted";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  fs::create_directories(path("folder.obj"));
  try {
    readMesh(path("folder.obj"));
    FAIL() << "folder accepted";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  fs::create_symlink("/dev/zero", path("zero.stl"));
  EXPECT_THROW(readMesh(path("zero.stl")), MeshError);
}

}  // namespace
}  // namespace sb::mesh
