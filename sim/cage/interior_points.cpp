#include "sim/cage/interior_points.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "sim/cage/auto_cage_geometry.h"

namespace sb::cage {

namespace {
std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}
}  // namespace

std::vector<Eigen::Vector3d> interiorLattice(const mesh::TriangleMesh& cage, double spacing) {
  using Vec = Eigen::Vector3d;
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw std::invalid_argument("spacing: must be positive and finite, got " + number(spacing));
  std::vector<Vec> out;
  if (cage.vertices.empty() || cage.triangles.empty()) return out;
  Vec lo = cage.vertices.front(), hi = lo;
  for (const Vec& v : cage.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  // Lattice points k·spacing from the box centre, k in [−n, n] per axis.
  const Vec centre = 0.5 * (lo + hi);
  Eigen::Vector3i n;
  double count = 1.0;
  for (int a = 0; a < 3; ++a) {
    n[a] = static_cast<int>(std::min(1e7, std::floor(0.5 * (hi[a] - lo[a]) / spacing)));
    count *= 2.0 * n[a] + 1.0;
  }
  if (count > double(kMaxInteriorPoints))
    throw std::invalid_argument("spacing: " + number(spacing) + " would put " +
                                std::to_string(static_cast<long long>(count)) +
                                " lattice points in the cage's box (at most " +
                                std::to_string(kMaxInteriorPoints) + ")");
  const auto& V = cage.vertices;
  for (int k = -n[2]; k <= n[2]; ++k)
    for (int j = -n[1]; j <= n[1]; ++j)
      for (int i = -n[0]; i <= n[0]; ++i) {
        const Vec p = centre + spacing * Vec(i, j, k);
        double angles = 0.0, nearest = INFINITY;
        for (const auto& t : cage.triangles) {
          const Vec &a = V[size_t(t[0])], &b = V[size_t(t[1])], &c = V[size_t(t[2])];
          angles += detail::solidAngle(p, a, b, c);
          nearest = std::min(nearest, detail::pointTriangleDistance(p, a, b, c));
        }
        if (angles > 2.0 * M_PI && nearest >= 0.5 * spacing) out.push_back(p);
      }
  return out;
}

}  // namespace sb::cage
