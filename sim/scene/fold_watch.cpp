#include "sim/scene/fold_watch.h"

#include <Eigen/LU>
#include <algorithm>

namespace sb {
namespace {

// The cage of body b as it stands: its first cageVertexCount particles (interior particles,
// when there are any, come after them) and its faces, in double precision.
Eigen::Matrix<double, Eigen::Dynamic, 3> cagePositions(const Scene& scene, const SceneBody& b) {
  const ConstPointsRef x = scene.world.positions(b.handle);
  return x.topRows(b.cageVertexCount).cast<double>();
}

}  // namespace

FoldWatch::FoldWatch(const Scene& scene, int samplesPerBody, Pose pose)
    : samplesPerBody_(samplesPerBody), pose_(pose) {
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i) {
    Watched w;
    if (watch(scene, i, &w)) bodies_.push_back(std::move(w));
  }
}

bool FoldWatch::watch(const Scene& scene, int i, Watched* out) const {
  const SceneBody& b = scene.bodies[size_t(i)];
  if (!b.render) return false;
  Watched& w = *out;
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
    const cage::FoldSampling s = cage::foldSamples(box, samplesPerBody_);
    w.probes = cage::makeFoldProbes(s.samples, s.step, [&](const std::vector<Vec3>& points) {
      return cage::bindFfd(points, lattice);
    });
    return true;
  }
  mesh::TriangleMesh cage;
  const Eigen::Matrix<double, Eigen::Dynamic, 3> now =
      pose_ == Pose::Start
          ? Eigen::Matrix<double, Eigen::Dynamic, 3>(
                scene.world.restPositions(b.handle).topRows(b.cageVertexCount).cast<double>())
          : cagePositions(scene, b);
  for (Eigen::Index j = 0; j < now.rows(); ++j) cage.vertices.push_back(now.row(j).transpose());
  cage.triangles = b.cageTriangles;
  cage.polygonOf = b.cagePolygonOf;
  const cage::FoldSampling s = cage::foldSamples(cage, samplesPerBody_);
  w.probes = cage::makeFoldProbes(s.samples, s.step, [&](const std::vector<Vec3>& points) {
    return cage::bindToCage(points, cage, b.embedding);
  });
  return true;
}

void FoldWatch::rewatch(const Scene& scene, int body) {
  Watched w;
  const bool watched = watch(scene, body, &w);
  auto it = std::find_if(bodies_.begin(), bodies_.end(),
                         [&](const Watched& x) { return x.body == body; });
  if (!watched) {
    if (it != bodies_.end()) bodies_.erase(it);
  } else if (it != bodies_.end()) {
    *it = std::move(w);
  } else {
    // Kept in body order, as the constructor makes them.
    it = std::find_if(bodies_.begin(), bodies_.end(),
                      [&](const Watched& x) { return x.body > body; });
    bodies_.insert(it, std::move(w));
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

std::vector<FoldWatch::FoldedRegion> FoldWatch::foldedRegions(const Scene& scene) const {
  std::vector<FoldedRegion> out;
  for (const Watched& w : bodies_) {
    const Eigen::Matrix<double, Eigen::Dynamic, 3> controls =
        cagePositions(scene, scene.bodies[size_t(w.body)]);
    FoldedRegion region;
    region.body = w.body;
    region.report = cage::checkFolds(w.probes, controls);
    if (region.report.folded == 0) continue;
    // det J per sample as checkFolds computes it (the same rows, the same test), keeping the
    // folded samples' moved positions.
    Eigen::Matrix<double, Eigen::Dynamic, 3> moved;
    w.probes.embedding.deformDouble(controls, moved);
    const double h = w.probes.step;
    for (std::size_t i = 0; i < w.probes.samples.size(); ++i) {
      const Eigen::Index r = 4 * static_cast<Eigen::Index>(i);
      const Vec3 x = moved.row(r).transpose();
      Mat3 J;
      for (int k = 0; k < 3; ++k) J.col(k) = (moved.row(r + 1 + k).transpose() - x) / h;
      if (!(J.determinant() > 0.0)) region.points.push_back(x);
    }
    // foldSamples' difference step is a quarter of the lattice spacing; a lattice body's samples
    // are in its mesh file's units, which the body's scale turns into metres.
    const SceneBody& b = scene.bodies[size_t(w.body)];
    region.spacing = 4.0 * h * (b.latticeFrame ? b.scale : 1.0);
    out.push_back(std::move(region));
  }
  return out;
}

}  // namespace sb
