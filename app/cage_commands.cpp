// softbody bind / softbody deform / softbody cage: bind a mesh to a cage (mean value, harmonic or
// RBF coordinates: sim/cage/bind.h), report the weight statistics, write a mesh deformed by a moved
// cage, and make an automatic cage for any mesh.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/command_line.h"
#include "app/commands.h"
#include "sim/base/parallel.h"
#include "sim/cage/auto_cage.h"
#include "sim/cage/bind.h"
#include "sim/cage/embedding.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::app {

namespace {

using cage::BindOptions;
using cage::Embedding;
using mesh::TriangleMesh;

BindOptions makeOptions(const std::string& cacheDir, int threads, const std::string& storage,
                        double prune, bool progress) {
  BindOptions o;
  o.cacheDir = cacheDir;
  if (threads > 0) setThreadCount(threads);  // the pool the bind runs on (sim/base/parallel.h)
  o.threads = threads;
  o.pruneThreshold = prune;
  if (storage == "dense")
    o.storage = cage::WeightStorage::Dense;
  else if (storage == "sparse")
    o.storage = cage::WeightStorage::Sparse;
  else
    o.storage = cage::WeightStorage::Auto;
  o.warning = [](const std::string& m) { std::fprintf(stderr, "warning: %s\n", m.c_str()); };
  if (progress) {
    auto last =
        std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
    o.progress = [last](std::size_t done, std::size_t total) {
      const auto now = std::chrono::steady_clock::now();
      if (done == total || now - *last > std::chrono::milliseconds(500)) {
        *last = now;
        std::fprintf(stderr, "\rbinding: %zu / %zu points (%.0f%%)%s", done, total,
                     total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0,
                     done == total ? "\n" : "");
        std::fflush(stderr);
      }
    };
  }
  return o;
}

// --method and its options, shared by bind and deform.
struct MethodArgs {
  std::string method = "mvc";
  int resolution = cage::HarmonicOptions{}.resolution;
  double shape = cage::RbfOptions{}.shape;

  cage::EmbeddingMethod toMethod() const {
    cage::EmbeddingMethod m;
    cage::parseEmbeddingKind(method, &m.kind);  // checked by IsMember below
    m.harmonic.resolution = resolution;
    m.rbf.shape = shape;
    return m;
  }
};

void addCommonOptions(CLI::App& app, std::string& cacheDir, int& threads, std::string& storage,
                      double& prune, MethodArgs& method) {
  app.add_option("--method", method.method,
                 "Coordinates: mvc (mean value), harmonic (Laplace solve on a grid), rbf "
                 "(multiquadric, handles at the cage vertices) or green (Green coordinates: "
                 "shape-preserving; the mesh must lie inside the cage)")
      ->check(CLI::IsMember({"mvc", "harmonic", "rbf", "green"}));
  app.add_option("--resolution", method.resolution,
                 "harmonic: grid cells along the cage's longest side")
      ->check(CLI::Range(4, 64));
  app.add_option("--shape", method.shape,
                 "rbf: multiquadric shape s / mean nearest-handle distance")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--cache-dir", cacheDir,
                 "Directory for cached binds (reused when mesh, cage and options match)");
  app.add_option("--threads", threads, "Threads for the bind (0 = all cores)")
      ->check(CLI::Range(0, 1024));
  app.add_option("--storage", storage, "Weight storage: auto, dense or sparse")
      ->check(CLI::IsMember({"auto", "dense", "sparse"}));
  app.add_option("--prune", prune,
                 "Sparse pruning: fraction of each row's absolute weight mass that may be dropped")
      ->check(CLI::Range(0.0, 0.5));
}

}  // namespace

