// A render mesh whose cage moved as a whole follows it without the weights.
//
// The cage coordinates this library binds reproduce affine maps: where every weight row sums to
// one and reproduces its point from the rest cage (Σ_j w_ij = 1, Σ_j w_ij c_j = v_i), a cage
// moved by a similarity x = sRc + t deforms its mesh to W·x = sRv + t. A rigid body's cage
// moves that way (its particles are its goals, R·q + t), so W·x — 3 multiply-adds per weight,
// the seed-scale scene's 90 M weights per frame — can be replaced by moving the rest mesh: 9
// per vertex. RigidFollow checks how far the cage is from the best-fitting similarity and how
// well the float weights reproduce affine maps, and moves the rest mesh only when the two
// results cannot differ by more than a stated tolerance.
//
// The bound: with the fitted map T(c) = sRc + t and the cage's largest distance δ from it,
//   |T(v_i) − Σ_j w_ij x_j| ≤ s·ε_rest + |t|·ε_unity + L·δ,
// ε_rest = max_i |Σ_j w_ij c_j − v_i| and ε_unity = max_i |Σ_j w_ij − 1| of the float weights
// at rest, L = max_i Σ_j |w_ij| (Lebesgue constant of the weights). Both results also round in
// float (a few ulp of the coordinates). docs/design.md §5.8.
#pragma once

#include <optional>
#include <vector>

#include "sim/base/types.h"
#include "sim/cage/embedding.h"

namespace sb::cage {

class RigidFollow {
 public:
  // The mesh's rest vertices and the cage's rest vertices the embedding was bound to, in the
  // same frame (#mesh × 3 and cageVertexCount() × 3, any unit). Measures ε_rest, ε_unity and L
  // of the embedding's float weights; none when the embedding's rows do not match or it does
  // not reproduce its rest mesh to 1e-4 of the cage's size (then every deform takes the weights).
  static std::optional<RigidFollow> make(const Embedding& embedding, ConstPointsRef restCage,
                                         ConstPointsRef restMesh);

  // When `cage` (cageVertexCount() × 3, metres) is a similarity transform of the rest cage
  // whose bound above is at most tolerance × the moved cage's bounding-box diagonal, writes the
  // rest mesh moved by it to out (#mesh × 3) and returns true; otherwise leaves out alone and
  // returns false. Non-finite positions return false.
  bool follow(ConstPointsRef cage, PointsRowMajor& out) const;

  // Relative tolerance of follow (the bound over the cage's diagonal): 1e-5, i.e. 5 µm for a
  // 0.5 m body, about the rounding of W·x itself in float (a sum of ~160 products of
  // coordinates of a few metres).
  static constexpr double kTolerance = 1e-5;

  // The bound's parts (see above), for tests and reports.
  double restError() const { return restError_; }    // ε_rest, in the rest frame's units
  double unityError() const { return unityError_; }  // ε_unity
  double lebesgue() const { return lebesgue_; }      // L

 private:
  // Pairs of far-apart cage vertices and their rest distances: a similarity keeps their ratios,
  // so a cage whose pairs stretch by different factors is turned down before the fit (a soft
  // body's every frame) — soundly: such a cage cannot pass the bound (follow).
  struct Pair {
    int a, b;
    double restLength;
  };
  std::vector<Pair> pairs_;
  Eigen::Matrix<double, Eigen::Dynamic, 3> restCage_;
  Vec3 restCentre_ = Vec3::Zero();
  double restSpread_ = 0;  // Σ_j |c_j − centre|²
  PointsRowMajor restMesh_;
  double restError_ = 0, unityError_ = 0, lebesgue_ = 0;
};

}  // namespace sb::cage
