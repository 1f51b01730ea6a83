#include "sim/world/matching/plasticity.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace sb {

double spectralNorm(const Mat3& M) {
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(M.transpose() * M, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

namespace {

bool normaliseVolume(Mat3& M) {
  const double det = M.determinant();
  if (!(det > 0.0) || !std::isfinite(det)) return false;
  M /= std::cbrt(det);
  return true;
}

}  // namespace

bool updatePlasticDeformation(const Mat3& stretch, double h, const PlasticityParams& params,
                              Mat3& plastic) {
  if (!params.enabled() || !stretch.allFinite()) return false;
  const Mat3 I = Mat3::Identity();
  const Mat3 excess = stretch - I;
  if (!(spectralNorm(excess) > params.yield)) return false;
  Mat3 next = (I + h * params.creep * excess) * plastic;
  if (!normaliseVolume(next)) return false;
  // Clamping toward I and renormalising the volume interact slightly; a few rounds converge to
  // a matrix inside the c_max ball with det = 1.
  for (int round = 0; round < 8; ++round) {
    const double norm = spectralNorm(next - I);
    if (norm <= params.max) break;
    next = I + (params.max * (1.0 - 1e-9) / norm) * (next - I);
    if (!normaliseVolume(next)) return false;
  }
  plastic = next;
  return true;
}

}  // namespace sb
