// Shared by the cage tests: the shipped bunny and its cage (read once), and point lists as
// #P×3 matrices.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim/mesh/mesh_io.h"

namespace sb::cage::test_data {

inline Eigen::Matrix<double, Eigen::Dynamic, 3> toMatrix(const std::vector<Eigen::Vector3d>& v) {
  Eigen::Matrix<double, Eigen::Dynamic, 3> m(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.row(Eigen::Index(i)) = v[i].transpose();
  return m;
}

inline const mesh::TriangleMesh& bunnyCage() {
  static const mesh::TriangleMesh c =
      mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny_cage.obj");
  return c;
}

inline const mesh::TriangleMesh& bunny() {
  static const mesh::TriangleMesh c =
      mesh::readMesh(std::string(SOFTBODY_TEST_MESH_DIR) + "/bunny.obj");
  return c;
}

}  // namespace sb::cage::test_data
