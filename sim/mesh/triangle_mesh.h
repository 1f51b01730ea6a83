// A plain indexed triangle mesh in double precision: the exchange type of the cage module.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

namespace sb::mesh {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
};

}  // namespace sb::mesh
