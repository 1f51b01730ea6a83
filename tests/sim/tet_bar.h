// A bar of grid points split into tetrahedral four-particle clusters: the small-cluster set-up
// shared by the simulation tests and benchmarks.
#pragma once

#include "sim/world/body_def.h"

namespace sb::test {

// nx × ny × nz points `spacing` (m) apart, x fastest; explicit clusters: five tetrahedra per grid
// cube; the four corner points at x = 0 pinned. Parameters are left at their defaults.
inline BodyDef tetBar(int nx, int ny, int nz, double spacing) {
  BodyDef def;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) def.positions.push_back(spacing * Vec3(i, j, k));
  auto id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  def.clusters.kind = ClusterDef::Kind::Explicit;
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        const int c[8] = {id(i, j, k),         id(i + 1, j, k),        id(i, j + 1, k),
                          id(i + 1, j + 1, k), id(i, j, k + 1),        id(i + 1, j, k + 1),
                          id(i, j + 1, k + 1), id(i + 1, j + 1, k + 1)};
        def.clusters.clusters.push_back({c[0], c[1], c[2], c[4]});
        def.clusters.clusters.push_back({c[1], c[3], c[2], c[7]});
        def.clusters.clusters.push_back({c[1], c[4], c[5], c[7]});
        def.clusters.clusters.push_back({c[2], c[4], c[7], c[6]});
        def.clusters.clusters.push_back({c[1], c[2], c[4], c[7]});
      }
  def.pinned = {id(0, 0, 0), id(0, ny - 1, 0), id(0, 0, nz - 1), id(0, ny - 1, nz - 1)};
  return def;
}

}  // namespace sb::test
