// Mesh I/O (OBJ, OFF, PLY, STL round trips; errors) and cage validation (each failure names
// the offending element).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::mesh {
namespace {

namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;

using MeshIo = sb::test_support::TempDirTest;

// Checks that b has the same triangles as a up to a vertex renumbering by position.
void expectSameSurface(const TriangleMesh& a, const TriangleMesh& b, double tol) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  std::vector<int> map(a.vertices.size(), -1);
  for (std::size_t i = 0; i < a.vertices.size(); ++i)
    for (std::size_t j = 0; j < b.vertices.size(); ++j)
      if ((a.vertices[i] - b.vertices[j]).norm() <= tol) map[i] = static_cast<int>(j);
  for (int m : map) ASSERT_GE(m, 0);
  for (std::size_t t = 0; t < a.triangles.size(); ++t) {
    const auto& ta = a.triangles[t];
    const auto& tb = b.triangles[t];
    // same cyclic order (orientation preserved)
    bool same = false;
    for (int r = 0; r < 3; ++r)
      same = same || (map[ta[0]] == tb[r] && map[ta[1]] == tb[(r + 1) % 3] &&
                      map[ta[2]] == tb[(r + 2) % 3]);
    EXPECT_TRUE(same) << "triangle " << t;
  }
}

TEST_F(MeshIo, ObjRoundTripIsExact) {
  TriangleMesh m = testing::makeIcosphere(1, 0.1234567890123, Vec3(1.0 / 3.0, -2e-7, 5e3));
  writeObj(path("a.obj"), m);
  const TriangleMesh r = readMesh(path("a.obj"));
  ASSERT_EQ(r.vertices.size(), m.vertices.size());
  for (std::size_t i = 0; i < m.vertices.size(); ++i) EXPECT_EQ(r.vertices[i], m.vertices[i]) << i;
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_FALSE(fs::exists(path("a.obj.tmp." + std::to_string(::getpid()))));
}

TEST_F(MeshIo, ObjQuadsAreTriangulatedAndNegativeIndicesWork) {
  write("q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -4 -2 -3\n");
  const TriangleMesh r = readMesh(path("q.obj"));
  ASSERT_EQ(r.triangles.size(), 3u);
  EXPECT_EQ(r.triangles[0], (std::array<int, 3>{0, 1, 2}));
  EXPECT_EQ(r.triangles[1], (std::array<int, 3>{0, 2, 3}));
  EXPECT_EQ(r.triangles[2], (std::array<int, 3>{0, 2, 1}));
}

