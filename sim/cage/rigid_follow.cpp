#include "sim/cage/rigid_follow.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "sim/base/linalg.h"

namespace sb::cage {

std::optional<RigidFollow> RigidFollow::make(const Embedding& embedding, ConstPointsRef restCage,
                                             ConstPointsRef restMesh) {
  const int n = int(restCage.rows());
  if (n < 4 || n != embedding.cageVertexCount() || restMesh.rows() != embedding.meshVertexCount() ||
      restMesh.rows() == 0)
    return std::nullopt;
  RigidFollow f;
  f.restCage_ = restCage.cast<double>();
  f.restCentre_ = f.restCage_.colwise().mean().transpose();
  f.restSpread_ = (f.restCage_.rowwise() - f.restCentre_.transpose()).squaredNorm();
  const double diagonal =
      (f.restCage_.colwise().maxCoeff() - f.restCage_.colwise().minCoeff()).norm();
  if (!(f.restSpread_ > 0.0) || !std::isfinite(diagonal)) return std::nullopt;
  f.restMesh_ = restMesh;
  // ε_rest and ε_unity from the float product itself (what deform computes).
  PointsRowMajor atRest, unity;
  embedding.deform(restCage, atRest);
  f.restError_ = (atRest - restMesh).rowwise().norm().maxCoeff();
  if (!(f.restError_ <= 1e-4 * diagonal)) return std::nullopt;
  PointsRowMajor ones = PointsRowMajor::Zero(n, 3);
  ones.col(0).setOnes();
  embedding.deform(ones, unity);
  f.unityError_ = (unity.col(0).array() - 1.0f).abs().maxCoeff();
  // Long baselines: from each of the cage's six extreme vertices (least and most x, y, z) to
  // the vertex farthest from it.
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      int a = 0;
      for (int j = 1; j < n; ++j)
        if (side == 0 ? f.restCage_(j, axis) < f.restCage_(a, axis)
                      : f.restCage_(j, axis) > f.restCage_(a, axis))
          a = j;
      int b = a;
      double far = 0;
      for (int j = 0; j < n; ++j) {
        const double d = (f.restCage_.row(j) - f.restCage_.row(a)).norm();
        if (d > far) far = d, b = j;
      }
      if (far > 0.1 * diagonal) f.pairs_.push_back({a, b, far});
    }
  std::vector<std::pair<int, double>> row;
  for (int i = 0; i < embedding.meshVertexCount(); ++i) {
    embedding.rowWeights(i, row);
    double sum = 0;
    for (const auto& w : row) sum += std::abs(w.second);
    f.lebesgue_ = std::max(f.lebesgue_, sum);
  }
  return f;
}

bool RigidFollow::follow(ConstPointsRef cage, PointsRowMajor& out) const {
  const int n = int(restCage_.rows());
  if (cage.rows() != n) return false;
  auto at = [&](int j) { return Vec3(cage.row(j).transpose().cast<double>()); };
  // Within δ of a similarity of scale s, a pair of rest length ℓ stretches by s ± 2δ/ℓ, so
  // the pairs' intervals [stretch ± 2δ/ℓ] share a point. follow needs L·δ ≤ kTolerance·diagonal
  // (L ≥ 1); the diagonal is less than 4 times the longest pair (each pair runs from a vertex to
  // the one farthest from it, at least half the cage's widest span, and the diagonal is at most
  // √3 times that span). Pairs whose intervals for that δ share no point rule the cage out
  // before the fit: a soft body's every frame.
  if (pairs_.size() >= 2) {
    double longest = 0;
    for (const Pair& p : pairs_) longest = std::max(longest, (at(p.a) - at(p.b)).norm());
    const double deltaMax = kTolerance * 4.0 * longest / lebesgue_;
    double low = -INFINITY, high = INFINITY;
    for (const Pair& p : pairs_) {
      const double stretch = (at(p.a) - at(p.b)).norm() / p.restLength;
      const double slack = 2.0 * deltaMax / p.restLength;
      low = std::max(low, stretch - slack);
      high = std::min(high, stretch + slack);
    }
    if (!(low <= high)) return false;  // also NaN
  }
  Vec3 centre = Vec3::Zero();
  for (int j = 0; j < n; ++j) centre += at(j);
  centre /= double(n);
  if (!centre.allFinite()) return false;
  // The similarity that fits best in the least-squares sense (Umeyama 1991): R the rotation
  // closest to the cross-covariance H, s = tr(RᵀH) over the rest cage's spread.
  Mat3 H = Mat3::Zero();
  for (int j = 0; j < n; ++j)
    H += (at(j) - centre) * (restCage_.row(j).transpose() - restCentre_).transpose();
  const Mat3 R = closestRotationSvd(H);
  const double s = (R.transpose() * H).trace() / restSpread_;  // tr(DΣ), the fitted scale
  const Mat3 sR = s * R;
  const Vec3 t = centre - sR * restCentre_;
  double delta = 0;
  Vec3 lo = at(0), hi = at(0);
  for (int j = 0; j < n; ++j) {
    const Vec3 x = at(j);
    delta = std::max(delta, (x - (sR * restCage_.row(j).transpose() + t)).norm());
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double bound = s * restError_ + t.norm() * unityError_ + lebesgue_ * delta;
  if (!(bound <= kTolerance * (hi - lo).norm())) return false;
  const Eigen::Matrix3f M = sR.cast<float>();
  const Eigen::Vector3f shift = t.cast<float>();
  const Eigen::Index rows = restMesh_.rows();
  out.resize(rows, 3);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const Eigen::Vector3f v = restMesh_.row(i).transpose();
    out.row(i) = (M * v + shift).transpose();
  }
  return true;
}

}  // namespace sb::cage
