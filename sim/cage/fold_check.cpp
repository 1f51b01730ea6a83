#include "sim/cage/fold_check.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <stdexcept>
#include <string>

#include "sim/cage/interior_points.h"
#include "sim/mesh/closed_surface.h"

namespace sb::cage {

FoldProbes makeFoldProbes(const std::vector<Vec3>& samples, double step,
                          const std::function<Embedding(const std::vector<Vec3>&)>& bind) {
  if (!(step > 0.0 && std::isfinite(step)))
    throw std::invalid_argument("fold check: step must be positive and finite, got " +
                                std::to_string(step));
  if (samples.empty()) throw std::invalid_argument("fold check: no samples");
  std::vector<Vec3> points;
  points.reserve(4 * samples.size());
  for (const Vec3& x : samples) {
    points.push_back(x);
    for (int k = 0; k < 3; ++k) points.push_back(x + step * Vec3::Unit(k));
  }
  FoldProbes p;
  p.samples = samples;
  p.step = step;
  p.embedding = bind(points);
  if (p.embedding.meshVertexCount() != static_cast<int>(points.size()))
    throw std::invalid_argument("fold check: the bind returned " +
                                std::to_string(p.embedding.meshVertexCount()) + " rows for " +
                                std::to_string(points.size()) + " points");
  return p;
}

FoldSampling foldSamples(const mesh::TriangleMesh& cage, int target) {
  if (target < 8 || target > 100000)
    throw std::invalid_argument("fold check: sample target must be in [8, 100000], got " +
                                std::to_string(target));
  mesh::validateClosedSurface(cage, "the cage");
  // The enclosed volume, from the divergence theorem, sets the lattice spacing; the lattice
  // keeps only points half a spacing clear of the surface, so the count comes out lower than
  // volume / spacing³: the spacing shrinks until the target is met (at most a few rounds).
  double volume = 0.0;
  for (const auto& t : cage.triangles)
    volume += cage.vertices[size_t(t[0])].dot(
                  cage.vertices[size_t(t[1])].cross(cage.vertices[size_t(t[2])])) /
              6.0;
  double spacing = std::cbrt(std::abs(volume) / target);
  FoldSampling s;
  for (int round = 0; round < 8; ++round) {
    s.samples = interiorLattice(cage, spacing);
    if (static_cast<int>(s.samples.size()) >= target / 2) break;
    spacing *= 0.8;
  }
  s.step = 0.25 * spacing;
  return s;
}

FoldReport checkFolds(const FoldProbes& probes,
                      const Eigen::Matrix<double, Eigen::Dynamic, 3>& controls) {
  if (controls.rows() != probes.embedding.cageVertexCount())
    throw std::invalid_argument("fold check: " + std::to_string(controls.rows()) +
                                " control positions for an embedding of " +
                                std::to_string(probes.embedding.cageVertexCount()));
  Eigen::Matrix<double, Eigen::Dynamic, 3> moved;
  probes.embedding.deformDouble(controls, moved);
  FoldReport r;
  r.samples = static_cast<int>(probes.samples.size());
  r.minDeterminant = r.samples > 0 ? std::numeric_limits<double>::infinity() : 1.0;
  for (int i = 0; i < r.samples; ++i) {
    const Eigen::RowVector3d x = moved.row(4 * i);
    Mat3 J;
    for (int k = 0; k < 3; ++k) J.col(k) = (moved.row(4 * i + 1 + k) - x).transpose() / probes.step;
    const double det = J.determinant();
    if (!(det > 0.0)) ++r.folded;  // NaN (a non-finite control) counts as folded
    if (!(det >= r.minDeterminant)) {
      r.minDeterminant = det;
      r.worstSample = i;
    }
  }
  return r;
}

}  // namespace sb::cage