int runBindCommand(int argc, char** argv) {
  CLI::App app{"Bind a mesh to a cage and report weight statistics", "bind"};
  std::string meshPath, cagePath, outPath, cacheDir, storage = "auto";
  int threads = 0;
  double prune = BindOptions{}.pruneThreshold;
  app.add_option("--mesh", meshPath, "Mesh whose vertices are bound (OBJ, OFF, PLY, STL)")
      ->required();
  app.add_option("--cage", cagePath, "Closed, outward-oriented cage mesh")->required();
  app.add_option("--out", outPath,
                 "Write the weight matrix (binary .sbw file, see sim/cage/README.md)");
  MethodArgs method;
  addCommonOptions(app, cacheDir, threads, storage, prune, method);
  if (const int rc = parseArguments(app, argc, argv); rc >= 0) return rc;

  try {
    const TriangleMesh mesh = mesh::readMesh(meshPath);
    const TriangleMesh cageMesh = mesh::readMesh(cagePath);
    try {
      mesh::validateClosedSurface(cageMesh, cagePath);
    } catch (const mesh::SurfaceError& e) {
      std::fprintf(stderr, "bind: %s\n", e.what());
      return 1;
    }
    const BindOptions options = makeOptions(cacheDir, threads, storage, prune, true);
    const Embedding emb = cage::bindToCage(mesh.vertices, cageMesh, method.toMethod(), options);
    const cage::BindStats& s = emb.stats();
    std::printf("method:             %s\n", cage::embeddingKindName(emb.kind()));
    std::printf("mesh:               %s (%d vertices)\n", meshPath.c_str(), emb.meshVertexCount());
    std::printf("cage:               %s (%d vertices, %zu triangles)\n", cagePath.c_str(),
                emb.cageVertexCount(), cageMesh.triangles.size());
    if (emb.kind() == cage::EmbeddingKind::Green)
      std::printf("controls:           %d (a weight per cage vertex and per face normal)\n",
                  emb.weightColumns());
    if (mesh::hasPolygonFaces(cageMesh))
      std::printf("polygon faces:      %zu faces, %s\n", mesh::polygonFaces(cageMesh).size(),
                  emb.kind() == cage::EmbeddingKind::MeanValue
                      ? "polygon mean value coordinates (no diagonal dependence)"
                      : "bound over the reader's fan triangles");
    if (s.fromCache)
      std::printf("time:               cached (%s)\n", cacheDir.c_str());
    else
      std::printf("time:               %.3f s on %d thread(s)\n", s.seconds, s.threads);
    std::printf(
        "storage:            %s, %lld nonzeros (%.1f%%)\n", emb.isSparse() ? "sparse" : "dense",
        static_cast<long long>(emb.nonZeros()),
        100.0 * static_cast<double>(emb.nonZeros()) /
            std::max(1.0, static_cast<double>(emb.meshVertexCount()) * emb.weightColumns()));
    std::printf("weights:            min %.6g, max %.6g, %lld negative\n", s.minWeight, s.maxWeight,
                static_cast<long long>(s.negativeCount));
    std::printf("sum error:          %.3g (max |sum w - 1|)\n", s.maxSumError);
    std::printf("linear precision:   %.3g (max |sum w v - x| / cage diagonal)\n", s.maxLinearError);
    if (emb.isSparse())
      std::printf("pruning:            rest-pose error %.3g, max row L1 change %.3g\n",
                  s.pruningError, s.maxPrunedL1);
    if (emb.kind() == cage::EmbeddingKind::MeanValue)
      std::printf(
          "conditioning:       %.3g (worst cancellation factor), %lld points beyond 4x cage size, "
          "%lld on the cage\n",
          s.worstConditioning, static_cast<long long>(s.farPoints),
          static_cast<long long>(s.onCagePoints));
    if (!outPath.empty()) {
      emb.save(outPath);
      std::printf("wrote:              %s\n", outPath.c_str());
    }
    return 0;
  } catch (const mesh::MeshError& e) {
    std::fprintf(stderr, "bind: %s\n", e.what());
  } catch (const mesh::SurfaceError& e) {
    std::fprintf(stderr, "bind: %s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bind: %s\n", e.what());
  }
  return 1;
}

