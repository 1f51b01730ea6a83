// Shared helpers for the simulation tests: deterministic random shapes and bodies.
#pragma once

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "sim/world/param_ranges.h"
#include "sim/world/world.h"
#include "tests/draws.h"

namespace sb::test {

// A jittered n×n×n grid of points of edge `size` around `centre`, reproducible from `seed`.
inline std::vector<Vec3> jitteredGrid(int n, double size, const Vec3& centre, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  std::vector<Vec3> out;
  const double step = size / (n - 1);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 d = drawVector<Vec3>([&] { return jitter(rng); });  // tests/draws.h
        out.push_back(centre + step * Vec3(i + d.x() - 0.5 * (n - 1), j + d.y() - 0.5 * (n - 1),
                                           k + d.z() - 0.5 * (n - 1)));
      }
  return out;
}

inline Mat3 randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q = drawQuaternion([&] { return g(rng); });
  q.normalize();
  return q.toRotationMatrix();
}

inline Eigen::MatrixX3d toMatrix(const std::vector<Vec3>& v) {
  Eigen::MatrixX3d m(static_cast<int>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) m.row(static_cast<int>(i)) = v[i].transpose();
  return m;
}

inline Eigen::MatrixX3d toDouble(const ConstPointsRef& p) {
  return p.cast<double>();
}

inline double kineticEnergy(const World& w, BodyHandle b) {
  const Eigen::VectorXf m = w.masses(b);
  const Eigen::MatrixX3d v = toDouble(w.velocities(b));
  double e = 0;
  for (int i = 0; i < v.rows(); ++i) e += 0.5 * m[i] * v.row(i).squaredNorm();
  return e;
}

// Settings whose sub-step is exactly dt / substeps, split by maxSubstep only beyond 1 s (the
// longest sub-step accepted): what tests of the update itself at long sub-steps need.
inline WorldSettings exactSubsteps(double dt, int substeps = 1) {
  WorldSettings s;
  s.timeStep = dt;
  s.substeps = substeps;
  s.maxSubstep = limits::maxSubstep.hi;
  return s;
}

inline WorldSettings noGravity(double dt = 0.01, int substeps = 1) {
  WorldSettings s = exactSubsteps(dt, substeps);
  s.gravity = Vec3::Zero();
  return s;
}

}  // namespace sb::test