TEST_F(MeshIo, OffPlyStlReadTheSameCube) {
  const TriangleMesh cube = testing::makeBox(1, 1, 1, Vec3(2, 1, 0.5), Vec3(-1, 0.25, 3));
  // OFF
  {
    std::ofstream f(path("c.off"));
    f.precision(17);
    f << "OFF\n" << cube.vertices.size() << " " << cube.triangles.size() << " 0\n";
    for (const auto& v : cube.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
    for (const auto& t : cube.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  }
  // PLY (ASCII)
  {
    std::ofstream f(path("c.ply"));
    f.precision(17);
    f << "ply\nformat ascii 1.0\nelement vertex " << cube.vertices.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
      << cube.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& v : cube.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
    for (const auto& t : cube.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  }
  // STL (ASCII): three separate vertices per facet
  {
    std::ofstream f(path("c.stl"));
    f.precision(17);
    f << "solid cube\n";
    for (const auto& t : cube.triangles) {
      const Vec3 n = (cube.vertices[t[1]] - cube.vertices[t[0]])
                         .cross(cube.vertices[t[2]] - cube.vertices[t[0]])
                         .normalized();
      f << " facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n  outer loop\n";
      for (int k = 0; k < 3; ++k)
        f << "   vertex " << cube.vertices[t[k]].x() << " " << cube.vertices[t[k]].y() << " "
          << cube.vertices[t[k]].z() << "\n";
      f << "  endloop\n endfacet\n";
    }
    f << "endsolid cube\n";
  }
  for (const char* name : {"c.off", "c.ply", "c.stl"}) {
    SCOPED_TRACE(name);
    const TriangleMesh r = readMesh(path(name));
    // The values are exactly representable in float, so every reader returns them exactly.
    expectSameSurface(cube, r, 0.0);
    EXPECT_NO_THROW(
        validateClosedSurface(r, name));  // STL vertices were merged: the cube is closed
  }
}

TEST_F(MeshIo, VerticesOnlyFileIsAccepted) {
  write("p.obj", "# points\nv 1 2 3\nv 4 5 6.5\n");
  const TriangleMesh r = readMesh(path("p.obj"));
  ASSERT_EQ(r.vertices.size(), 2u);
  EXPECT_TRUE(r.triangles.empty());
  EXPECT_EQ(r.vertices[1], Vec3(4, 5, 6.5));
}

TEST_F(MeshIo, ErrorsNameTheFileAndReason) {
  auto expectError = [&](const std::string& file, const std::string& part) {
    try {
      readMesh(file);
      FAIL() << "no error for " << file;
    } catch (const MeshError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file), std::string::npos) << what;
      EXPECT_NE(what.find(part), std::string::npos) << what;
    }
  };
  expectError(path("missing.obj"), "cannot open");
  write("empty.obj", "");
  expectError(path("empty.obj"), "empty");
  write("x.xyz", "1 2 3\n");
  expectError(path("x.xyz"), "unsupported");
  write("badv.obj", "v 0 0 0\nv 1 zero 0\n");
  expectError(path("badv.obj"), "line 2");
  write("badf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  expectError(path("badf.obj"), "line 4");
  write("junk.off", "this is not an OFF file\n");
  expectError(path("junk.off"), "junk.off");
  EXPECT_THROW(writeObj(path("no/such/dir/out.obj"), testing::makeBox(1, 1, 1)), MeshError);
}

TEST(RealMeshes, LoadAndCagesAreValid) {
  const std::string dir = SOFTBODY_TEST_MESH_DIR;
  for (const char* name : {"bunny_cage.obj", "suzanne_cage.obj"}) {
    const TriangleMesh c = readMesh(dir + "/" + name);
    EXPECT_GT(c.triangles.size(), 100u);
    EXPECT_NO_THROW(validateClosedSurface(c, name));
  }
  for (const char* name : {"bunny.obj", "suzanne.obj", "hand.obj"}) {
    const TriangleMesh m = readMesh(dir + "/" + name);
    EXPECT_GT(m.vertices.size(), 1000u);
    EXPECT_GT(m.triangles.size(), 2000u);
  }
}

// ---------------------------------------------------------------------------------------------
// Validation

std::string validationError(const TriangleMesh& cage) {
  try {
    validateClosedSurface(cage, "test");
  } catch (const SurfaceError& e) {
    return e.what();
  }
  return "";
}

TEST(CageValidation, AcceptsClosedOutwardCages) {
  EXPECT_EQ(validationError(testing::makeBox(2, 3, 4)), "");
  EXPECT_EQ(validationError(testing::makeTorus()), "");  // genus 1 is fine
}

TEST(CageValidation, OpenCage) {
  TriangleMesh c = testing::makeBox(1, 1, 1);
  c.triangles.erase(c.triangles.begin() + 4);
  const std::string e = validationError(c);
  EXPECT_NE(e.find("not closed"), std::string::npos) << e;
  EXPECT_NE(e.find("edge"), std::string::npos) << e;
}

TEST(CageValidation, NonManifoldEdge) {
  // Two tetrahedra sharing the edge 0-1.
  TriangleMesh c;
  c.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}, {0, 0, -1}};
  c.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},
                 {0, 1, 4}, {0, 4, 5}, {0, 5, 1}, {1, 5, 4}};
  const std::string e = validationError(c);
  EXPECT_NE(e.find("not 2-manifold"), std::string::npos) << e;
  EXPECT_NE(e.find("edge 0-1"), std::string::npos) << e;
}

TEST(CageValidation, NonManifoldVertex) {
  // Two tetrahedra sharing only vertex 0, joined into one component... a vertex shared by two
  // fans is reported (as two components: the fans touch only at the vertex).
  TriangleMesh c;
  c.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  c.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},
                 {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
  const std::string e = validationError(c);
  EXPECT_NE(e.find("components"), std::string::npos) << e;
}

// One edge-connected surface whose vertex P has two separate fans: a tube bent into a loop
// with both ends coned to the same apex P.
TEST(CageValidation, PinchedVertexJoiningTwoFans) {
  const int rings = 10, k = 6;
  TriangleMesh c;
  for (int r = 0; r < rings; ++r) {
    const double phi = 2 * M_PI * (r + 1) / (rings + 1);
    const Vec3 centre(std::cos(phi), std::sin(phi), 0.0), radial = centre, up(0, 0, 1);
    for (int j = 0; j < k; ++j) {
      const double a = 2 * M_PI * j / k;
      c.vertices.push_back(centre + 0.2 * (std::cos(a) * radial + std::sin(a) * up));
    }
  }
  c.vertices.emplace_back(1.0, 0.0, 0.0);
  const int P = static_cast<int>(c.vertices.size()) - 1;
  for (int r = 0; r + 1 < rings; ++r)
    for (int j = 0; j < k; ++j) {
      const int a = r * k + j, b = r * k + (j + 1) % k, a2 = a + k, b2 = b + k;
      c.triangles.push_back({a, a2, b2});
      c.triangles.push_back({a, b2, b});
    }
  const std::size_t coneStart = c.triangles.size();
  for (int j = 0; j < k; ++j) {
    c.triangles.push_back({P, j, (j + 1) % k});
    c.triangles.push_back({P, (rings - 1) * k + (j + 1) % k, (rings - 1) * k + j});
  }
  // Make the cones agree with the tube's orientation whichever way the tube came out.
  if (validationError(c).find("inconsistent orientation") != std::string::npos)
    for (std::size_t t = coneStart; t < c.triangles.size(); ++t)
      std::swap(c.triangles[t][1], c.triangles[t][2]);
  const std::string e = validationError(c);
  EXPECT_NE(e.find("vertex " + std::to_string(P)), std::string::npos) << e;
  EXPECT_NE(e.find("separate fans"), std::string::npos) << e;
}

