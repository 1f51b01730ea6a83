// The softbody bind / deform / cage commands, run as a separate process (SOFTBODY_EXE).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "sim/cage/embedding.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/support/temp_dir_test.h"

namespace sb::cage {
using namespace sb::mesh;  // meshes, mesh files, surfaces
namespace {

namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;

struct ProcessResult {
  int code = -1;
  std::string out, err;
};

class Cli : public sb::test_support::TempDirTest {
 protected:
  ProcessResult run(const std::string& args) const {
    const std::string cmd = std::string("'") + SOFTBODY_EXE + "' " + args + " > '" +
                            path("stdout.txt") + "' 2> '" + path("stderr.txt") + "'";
    const int status = std::system(cmd.c_str());
    ProcessResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = contents(path("stdout.txt"));
    r.err = contents(path("stderr.txt"));
    return r;
  }
};

const std::string kMeshDir = SOFTBODY_TEST_MESH_DIR;

TEST_F(Cli, BindReportsStatistics) {
  const ProcessResult r = run("bind --mesh " + kMeshDir + "/bunny.obj --cage " + kMeshDir +
                              "/bunny_cage.obj --threads 2 --out " + path("w.sbw"));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"time:", "storage:", "nonzeros", "min ", "max ", "negative",
                          "sum error:", "linear precision:", "dense"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
  EXPECT_NE(r.err.find("binding: 1839 / 1839"), std::string::npos) << r.err;  // progress on stderr
  const Embedding e = Embedding::load(path("w.sbw"));
  EXPECT_EQ(e.meshVertexCount(), 1839);
  EXPECT_EQ(e.cageVertexCount(), 164);
  EXPECT_LT(e.stats().maxLinearError, 1e-10);
}

TEST_F(Cli, BindUsesTheCache) {
  const std::string args = "bind --mesh " + kMeshDir + "/suzanne.obj --cage " + kMeshDir +
                           "/suzanne_cage.obj --storage sparse --cache-dir " + path("");
  const ProcessResult a = run(args);
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_NE(a.out.find("sparse"), std::string::npos);
  EXPECT_NE(a.out.find("pruning:"), std::string::npos);
  const ProcessResult b = run(args);
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(b.out.find("cached"), std::string::npos) << b.out;
}

TEST_F(Cli, DeformAppliesTheCageMotion) {
  const TriangleMesh mesh = readMesh(kMeshDir + "/suzanne.obj");
  const TriangleMesh cage = readMesh(kMeshDir + "/suzanne_cage.obj");
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.9, 0.2, 0.0, -0.1, 1.1, 0.3, 0.05, 0.0, 0.8).finished();
  const Vec3 t(1.0, 2.0, -0.5);
  TriangleMesh moved = cage;
  for (auto& v : moved.vertices) v = A * v + t;
  writeObj(path("moved.obj"), moved);
  // Also a vertices-only copy of the mesh.
  TriangleMesh points;
  points.vertices = mesh.vertices;
  writeObj(path("points.obj"), points);
  for (const std::string& m : {kMeshDir + "/suzanne.obj", path("points.obj")}) {
    const ProcessResult r =
        run("deform --mesh " + m + " --cage " + kMeshDir + "/suzanne_cage.obj --deformed-cage " +
            path("moved.obj") + " --out " + path("out.obj"));
    ASSERT_EQ(r.code, 0) << r.err;
    const TriangleMesh out = readMesh(path("out.obj"));
    ASSERT_EQ(out.vertices.size(), mesh.vertices.size());
    EXPECT_EQ(out.triangles.size(), m == path("points.obj") ? 0u : mesh.triangles.size());
    double err = 0.0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      err = std::max(err, (out.vertices[i] - (A * mesh.vertices[i] + t)).norm());
    EXPECT_LT(err / testing::diagonal(moved), 1e-10);
  }
}

// A cage of planar quads (a frustum over a general quadrilateral) in an OBJ: bind reports its
// polygons, deform reproduces an affine cage motion, and the result does not depend on which
// corner each face starts at (the diagonal the reader's fan would pick). A polygon with a
// repeated corner is refused naming the file and line.
TEST_F(Cli, QuadCageBindsAndDeforms) {
  const Vec3 bottom[4] = {{0.0, 0.0, 0.0}, {2.2, 0.3, 0.0}, {1.9, 2.1, 0.0}, {-0.2, 1.7, 0.0}};
  const Vec3 apex(0.7, 1.1, 3.0);
  std::vector<Vec3> v(bottom, bottom + 4);
  for (const Vec3& b : bottom) v.push_back(apex + 0.45 * (b - apex));
  const std::vector<std::vector<int>> faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                               {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  auto writeCage = [&](const std::string& name, const std::vector<Vec3>& at, int rotate,
                       const std::string& extra) {
    std::ofstream f(path(name));
    f.precision(17);
    for (const Vec3& p : at) f << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const auto& face : faces) {
      f << "f";
      for (std::size_t c = 0; c < 4; ++c) f << " " << face[(c + std::size_t(rotate)) % 4] + 1;
      f << "\n";
    }
    f << extra;
  };
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.9, 0.2, 0.0, -0.1, 1.1, 0.3, 0.05, 0.0, 0.8).finished();
  const Vec3 t(1.0, 2.0, -0.5);
  std::vector<Vec3> movedAffine, movedBent;
  for (const Vec3& p : v) {
    movedAffine.push_back(A * p + t);
    movedBent.push_back(p + Vec3(0.3 * p.z() * p.z(), 0.0, 0.1 * p.x()));  // not affine
  }
  writeCage("cage.obj", v, 0, "");
  writeCage("cage_rotated.obj", v, 1, "");
  writeCage("affine.obj", movedAffine, 0, "");
  writeCage("bent.obj", movedBent, 0, "");
  writeCage("bent_rotated.obj", movedBent, 1, "");
  // The detailed mesh: points inside the frustum.
  TriangleMesh points;
  for (int i = 1; i < 4; ++i)
    for (int j = 1; j < 4; ++j)
      for (int k = 1; k < 4; ++k) {
        const Vec3 b =
            bottom[0] + 0.25 * i * (bottom[1] - bottom[0]) + 0.25 * j * (bottom[3] - bottom[0]);
        // Between the top (scale 0.45 towards the apex) and the bottom (scale 1).
        points.vertices.push_back(apex + 0.9 * (1.0 - 0.1375 * k) * (b - apex));
      }
  writeObj(path("points.obj"), points);

