// softbody ffd: free-form deformation of a mesh with a lattice (sim/cage/ffd_lattice.h). Writes
// the rest lattice for a DCC tool to move, deforms the mesh with the moved lattice, and says
// whether the map folds (the injectivity bound, and det J at the mesh's vertices).
#include <CLI/CLI.hpp>
#include <array>
#include <chrono>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "app/command_line.h"
#include "app/commands.h"
#include "sim/base/file_io.h"
#include "sim/cage/ffd_lattice.h"
#include "sim/mesh/mesh_io.h"

namespace sb::app {

namespace {

// The nodes as OBJ vertices (node order: x fastest, then y, then z) and the lattice's grid lines
// as OBJ line elements, so Blender and the like show (and keep) the lattice.
void writeLatticeObj(const std::string& path, const cage::FfdLattice& lattice,
                     const cage::FfdNodes& nodes) {
  writeFileAtomic(path, [&](std::ostream& out) {
    out.precision(17);
    out << "# softbody ffd lattice: " << lattice.nodes[0] << " x " << lattice.nodes[1] << " x "
        << lattice.nodes[2] << " nodes, x fastest\n";
    for (Eigen::Index n = 0; n < nodes.rows(); ++n)
      out << "v " << nodes(n, 0) << ' ' << nodes(n, 1) << ' ' << nodes(n, 2) << '\n';
    const auto& c = lattice.nodes;
    for (int k = 0; k < c[2]; ++k)
      for (int j = 0; j < c[1]; ++j)
        for (int i = 0; i < c[0]; ++i) {
          const int here = lattice.nodeIndex(i, j, k) + 1;  // OBJ counts from 1
          if (i + 1 < c[0])
            out << "l " << here << ' ' << lattice.nodeIndex(i + 1, j, k) + 1 << '\n';
          if (j + 1 < c[1])
            out << "l " << here << ' ' << lattice.nodeIndex(i, j + 1, k) + 1 << '\n';
          if (k + 1 < c[2])
            out << "l " << here << ' ' << lattice.nodeIndex(i, j, k + 1) + 1 << '\n';
        }
  });
}

}  // namespace

int runFfdCommand(int argc, char** argv) {
  CLI::App app{"Deform a mesh with a free-form deformation lattice", "ffd"};
  std::string meshPath, writeLattice, deformedPath, outPath, basisName = "bspline";
  std::vector<int> nodeList{4, 4, 4};
  double margin = 0.05;
  bool deBoor = false;
  app.add_option("--mesh", meshPath, "Mesh to deform (OBJ, OFF, PLY, STL)")->required();
  app.add_option("--nodes", nodeList,
                 "Nodes along x, y, z as L,M,N (B-spline ≥ 4, Bernstein 2..32)")
      ->delimiter(',')
      ->expected(3)
      ->check(CLI::Range(1, 1000));
  app.add_option("--basis", basisName, "bspline (local, cubic) or bernstein (global)")
      ->check(CLI::IsMember({"bspline", "bernstein"}));
  app.add_option("--margin", margin,
                 "The lattice's box: the mesh's bounding box grown by this share of its diagonal")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--write-lattice", writeLattice,
                 "Write the rest lattice (OBJ: nodes as vertices, x fastest, grid lines as "
                 "edges) to move in a DCC tool");
  app.add_option("--deformed-lattice", deformedPath,
                 "The same lattice, moved (same node count and order; made with the same "
                 "--mesh, --nodes, --basis and --margin)");
  app.add_option("--out", outPath, "Write the deformed mesh (OBJ; needs --deformed-lattice)");
  app.add_flag("--de-boor", deBoor,
               "Evaluate with de Boor's algorithm per vertex instead of the precomputed weights "
               "(the same result)");
  if (const int rc = parseArguments(app, argc, argv); rc >= 0) return rc;
  if (!outPath.empty() && deformedPath.empty()) {
    std::fprintf(stderr, "ffd: --out needs --deformed-lattice (the moved lattice)\n");
    return 2;
  }
  const std::array<int, 3> nodes{nodeList[0], nodeList[1], nodeList[2]};
  try {
    const mesh::TriangleMesh mesh = mesh::readMesh(meshPath);
    const cage::FfdBasis basis =
        basisName == "bernstein" ? cage::FfdBasis::Bernstein : cage::FfdBasis::BSpline;
    const cage::FfdLattice lattice = cage::ffdLatticeAround(mesh.vertices, nodes, basis, margin);
    const cage::FfdNodes rest = lattice.restNodes();
    const Eigen::Vector3d h = lattice.spacing();
    std::printf(
        "lattice:   %d x %d x %d %s nodes, box (%.6g, %.6g, %.6g) + (%.6g, %.6g, %.6g), "
        "spacing (%.6g, %.6g, %.6g)\n",
        nodes[0], nodes[1], nodes[2], basisName.c_str(), lattice.origin.x(), lattice.origin.y(),
        lattice.origin.z(), lattice.size.x(), lattice.size.y(), lattice.size.z(), h.x(), h.y(),
        h.z());
    if (!writeLattice.empty()) {
      writeLatticeObj(writeLattice, lattice, rest);
      std::printf("wrote:     %s (%d nodes)\n", writeLattice.c_str(), lattice.nodeCount());
    }
    if (deformedPath.empty()) return 0;

    const mesh::TriangleMesh moved = mesh::readMesh(deformedPath);
    if (int(moved.vertices.size()) != lattice.nodeCount()) {
      std::fprintf(stderr, "ffd: %s: has %zu vertices but the lattice has %d nodes\n",
                   deformedPath.c_str(), moved.vertices.size(), lattice.nodeCount());
      return 1;
    }
    cage::FfdNodes P(lattice.nodeCount(), 3);
    for (int n = 0; n < lattice.nodeCount(); ++n) P.row(n) = moved.vertices[size_t(n)].transpose();

    const auto t0 = std::chrono::steady_clock::now();
    Eigen::Matrix<double, Eigen::Dynamic, 3> out;
    if (deBoor) {
      cage::ffdDeformDeBoor(lattice, P, mesh.vertices, out);
    } else {
      const cage::Embedding e = cage::bindFfd(mesh.vertices, lattice);
      e.deformDouble(P, out);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("deformed:  %zu vertices in %.3f s (%s)\n", mesh.vertices.size(), seconds,
                deBoor ? "de Boor" : "precomputed weights");

    const cage::FfdInjectivityReport bound = cage::ffdInjectivityBound(lattice, P);
    if (bound.applicable) {
      const double worst = bound.maxDisplacementRatio.maxCoeff();
      std::printf(
          "one-to-one: %s (largest node displacement %.3g of a spacing; below %.2g "
          "guarantees it)\n",
          bound.guaranteedInjective ? "guaranteed" : "not guaranteed", worst, bound.bound);
    }
    const cage::FfdJacobianReport folds = cage::ffdJacobianCheck(lattice, P, mesh.vertices);
    if (folds.nonPositiveCount > 0)
      std::printf(
          "folds:     %lld of %lld vertices where the map folds (det J <= 0; min %.3g at "
          "(%.6g, %.6g, %.6g))\n",
          static_cast<long long>(folds.nonPositiveCount), static_cast<long long>(folds.samples),
          folds.minDeterminant, folds.argMin.x(), folds.argMin.y(), folds.argMin.z());
    else
      std::printf("folds:     none at the %lld vertices (min det J %.3g)\n",
                  static_cast<long long>(folds.samples), folds.minDeterminant);

    if (!outPath.empty()) {
      mesh::TriangleMesh result;
      result.triangles = mesh.triangles;
      result.vertices.resize(mesh.vertices.size());
      for (size_t i = 0; i < result.vertices.size(); ++i)
        result.vertices[i] = out.row(Eigen::Index(i)).transpose();
      mesh::writeObj(outPath, result);
      std::printf("wrote:     %s\n", outPath.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ffd: %s\n", e.what());
  }
  return 1;
}

}  // namespace sb::app