TEST(CageValidation, TwoComponents) {
  TriangleMesh a = testing::makeBox(1, 1, 1);
  const TriangleMesh b = testing::makeBox(1, 1, 1, Vec3(1, 1, 1), Vec3(3, 0, 0));
  const int off = static_cast<int>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  const std::string e = validationError(a);
  EXPECT_NE(e.find("2 connected components"), std::string::npos) << e;
}

TEST(CageValidation, OneFlippedTriangleIsNamed) {
  for (int flipped : {0, 5, 11}) {
    TriangleMesh c = testing::makeBox(1, 1, 1);
    std::swap(c.triangles[flipped][1], c.triangles[flipped][2]);
    const std::string e = validationError(c);
    EXPECT_NE(
        e.find("inconsistent orientation: triangle " + std::to_string(flipped) + " is flipped"),
        std::string::npos)
        << e;
  }
}

TEST(CageValidation, FullyInvertedCage) {
  TriangleMesh c = testing::makeIcosphere(1);
  for (auto& t : c.triangles) std::swap(t[1], t[2]);
  const std::string e = validationError(c);
  EXPECT_NE(e.find("inverted"), std::string::npos) << e;
}

TEST(CageValidation, ZeroAreaTriangle) {
  // The top face of a cube as a fan around a vertex placed exactly on one of its edges.
  TriangleMesh c = testing::makeBox(1, 1, 1);
  std::vector<std::array<int, 3>> tris;
  for (const auto& t : c.triangles) {
    if (!(c.vertices[t[0]].z() == 1 && c.vertices[t[1]].z() == 1 && c.vertices[t[2]].z() == 1))
      tris.push_back(t);
  }
  auto find = [&](const Vec3& p) {
    for (std::size_t i = 0; i < c.vertices.size(); ++i)
      if (c.vertices[i] == p) return static_cast<int>(i);
    return -1;
  };
  const int a = find({0, 0, 1}), b = find({1, 0, 1}), d = find({1, 1, 1}), e4 = find({0, 1, 1});
  c.vertices.emplace_back(0.5, 0, 1);
  const int m = static_cast<int>(c.vertices.size()) - 1;
  tris.push_back({m, b, d});
  tris.push_back({m, d, e4});
  tris.push_back({m, e4, a});
  const int bad = static_cast<int>(tris.size());
  tris.push_back({m, a, b});  // collinear
  c.triangles = tris;
  const std::string e = validationError(c);
  EXPECT_NE(e.find("triangle " + std::to_string(bad) + " "), std::string::npos) << e;
  EXPECT_NE(e.find("zero area"), std::string::npos) << e;
}

TEST(CageValidation, IndexOutOfRangeAndRepeatedIndex) {
  TriangleMesh c = testing::makeBox(1, 1, 1);
  c.triangles[3][1] = 99;
  std::string e = validationError(c);
  EXPECT_NE(e.find("triangle 3 has vertex index 99 out of range"), std::string::npos) << e;
  c = testing::makeBox(1, 1, 1);
  c.triangles[2][1] = c.triangles[2][0];
  e = validationError(c);
  EXPECT_NE(e.find("triangle 2 repeats a vertex"), std::string::npos) << e;
  c.triangles[2][1] = -1;
  e = validationError(c);
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
}

TEST(CageValidation, NaNCoordinate) {
  TriangleMesh c = testing::makeBox(1, 1, 1);
  c.vertices[6].y() = std::numeric_limits<double>::quiet_NaN();
  const std::string e = validationError(c);
  EXPECT_NE(e.find("vertex 6 has a non-finite coordinate"), std::string::npos) << e;
}

TEST(CageValidation, UnusedVertexAndTooSmall) {
  TriangleMesh c = testing::makeBox(1, 1, 1);
  c.vertices.emplace_back(0.5, 0.5, 0.5);
  std::string e = validationError(c);
  EXPECT_NE(e.find("vertex 8"), std::string::npos) << e;
  EXPECT_NE(e.find("not used"), std::string::npos) << e;
  TriangleMesh tiny;
  tiny.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tiny.triangles = {{0, 1, 2}, {0, 2, 1}};
  EXPECT_NE(validationError(tiny).find("at least 4"), std::string::npos);
}

}  // namespace
}  // namespace sb::mesh