  const ProcessResult b = run("bind --mesh " + path("points.obj") + " --cage " + path("cage.obj") +
                              " --out " + path("w.sbw"));
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(b.out.find("polygon faces:      6 faces, polygon mean value coordinates"),
            std::string::npos)
      << b.out;
  EXPECT_LT(Embedding::load(path("w.sbw")).stats().maxLinearError, 1e-12);

  auto deform = [&](const std::string& cage, const std::string& moved) {
    const ProcessResult r = run("deform --mesh " + path("points.obj") + " --cage " + path(cage) +
                                " --deformed-cage " + path(moved) + " --out " + path("out.obj"));
    EXPECT_EQ(r.code, 0) << r.err;
    return readMesh(path("out.obj")).vertices;
  };
  const std::vector<Vec3> affine = deform("cage.obj", "affine.obj");
  ASSERT_EQ(affine.size(), points.vertices.size());
  for (std::size_t i = 0; i < affine.size(); ++i)
    EXPECT_LT((affine[i] - (A * points.vertices[i] + t)).norm(), 1e-10);
  const std::vector<Vec3> bent = deform("cage.obj", "bent.obj");
  const std::vector<Vec3> bentRotated = deform("cage_rotated.obj", "bent_rotated.obj");
  ASSERT_EQ(bent.size(), bentRotated.size());
  for (std::size_t i = 0; i < bent.size(); ++i) EXPECT_LT((bent[i] - bentRotated[i]).norm(), 1e-10);

