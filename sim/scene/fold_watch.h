// Watches a scene's render meshes for folds: for every body with a render mesh, the map its
// cage makes of space (the body's embedding method) is sampled inside the cage and checked for
// det J ≤ 0 (sim/cage/fold_check.h) — where the render mesh passes through itself.
#pragma once

#include <vector>

#include "sim/cage/fold_check.h"
#include "sim/scene/scene.h"

namespace sb {

class FoldWatch {
 public:
  // Binds about samplesPerBody samples inside each body's cage as it stands now (normally the
  // scene's start) with the body's own method; samplesPerBody in [8, 100000]. Bodies without a
  // render mesh are not watched. Throws what the binds throw (invalid cages cannot reach here:
  // the scene bound its render meshes to the same cages).
  FoldWatch(const Scene& scene, int samplesPerBody = 500);

  struct BodyFolds {
    int body = 0;             // index into scene.bodies
    cage::FoldReport report;  // det J relative to the pose the watch was made in
  };
  // The watched bodies whose maps fold now (none: empty).
  std::vector<BodyFolds> folded(const Scene& scene) const;
  int watchedBodies() const { return static_cast<int>(bodies_.size()); }

 private:
  struct Watched {
    int body = 0;
    cage::FoldProbes probes;
  };
  std::vector<Watched> bodies_;
};

}  // namespace sb