int runDeformCommand(int argc, char** argv) {
  CLI::App app{"Deform a mesh by moving its cage (vertices correspond by index)", "deform"};
  std::string meshPath, cagePath, deformedPath, outPath, cacheDir, storage = "auto";
  int threads = 0;
  double prune = BindOptions{}.pruneThreshold;
  app.add_option("--mesh", meshPath, "Mesh to deform (faces optional)")->required();
  app.add_option("--cage", cagePath, "Cage in the rest pose")->required();
  app.add_option("--deformed-cage", deformedPath,
                 "The same cage, moved (same vertex count and faces)")
      ->required();
  app.add_option("--out", outPath, "Output OBJ")->required();
  MethodArgs method;
  addCommonOptions(app, cacheDir, threads, storage, prune, method);
  if (const int rc = parseArguments(app, argc, argv); rc >= 0) return rc;

  try {
    const TriangleMesh mesh = mesh::readMesh(meshPath);
    const TriangleMesh rest = mesh::readMesh(cagePath);
    const TriangleMesh moved = mesh::readMesh(deformedPath);
    if (moved.vertices.size() != rest.vertices.size()) {
      std::fprintf(stderr, "deform: %s: has %zu vertices but the cage %s has %zu\n",
                   deformedPath.c_str(), moved.vertices.size(), cagePath.c_str(),
                   rest.vertices.size());
      return 1;
    }
    if (moved.triangles != rest.triangles) {
      std::size_t first = 0;
      while (first < moved.triangles.size() && first < rest.triangles.size() &&
             moved.triangles[first] == rest.triangles[first])
        ++first;
      std::fprintf(stderr,
                   "deform: %s: faces differ from the cage %s (first difference at face %zu)\n",
                   deformedPath.c_str(), cagePath.c_str(), first);
      return 1;
    }
    try {
      mesh::validateClosedSurface(rest, cagePath);
    } catch (const mesh::SurfaceError& e) {
      std::fprintf(stderr, "deform: %s\n", e.what());
      return 1;
    }
    const BindOptions options =
        makeOptions(cacheDir, threads, storage, prune, mesh.vertices.size() > 20000);
    const Embedding emb = cage::bindToCage(mesh.vertices, rest, method.toMethod(), options);
    PointsRowMajor cagePos(static_cast<Eigen::Index>(moved.vertices.size()), 3);
    Eigen::Matrix<double, Eigen::Dynamic, 3> cageD(static_cast<Eigen::Index>(moved.vertices.size()),
                                                   3);
    for (std::size_t j = 0; j < moved.vertices.size(); ++j)
      cageD.row(static_cast<Eigen::Index>(j)) = moved.vertices[j].transpose();
    Eigen::Matrix<double, Eigen::Dynamic, 3> outD;
    emb.deformDouble(cageD, outD);  // double precision for the file; the per-frame path is float
    TriangleMesh out;
    out.triangles = mesh.triangles;
    out.polygonOf = mesh.polygonOf;  // a quad mesh is written back with quads
    out.vertices.resize(mesh.vertices.size());
    for (std::size_t i = 0; i < out.vertices.size(); ++i)
      out.vertices[i] = outD.row(static_cast<Eigen::Index>(i)).transpose();
    mesh::writeObj(outPath, out);
    std::printf("wrote %s (%zu vertices, %zu triangles)\n", outPath.c_str(), out.vertices.size(),
                out.triangles.size());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "deform: %s\n", e.what());
  }
  return 1;
}

int runCageCommand(int argc, char** argv) {
  CLI::App app{"Make a closed cage that strictly encloses a mesh, within a vertex budget", "cage"};
  std::string meshPath, outPath;
  cage::CageOptions options;
  app.add_option("--mesh", meshPath,
                 "Mesh to enclose (OBJ, OFF, PLY, STL; soups, holes and pieces are fine)")
      ->required();
  app.add_option("--out", outPath, "Output cage (OBJ; replaced only on success)")->required();
  app.add_option("--vertices", options.vertexBudget, "Most cage vertices (at least 4)");
  app.add_option("--tightness", options.tightness,
                 "0 (fast, loose) to 1 (tight, slower): the voxel resolution of the first surface");
  app.add_option("--threads", options.threads, "Threads for the final checks (0 = all cores)");
  if (const int rc = parseArguments(app, argc, argv); rc >= 0) return rc;

  try {
    const TriangleMesh mesh = mesh::readMesh(meshPath);
    if (options.threads > 0) setThreadCount(options.threads);
    const cage::CageResult result = cage::makeCage(mesh, options);
    mesh::writeObj(outPath, result.cage);
    const cage::CageReport& r = result.report;
    std::printf("mesh:               %s (%zu vertices, %zu triangles)\n", meshPath.c_str(),
                mesh.vertices.size(), mesh.triangles.size());
    std::printf("cage:               %s (%d vertices, %d triangles; budget %d)\n", outPath.c_str(),
                r.vertices, r.triangles, options.vertexBudget);
    std::printf("hausdorff:          %.6g (%.2f%% of the diagonal %.6g), cage to mesh\n",
                r.hausdorff, 100.0 * r.hausdorffRelative, r.diagonal);
    std::printf("clearance:          >= %.6g (every guard point inside, %d guard points)\n",
                r.minClearance, r.guardPoints);
    std::printf("voxels:             %d along the longest side, %d vertices before decimation\n",
                r.voxelResolution, r.fineVertices);
    std::printf("time:               %.3f s\n", r.seconds);
    if (r.vertices > options.vertexBudget)
      std::fprintf(stderr,
                   "cage: warning: %d vertices, over the budget of %d (the fewest the "
                   "enclosure allows from the coarsest voxels)\n",
                   r.vertices, options.vertexBudget);
    return 0;
  } catch (const std::invalid_argument& e) {
    // makeCage names the field: "mesh: ..." is the input file, the others are options.
    std::string message = e.what();
    if (message.rfind("mesh:", 0) == 0) message = meshPath + message.substr(4);
    std::fprintf(stderr, "cage: %s\n", message.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cage: %s\n", e.what());
  }
  return 1;
}

}  // namespace sb::app