  writeCage("broken.obj", v, 0, "f 1 2 3 2\n");
  const ProcessResult bad =
      run("bind --mesh " + path("points.obj") + " --cage " + path("broken.obj"));
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("broken.obj: line 15: a polygon repeats a corner: corners 2 and 4"),
            std::string::npos)
      << bad.err;
}

// --method: each method binds and deforms through the same commands; the weight file keeps
// the method; a bad method or option is refused with the allowed values.
TEST_F(Cli, MethodsBindAndDeform) {
  const TriangleMesh mesh = readMesh(kMeshDir + "/suzanne.obj");
  const TriangleMesh cage = readMesh(kMeshDir + "/suzanne_cage.obj");
  TriangleMesh moved = cage;
  for (auto& v : moved.vertices) v = 1.5 * v + Vec3(0, 1, 0);
  writeObj(path("moved.obj"), moved);
  const std::string pair =
      " --mesh " + kMeshDir + "/suzanne.obj --cage " + kMeshDir + "/suzanne_cage.obj";
  for (const std::string method : {"harmonic", "rbf", "green"}) {
    const ProcessResult b = run("bind" + pair + " --method " + method + " --resolution 16 --out " +
                                path(method + ".sbw"));
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_NE(b.out.find("method:             " + method), std::string::npos) << b.out;
    const Embedding e = Embedding::load(path(method + ".sbw"));
    EXPECT_EQ(std::string(embeddingKindName(e.kind())), method);
    const ProcessResult d =
        run("deform" + pair + " --method " + method + " --resolution 16 --deformed-cage " +
            path("moved.obj") + " --out " + path("out.obj"));
    ASSERT_EQ(d.code, 0) << d.err;
    const TriangleMesh out = readMesh(path("out.obj"));
    ASSERT_EQ(out.vertices.size(), mesh.vertices.size());
    // A similarity of the cage moves the mesh by it: exactly for rbf and green (whose deform
    // takes the cage's vertices and adds the face frames itself), to the grid's precision (the
    // weights' own linear error, scaled by 1.5) for harmonic.
    const double allowed = method != "harmonic"
                               ? 1e-9
                               : 1.5 * e.stats().maxLinearError * testing::diagonal(cage) + 1e-9;
    double err = 0.0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      err = std::max(err, (out.vertices[i] - (1.5 * mesh.vertices[i] + Vec3(0, 1, 0))).norm());
    EXPECT_LT(err, allowed) << method;
  }
  const ProcessResult bad = run("bind" + pair + " --method ffd");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--method"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("harmonic"), std::string::npos) << bad.err;
  const ProcessResult shape = run("bind" + pair + " --method rbf --shape 20");
  EXPECT_EQ(shape.code, 2);
  EXPECT_NE(shape.err.find("--shape"), std::string::npos) << shape.err;
}

