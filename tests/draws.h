// Random test inputs that are the same whichever compiler builds the tests.
//
// The arguments of one call are evaluated in an unspecified order, and the two compilers differ:
// GCC evaluates them right to left, clang left to right. So Vec3(u(rng), u(rng), u(rng)) gives
// (x, y, z) = (3rd, 2nd, 1st draw) in a GCC build and (1st, 2nd, 3rd) in a clang build: every
// test built that way ran on other inputs under clang (other clusters, other start states, a
// different golden state hash). These helpers sequence the draws. They keep GCC's order — the
// last component is drawn first — so the inputs, and everything computed from them, are exactly
// what the GCC builds always used.
#pragma once

#include <Eigen/Geometry>

namespace sb::test {

// A fixed-size vector of draw() values, the last component drawn first.
template <class Vector, class Draw>
Vector drawVector(Draw&& draw) {
  Vector v;
  for (int i = int(v.size()) - 1; i >= 0; --i) v[i] = static_cast<typename Vector::Scalar>(draw());
  return v;
}

// Eigen::Quaterniond(draw(), draw(), draw(), draw()) as GCC evaluates it: z, y, x, then w.
template <class Draw>
Eigen::Quaterniond drawQuaternion(Draw&& draw) {
  const double z = draw(), y = draw(), x = draw(), w = draw();
  return Eigen::Quaterniond(w, x, y, z);
}

}  // namespace sb::test
