#include "sim/mesh/normals.h"

#include <cmath>

#include <Eigen/Geometry>

namespace sb::mesh {

void computeVertexNormals(const std::vector<std::array<int, 3>>& triangles,
                          const PointsRowMajor& positions, PointsRowMajor& normals) {
  const Eigen::Index n = positions.rows();
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> acc =
      Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>::Zero(n, 3);
  for (const auto& t : triangles) {
    if (t[0] < 0 || t[1] < 0 || t[2] < 0 || t[0] >= n || t[1] >= n || t[2] >= n) continue;
    const Eigen::Vector3d a = positions.row(t[0]).transpose().cast<double>();
    const Eigen::Vector3d b = positions.row(t[1]).transpose().cast<double>();
    const Eigen::Vector3d c = positions.row(t[2]).transpose().cast<double>();
    const Eigen::RowVector3d cr = (b - a).cross(c - a).transpose();  // 2·area·unit normal
    acc.row(t[0]) += cr;
    acc.row(t[1]) += cr;
    acc.row(t[2]) += cr;
  }
  normals.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double len = acc.row(i).norm();
    if (len > 0.0 && std::isfinite(len)) {
      normals.row(i) = (acc.row(i) / len).cast<float>();
    } else {
      normals.row(i).setZero();
    }
  }
}

}  // namespace sb::mesh