// softbody run --fold-check: a body resting on the floor never folds, and the run says how
// many steps it checked; a scene without render meshes is refused.
TEST_F(Cli, RunChecksForFolds) {
  const std::string scene = std::string(SOFTBODY_TEST_MESH_DIR) + "/../scenes/default.json";
  const ProcessResult r = run("run " + scene + " --steps 40 --every 10 --fold-check --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("fold check: 0 of 4 checked steps had a fold"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("fold: step"), std::string::npos) << r.out;
  std::ofstream(path("bare.json"))
      << R"({"bodies": [{"mesh": ")" << kMeshDir << R"(/suzanne_cage.obj"}]})";
  const ProcessResult bare = run("run " + path("bare.json") + " --steps 1 --fold-check");
  EXPECT_EQ(bare.code, 1);
  EXPECT_NE(bare.err.find("no render meshes to check"), std::string::npos) << bare.err;
}

// softbody ffd: the written rest lattice (x fastest) moved by an affine map moves the mesh by
// it; a node pushed four spacings past its neighbours is reported as a fold at the vertices
// there; mismatched lattices and bad options are refused.
TEST_F(Cli, FfdWritesALatticeAndDeformsWithTheMovedOne) {
  const std::string mesh = kMeshDir + "/suzanne.obj";
  const std::string lattice = " --mesh " + mesh + " --nodes 5,5,5";
  const ProcessResult w = run("ffd" + lattice + " --write-lattice " + path("rest.obj"));
  ASSERT_EQ(w.code, 0) << w.err;
  const TriangleMesh rest = readMesh(path("rest.obj"));
  ASSERT_EQ(rest.vertices.size(), 125u);
  EXPECT_LT(rest.vertices[0].x(), rest.vertices[1].x());  // x fastest
  EXPECT_EQ(rest.vertices[0].y(), rest.vertices[1].y());
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 1.2, 0.1, 0.0, 0.0, 0.9, 0.0, 0.3, 0.0, 1.0).finished();
  const Vec3 t(1, 0, 0);
  TriangleMesh moved = rest;
  for (auto& v : moved.vertices) v = A * v + t;
  writeObj(path("moved.obj"), moved);
  for (const char* how : {"", " --de-boor"}) {
    const ProcessResult d = run("ffd" + lattice + " --deformed-lattice " + path("moved.obj") +
                                " --out " + path("out.obj") + how);
    ASSERT_EQ(d.code, 0) << d.err;
    EXPECT_NE(d.out.find("folds:     none"), std::string::npos) << d.out;
    const TriangleMesh original = readMesh(mesh), out = readMesh(path("out.obj"));
    ASSERT_EQ(out.vertices.size(), original.vertices.size());
    EXPECT_EQ(out.triangles, original.triangles);
    double err = 0.0;
    for (size_t i = 0; i < out.vertices.size(); ++i)
      err = std::max(err, (out.vertices[i] - (A * original.vertices[i] + t)).norm());
    EXPECT_LT(err, 1e-9) << how;
  }
  TriangleMesh pushed = rest;
  const double spacing = rest.vertices[1].x() - rest.vertices[0].x();
  pushed.vertices[62].x() += 4.0 * spacing;  // the centre node (2, 2, 2)
  writeObj(path("pushed.obj"), pushed);
  const ProcessResult f = run("ffd" + lattice + " --deformed-lattice " + path("pushed.obj"));
  ASSERT_EQ(f.code, 0) << f.err;
  EXPECT_NE(f.out.find("one-to-one: not guaranteed"), std::string::npos) << f.out;
  EXPECT_NE(f.out.find("vertices where the map folds"), std::string::npos) << f.out;

  const ProcessResult count =
      run("ffd --mesh " + mesh + " --nodes 4,5,5 --deformed-lattice " + path("moved.obj"));
  EXPECT_EQ(count.code, 1);
  EXPECT_NE(count.err.find("has 125 vertices but the lattice has 100 nodes"), std::string::npos)
      << count.err;
  const ProcessResult few = run("ffd --mesh " + mesh + " --nodes 3,5,5");
  EXPECT_EQ(few.code, 1);
  EXPECT_NE(few.err.find("at least 4 nodes per axis"), std::string::npos) << few.err;
  const ProcessResult two = run("ffd --mesh " + mesh + " --nodes 5,5");
  EXPECT_EQ(two.code, 2);
  const ProcessResult out = run("ffd" + lattice + " --out " + path("x.obj"));
  EXPECT_EQ(out.code, 2);
  EXPECT_NE(out.err.find("--out needs --deformed-lattice"), std::string::npos) << out.err;
  EXPECT_FALSE(fs::exists(path("x.obj")));
}

