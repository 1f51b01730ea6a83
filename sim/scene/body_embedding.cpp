#include "sim/scene/body_embedding.h"

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "sim/mesh/mesh_io.h"

namespace sb {

void rebindRenderMesh(Scene& scene, int body, const cage::EmbeddingMethod& method,
                      const cage::BindOptions& options) {
  if (body < 0 || body >= static_cast<int>(scene.bodies.size()))
    throw std::out_of_range("rebind: no body " + std::to_string(body) + " (the scene has " +
                            std::to_string(scene.bodies.size()) + ")");
  SceneBody& b = scene.bodies[static_cast<std::size_t>(body)];
  const std::string name = scene.world.name(b.handle);
  if (!b.render)
    throw std::invalid_argument(name + ": has no render mesh to bind (it draws its particles)");
  if (b.latticeFrame)
    throw std::invalid_argument(name +
                                ": is a lattice body: its render mesh follows the lattice's "
                                "nodes, not a cage");

  // Options a scene file would refuse are refused here too (checked before the costly bind).
  if (method.kind == cage::EmbeddingKind::Harmonic &&
      (method.harmonic.resolution < kSceneHarmonicResolutionMin ||
       method.harmonic.resolution > kSceneHarmonicResolutionMax))
    throw std::invalid_argument(name + ": harmonic resolution must be in [" +
                                std::to_string(kSceneHarmonicResolutionMin) + ", " +
                                std::to_string(kSceneHarmonicResolutionMax) + "], got " +
                                std::to_string(method.harmonic.resolution));
  if (method.kind == cage::EmbeddingKind::Rbf &&
      !(method.rbf.shape >= kSceneRbfShapeMin && method.rbf.shape <= kSceneRbfShapeMax)) {
    char text[96];
    std::snprintf(text, sizeof text, ": RBF shape must be in [%g, %g], got %g", kSceneRbfShapeMin,
                  kSceneRbfShapeMax, method.rbf.shape);
    throw std::invalid_argument(name + text);
  }

  // Bound in the mesh file's coordinates, as a scene load binds: harmonic coordinates are not
  // invariant under rotation (their grid is aligned with the axes), so binding the placed mesh
  // would give other weights than the saved scene gets when it is opened again. The cage is the
  // body's start positions taken back through the placement (the cage file is not read again:
  // an automatic cage has none), exact to float rounding of the start positions.
  const mesh::TriangleMesh file =
      mesh::readMesh(resolveScenePath(scene.meshFolder, b.render->path));
  const Mat3 Rt = eulerDegrees(b.rotationDegrees).transpose();
  const ConstPointsRef start = scene.world.restPositions(b.handle);
  mesh::TriangleMesh cage;
  cage.vertices.reserve(static_cast<std::size_t>(b.cageVertexCount));
  for (int i = 0; i < b.cageVertexCount; ++i)
    cage.vertices.push_back(Rt * (start.row(i).transpose().cast<double>() - b.translation) /
                            b.scale);
  cage.triangles = b.cageTriangles;
  cage.polygonOf = b.cagePolygonOf;
  const std::vector<Vec3>& points = file.vertices;

  // Bind completely first; only a finished bind replaces the old one (nothing half-switched).
  auto render = std::make_shared<RenderMesh>();
  render->path = b.render->path;
  render->triangles = b.render->triangles;
  render->embedding =
      std::make_shared<const cage::Embedding>(cage::bindToCage(points, cage, method, options));
  if (render->embedding->meshVertexCount() !=
      static_cast<int>(b.render->embedding->meshVertexCount()))
    throw std::runtime_error(name + ": the render mesh file '" + b.render->path + "' now has " +
                             std::to_string(render->embedding->meshVertexCount()) +
                             " vertices, the scene loaded " +
                             std::to_string(b.render->embedding->meshVertexCount()));
  prepareRigidFollow(*render, points, cage.vertices);
  // The swap: both fields at once, neither can throw.
  b.render = std::move(render);
  b.embedding = method;
}

bool sameEmbeddingMethod(const cage::EmbeddingMethod& a, const cage::EmbeddingMethod& b) {
  if (a.kind != b.kind) return false;
  if (a.kind == cage::EmbeddingKind::Harmonic)
    return a.harmonic.resolution == b.harmonic.resolution;
  if (a.kind == cage::EmbeddingKind::Rbf) return a.rbf.shape == b.rbf.shape;
  return true;
}

}  // namespace sb
