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
  // The pose the samples are bound in, which det J is relative to: the cages as they stand now
  // (normally the scene's start), or the bodies' start positions (World::restPositions) whatever
  // the bodies do now (a viewer that starts watching mid-run, or watches again after a switch).
  enum class Pose { Now, Start };
  // Binds about samplesPerBody samples inside each body's cage (in `pose`) with the body's own
  // method; samplesPerBody in [8, 100000]. Bodies without a render mesh are not watched. Throws
  // what the binds throw (invalid cages cannot reach here: the scene bound its render meshes to
  // the same cages).
  FoldWatch(const Scene& scene, int samplesPerBody = 500, Pose pose = Pose::Now);
  // Binds body `body`'s samples again with its method now, in the watch's pose (after its
  // embedding was switched: sim/scene/body_embedding.h). Throws what the bind throws; the
  // watch is unchanged then.
  void rewatch(const Scene& scene, int body);

  struct BodyFolds {
    int body = 0;             // index into scene.bodies
    cage::FoldReport report;  // det J relative to the pose the watch was made in
  };
  // The watched bodies whose maps fold now (none: empty).
  std::vector<BodyFolds> folded(const Scene& scene) const;
  int watchedBodies() const { return static_cast<int>(bodies_.size()); }

  // folded(), with where: the current positions (world, metres) of the samples with det J ≤ 0
  // (points.size() == report.folded), and the samples' lattice spacing (metres, in the watch's
  // pose), so a caller can mark the render mesh near them.
  struct FoldedRegion {
    int body = 0;
    cage::FoldReport report;
    std::vector<Vec3> points;
    double spacing = 0.0;
  };
  std::vector<FoldedRegion> foldedRegions(const Scene& scene) const;

 private:
  struct Watched {
    int body = 0;
    cage::FoldProbes probes;
  };
  // The probes of body i (false: it has no render mesh, not watched).
  bool watch(const Scene& scene, int body, Watched* out) const;
  int samplesPerBody_ = 500;
  Pose pose_ = Pose::Now;
  std::vector<Watched> bodies_;
};

}  // namespace sb