TEST_F(Cli, ErrorsAreClearAndNonZero) {
  const std::string mesh = kMeshDir + "/bunny.obj", cage = kMeshDir + "/bunny_cage.obj";
  // Missing file.
  ProcessResult r = run("bind --mesh " + path("nope.obj") + " --cage " + cage);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find(path("nope.obj")), std::string::npos) << r.err;
  // Flipped triangle in the cage.
  TriangleMesh c = readMesh(cage);
  std::swap(c.triangles[17][0], c.triangles[17][1]);
  writeObj(path("flipped.obj"), c);
  r = run("bind --mesh " + mesh + " --cage " + path("flipped.obj"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("triangle 17 is flipped"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("flipped.obj"), std::string::npos) << r.err;
  // Open cage in deform.
  TriangleMesh open = readMesh(cage);
  open.triangles.pop_back();
  writeObj(path("open.obj"), open);
  r = run("deform --mesh " + mesh + " --cage " + path("open.obj") + " --deformed-cage " +
          path("open.obj") + " --out " + path("o.obj"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("not closed"), std::string::npos) << r.err;
  // Mismatched deformed cage: vertex count, then faces.
  TriangleMesh fewer = readMesh(cage);
  fewer.vertices.pop_back();
  writeObj(path("fewer.obj"), fewer);
  r = run("deform --mesh " + mesh + " --cage " + cage + " --deformed-cage " + path("fewer.obj") +
          " --out " + path("o.obj"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("fewer.obj"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("163 vertices"), std::string::npos) << r.err;
  TriangleMesh refaced = readMesh(cage);
  std::rotate(refaced.triangles[5].begin(), refaced.triangles[5].begin() + 1,
              refaced.triangles[5].end());
  std::swap(refaced.triangles[5], refaced.triangles[6]);
  writeObj(path("refaced.obj"), refaced);
  r = run("deform --mesh " + mesh + " --cage " + cage + " --deformed-cage " + path("refaced.obj") +
          " --out " + path("o.obj"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("faces differ"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("o.obj")));
  // Bad arguments.
  r = run("bind --mesh " + mesh);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--cage"), std::string::npos) << r.err;
  r = run("bind --mesh " + mesh + " --cage " + cage + " --threads -3");
  EXPECT_EQ(r.code, 2);
  r = run("deform --mesh " + mesh + " --cage " + cage + " --deformed-cage " + cage + " --out " +
          path("x.obj") + " --storage weird");
  EXPECT_EQ(r.code, 2);
  // Unwritable output.
  r = run("deform --mesh " + mesh + " --cage " + cage + " --deformed-cage " + cage + " --out " +
          path("no/dir/x.obj"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no/dir/x.obj"), std::string::npos) << r.err;
  // Help.
  r = run("deform --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--deformed-cage"), std::string::npos);
}

TEST_F(Cli, CageWritesAClosedEnclosingCageAndReports) {
  const ProcessResult r = run("cage --mesh " + kMeshDir + "/suzanne.obj --out " + path("c.obj") +
                              " --vertices 120 --tightness 0.2 --threads 2");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"cage:", "hausdorff:", "% of the diagonal", "clearance:", "time:"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
  const TriangleMesh c = readMesh(path("c.obj"));
  EXPECT_NO_THROW(validateClosedSurface(c, "c.obj"));
  EXPECT_LE(c.vertices.size(), 120u);
}

TEST_F(Cli, CageBadInputIsNamedAndLeavesTheOutputUntouched) {
  write("out.obj", "keep");
  write("empty.obj", "# no vertices\n");
  write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  const std::string suzanne = kMeshDir + "/suzanne.obj";
  struct Case {
    std::string args, message;
  };
  for (const Case& c : {Case{"--mesh " + path("empty.obj"), path("empty.obj") + ": no vertices"},
                        Case{"--mesh " + path("nan.obj"), "nan.obj"},
                        Case{"--mesh " + path("missing.obj"), "missing.obj"},
                        Case{"--mesh " + suzanne + " --vertices 3", "vertexBudget: 3 is below 4"},
                        Case{"--mesh " + suzanne + " --tightness 2", "tightness: 2 is outside"}}) {
    const ProcessResult r = run("cage " + c.args + " --out " + path("out.obj"));
    EXPECT_EQ(r.code, 1) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(contents(path("out.obj")), "keep") << c.args;
  }
  const ProcessResult r =
      run("cage --mesh " + suzanne + " --vertices 60 --tightness 0 --out " + path("no/dir/c.obj"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no/dir/c.obj"), std::string::npos) << r.err;
  EXPECT_EQ(run("cage --mesh " + suzanne).code, 2);  // --out missing
}

}  // namespace
}  // namespace sb::cage
