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
  // The fraction of the excess absorbed over h: 1 − e^(−h·c_creep) (exact for a constant
  // stretch), never more than all of it. h·c_creep itself overshoots once it exceeds 1: the rest
  // shape passes the current shape, the next stretch is larger and opposite, and the body swells.
  const double absorbed = -std::expm1(-h * params.creep);
  Mat3 next = (I + absorbed * excess) * plastic;
  // Keep Sᵖ a symmetric stretch (its polar factor): the product of two stretches carries a small
  // rotation that would turn the rest shape with every update, and the body would crawl.
  Eigen::SelfAdjointEigenSolver<Mat3> eig(next.transpose() * next);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues().minCoeff() > 0.0)) return false;
  next = eig.eigenvectors() * eig.eigenvalues().cwiseSqrt().asDiagonal() *
         eig.eigenvectors().transpose();
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
