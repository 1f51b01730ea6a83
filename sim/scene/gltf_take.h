// A take of the render meshes as one glTF 2.0 binary file (.glb), the interchange format every
// DCC tool, engine and web viewer reads.
//
// Each body is a node with its own mesh (named after the body): its triangles, the first frame as
// the vertex positions, and every later frame k as morph target k−1 (the displacement from the
// first frame). One animation ("softbody take") keys the morph weights: at frame k (time
// k · frameInterval from the take's start, s) weight k−1 is 1 and the others 0, interpolated
// linearly, so a player shows frame k exactly and blends neighbouring frames in between.
//
// Why morph targets: they carry the deformation exactly (to float round-off of the
// displacement) and every glTF reader supports them. They scale with frames × vertices, like a
// point cache (12 bytes per vertex per frame), and a naive player weighs every target at every
// vertex; for long takes of big meshes the PC2/MDD caches are the better route. Skinning to the
// cluster frames would be far smaller but cannot carry linear, quadratic or plastic deformation
// exactly. No normals are written: glTF readers compute them (the spec requires it).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sim/base/file_io.h"
#include "sim/base/types.h"
#include "sim/scene/scene.h"

namespace sb {

class GltfTakeWriter {
 public:
  // A take of `frameCount` ≥ 1 frames, frameInterval > 0 s apart, of the scene's bodies: body i
  // has vertexCounts[i] ≥ 1 render vertices (as SceneRunner::renderMeshes) and
  // Scene::renderTriangles(i) as faces. Throws std::invalid_argument on a bad layout (nothing is
  // created), FileError when the file cannot be created. The file appears at `path` only on
  // finish() (atomic, as sim/base/file_io.h); a writer destroyed before that removes it.
  GltfTakeWriter(const std::string& path, const Scene& scene, const std::vector<int>& vertexCounts,
                 int frameCount, double frameInterval);
  ~GltfTakeWriter();

  // The next frame: meshes[i] = body i's vertices (#V_i × 3, metres). std::invalid_argument
  // when the shapes differ from the layout, std::logic_error past the declared frame count.
  void addFrame(const std::vector<PointsRowMajor>& meshes);
  // Publishes the file; std::logic_error (nothing published) when frames are missing.
  void finish();

 private:
  struct Layout;
  static std::unique_ptr<Layout> makeLayout(const std::string& path, const Scene& scene,
                                            const std::vector<int>& vertexCounts, int frameCount,
                                            double frameInterval);
  std::unique_ptr<Layout> layout_;
  AtomicFileWriter file_;
};

}  // namespace sb
