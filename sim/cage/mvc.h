// Mean value coordinates for closed triangle cages (Ju, Schaefer, Warren 2005), evaluated with
// a formulation that stays accurate on, near and in the plane of cage faces. See README.md.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

// How a point was evaluated.
enum class MvcCase {
  General,    // the closed form (possibly with the in-plane treatment for some faces)
  OnVertex,   // within 1e-13·cage diagonal of a cage vertex: weight 1 there
  OnSurface,  // within 1e-13·cage diagonal of a face or edge: barycentric coordinates
};

struct MvcInfo {
  MvcCase kind = MvcCase::General;
  // Σ|per-triangle contributions| / |Σ weights| before normalisation: the cancellation factor.
  // The expected relative error of the weights is about 1e-16 times this. It grows like
  // (distance / cage size)^2 far outside the cage.
  double conditioning = 1.0;
  // Distance from the cage's bounding-box centre in cage diagonals; `far` beyond 4. Far points
  // lose accuracy like (distance)^4 (cancellation between front and back faces):
  // errorEstimate = 1e-12 up to 4 diagonals, 1e-14 · distance^4 beyond (measured, README.md).
  double distance = 0.0;
  bool far = false;
  double errorEstimate = 1e-12;
};

// A cage prepared for evaluating weights: edge list, per-triangle normals, areas, scale.
// Construct from a validated cage (bindMeanValue validates; this class does not).
class MeanValueCage {
 public:
  explicit MeanValueCage(const mesh::TriangleMesh& cage);

  int vertexCount() const { return static_cast<int>(vx_.size()); }
  double diagonal() const { return diagonal_; }
  const Eigen::Vector3d& centre() const { return centre_; }

  // Per-thread scratch space.
  struct Scratch {
    std::vector<double> ux, uy, uz, invd, d;
    std::vector<double> theta, s, nx, ny, nz;
    std::vector<double> w0, w1, w2;  // per-triangle contributions
    std::vector<int> nearPlane;      // per-triangle: needs the careful path
  };

  // Writes the vertexCount() normalised weights of x into w (Σw = 1, Σ w_j v_j = x).
  // Returns false (w filled with NaN) only if the weights cannot be normalised (Σ = 0 or not
  // finite), which does not happen for points within 4× the cage size of a valid cage.
  bool weights(const Eigen::Vector3d& x, double* w, Scratch& scratch,
               MvcInfo* info = nullptr) const;

 private:
  struct Tri {
    std::array<int, 3> v;
    std::array<int, 3> e;        // edge opposite corner k (from v[k+1] to v[k+2])
    std::array<double, 3> sign;  // +1 if the stored edge runs v[k+1] -> v[k+2]
    Eigen::Vector3d normal;      // unit, outward
    double twiceArea;
  };
  void triangleAlone(const Eigen::Vector3d& p, const Tri& t, double out[3]) const;
  Eigen::Vector3d vertex(int i) const { return {vx_[i], vy_[i], vz_[i]}; }

  std::vector<double> vx_, vy_, vz_;
  std::vector<std::array<int, 2>> edges_;  // (a, b), a < b
  std::vector<Tri> tris_;
  // Structure-of-arrays copies for the vectorised passes.
  std::vector<int> ea_, eb_;
  std::vector<int> tv0_, tv1_, tv2_, te0_, te1_, te2_;
  std::vector<double> ts0_, ts1_, ts2_, tnx_, tny_, tnz_, tarea_;
  double diagonal_ = 0.0;
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
};

// Stateless convenience: prepares the cage and evaluates one point (slow for many points).
// w must hold cage.vertices.size() values.
bool mvcWeights(const Eigen::Vector3d& x, const mesh::TriangleMesh& cage, double* w,
                MvcInfo* info = nullptr);

// Tolerances, all relative (see README.md).
inline constexpr double kOnCageTolerance = 1e-13;  // × cage diagonal: snap to vertex / face
inline constexpr double kPlaneBand =
    1e-4;  // |height| < 1e-4 × distance to a face: in-plane treatment

// In the plane band the closed form of a face's contribution to a weight is 0/0; the
// contribution is h · g(x) with g smooth (it vanishes in the plane). Given the closed form wp, wm
// at heights hp > 0 > hm (δ = kPlaneBand·ρ off the plane, where it is accurate), g is
// interpolated linearly to the height h (error O(δ³/ρ³) relative). Heights that cannot be
// resolved (not possible with the δ floor of the callers) give 0, the limit in the plane.
inline double planeBandContribution(double h, double hp, double hm, double wp, double wm) {
  const double gp = wp / hp, gm = wm / hm;
  const double g = 0.5 * (gp + gm) + (h - 0.5 * (hp + hm)) * (gp - gm) / (hp - hm);
  const double w = h * g;
  return hp > 0.0 && hm < 0.0 && std::isfinite(w) ? w : 0.0;
}

}  // namespace sb::cage
