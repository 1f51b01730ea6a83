#include "sim/world/contact/soft_impact.h"

#include <algorithm>
#include <cmath>

namespace sb {

int relaxSubsteps(double alpha) {
  if (!(alpha > 0.0)) return kMaxRelaxSubsteps;
  if (alpha >= 1.0) return 1;
  const double n = std::ceil(std::log(0.01) / std::log1p(-alpha));
  return int(std::min(n, double(kMaxRelaxSubsteps)));
}

float advanceSoftImpact(SoftImpact& impact, float relativeNormalVelocity, bool meets, float pushed,
                        bool& alive) {
  alive = true;
  const float target = impact.restitution * impact.approach;
  // Holding back takes at most what the pair's contacts gave (never pulls the bodies together
  // against what else moves them).
  auto holdBack = [&] {
    return relativeNormalVelocity > target
               ? std::max(target - relativeNormalVelocity, -std::max(pushed, 0.0f))
               : 0.0f;
  };
  if (!impact.met) {
    if (!meets) {
      alive = relativeNormalVelocity < 0.0f;  // still coming, or a near miss
      return 0.0f;
    }
    impact.met = true;
  }
  if (impact.released < 0) {
    if (relativeNormalVelocity < 0.0f) {
      ++impact.compressing;
      return 0.0f;
    }
    // Compression is over: the centres separate with e·u₀.
    impact.released = 0;
    return relativeNormalVelocity < target ? target - relativeNormalVelocity : holdBack();
  }
  // Release: the stored deformation may not throw the pair apart faster than e·u₀, for as long
  // as the compression took and the softer body needs to relax (and at least one sub-step).
  ++impact.released;
  if (impact.released > std::max(impact.compressing + 1, impact.relaxing)) {
    alive = false;
    return 0.0f;
  }
  return holdBack();
}

}  // namespace sb
