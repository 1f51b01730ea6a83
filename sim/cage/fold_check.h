// Fold check for any embedding: whether the map of space a moved cage (or lattice, or set of
// handles) makes through its weights stays one-to-one, sampled at points inside.
//
// The Jacobian J of the map at a sample x comes from the embedding itself: x and the three
// points x + h·e_x, x + h·e_y, x + h·e_z are bound with the same method, and J's columns are the
// differences of their deformed positions over h (a forward difference: exact for affine
// motions, O(h) otherwise). det J is the local volume ratio: 1 at rest (to the method's linear
// precision), ≤ 0 where the map turns space inside out — a fold, where the render mesh passes
// through itself. The check is sufficient for what it samples only: a fold smaller than the
// sample spacing can slip between samples (FFD B-spline lattices also have an exact sufficient
// bound, ffd_lattice.h).
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "sim/base/types.h"
#include "sim/cage/embedding.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

struct FoldProbes {
  std::vector<Vec3> samples;  // rest positions (the cage's units)
  double step = 0.0;          // h, the difference step (same units)
  Embedding embedding;        // 4 rows per sample: x, x + h·e_x, x + h·e_y, x + h·e_z
};

// Binds the samples and their offsets with `bind` (the same method and controls the mesh uses:
// points → Embedding over the controls). step > 0 and finite; the offsets should stay inside
// the controlled region (foldSamples keeps them there). Throws std::invalid_argument on a bad
// step or an empty sample list; whatever bind throws.
FoldProbes makeFoldProbes(const std::vector<Vec3>& samples, double step,
                          const std::function<Embedding(const std::vector<Vec3>&)>& bind);

// Samples for a closed cage: about `target` points of a cubic lattice inside it, each at least
// half a lattice spacing from the surface (interior_points.h), and the step that keeps every
// offset inside (a quarter spacing). target in [8, 100000]; std::invalid_argument otherwise or
// when the cage is not closed.
struct FoldSampling {
  std::vector<Vec3> samples;
  double step = 0.0;
};
FoldSampling foldSamples(const mesh::TriangleMesh& cage, int target = 2000);

struct FoldReport {
  int samples = 0;
  int folded = 0;               // samples with det J ≤ 0
  double minDeterminant = 1.0;  // smallest det J over the samples (1 = unchanged volume)
  int worstSample = -1;         // its index (-1 without samples)
};

// det J at every sample for the controls at `controls` (#controls × 3, same order and units as
// the bind; double precision). Throws std::invalid_argument on a wrong row count.
FoldReport checkFolds(const FoldProbes& probes,
                      const Eigen::Matrix<double, Eigen::Dynamic, 3>& controls);

}  // namespace sb::cage
