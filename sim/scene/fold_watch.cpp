#include "sim/scene/fold_watch.h"

namespace sb {
namespace {

// The cage of body b as it stands: its first cageVertexCount particles (interior particles,
// when there are any, come after them) and its faces, in double precision.
Eigen::Matrix<double, Eigen::Dynamic, 3> cagePositions(const Scene& scene, const SceneBody& b) {
  const ConstPointsRef x = scene.world.positions(b.handle);
  return x.topRows(b.cageVertexCount).cast<double>();
}

}  // namespace

FoldWatch::FoldWatch(const Scene& scene, int samplesPerBody) {
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i) {
    const SceneBody& b = scene.bodies[size_t(i)];
    if (!b.render) continue;
    Watched w;
    w.body = i;
    if (b.latticeFrame) {
      // A lattice body: samples inside the lattice's box, bound with its own weights in the
      // render mesh file's coordinates (they hold for any placement of the nodes).
      const cage::FfdLattice& lattice = *b.latticeFrame;
      mesh::TriangleMesh box;
      for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
          for (int c = 0; c < 2; ++c)
            box.vertices.push_back(lattice.origin + Vec3(c, j, k).cwiseProduct(lattice.size));
      box.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                       {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
      const cage::FoldSampling s = cage::foldSamples(box, samplesPerBody);
      w.probes = cage::makeFoldProbes(s.samples, s.step, [&](const std::vector<Vec3>& points) {
        return cage::bindFfd(points, lattice);
      });
      bodies_.push_back(std::move(w));
      continue;
    }
    mesh::TriangleMesh cage;
    const Eigen::Matrix<double, Eigen::Dynamic, 3> now = cagePositions(scene, b);
    for (Eigen::Index j = 0; j < now.rows(); ++j) cage.vertices.push_back(now.row(j).transpose());
    cage.triangles = b.cageTriangles;
    const cage::FoldSampling s = cage::foldSamples(cage, samplesPerBody);
    w.probes = cage::makeFoldProbes(s.samples, s.step, [&](const std::vector<Vec3>& points) {
      return cage::bindToCage(points, cage, b.embedding);
    });
    bodies_.push_back(std::move(w));
  }
}

std::vector<FoldWatch::BodyFolds> FoldWatch::folded(const Scene& scene) const {
  std::vector<BodyFolds> out;
  for (const Watched& w : bodies_) {
    const cage::FoldReport r =
        cage::checkFolds(w.probes, cagePositions(scene, scene.bodies[size_t(w.body)]));
    if (r.folded > 0) out.push_back({w.body, r});
  }
  return out;
}

}  // namespace sb
