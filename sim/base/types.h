// Basic math types shared by every part of the simulation library (base of the dependency
// graph: nothing here includes anything of sim/ but this folder).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

namespace sb {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec3f = Eigen::Vector3f;

// Positions of a set of points, one row per point, columns x, y, z (#P×3, metres). Column-major
// storage with an outer stride, so a body's rows inside the World's per-body particle arrays
// (BodyState::x, column-major #P×3) can be viewed without copying.
using ConstPointsRef =
    Eigen::Ref<const Eigen::Matrix<float, Eigen::Dynamic, 3>, 0, Eigen::OuterStride<>>;

// Interleaved xyz rows (#P×3, row-major): the layout vertex buffers and OBJ files use.
using PointsRowMajor = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Whether a value read as a double can be stored as a float (positions are single precision):
// finite and |v| ≤ the largest float. A larger finite double would become infinity.
inline bool fitsFloat(double v) {
  return std::isfinite(v) && std::abs(v) <= double(std::numeric_limits<float>::max());
}

}  // namespace sb
