// One way in for every embedding driven by a closed triangle cage: bind(points, cage, method)
// → Embedding (deform takes the #cage vertices × 3 positions), whatever the coordinates; the result
// deforms with Embedding::deform like any other and is cached like mean value binds (the key covers
// the method and its options). FFD lattices are driven by lattice nodes, not a cage: bindFfd
// (ffd_lattice.h).
#pragma once

#include <string>
#include <vector>

#include "sim/cage/embedding.h"
#include "sim/cage/harmonic.h"
#include "sim/cage/rbf.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

struct EmbeddingMethod {
  EmbeddingKind kind = EmbeddingKind::MeanValue;  // MeanValue, Harmonic, Rbf or Green
  HarmonicOptions harmonic;                       // used when kind is Harmonic
  RbfOptions rbf;                                 // used when kind is Rbf (handles: cage vertices)
};

// Validates the cage (closed, consistently outward: mesh::SurfaceError), then binds with the
// method. options: threads, cache folder, warnings; storage and pruning apply to mean value
// coordinates only (harmonic, RBF and Green weights are dense). Green weights have V + F
// columns and come with the cage attached (Embedding::attachGreenCage), so they deform from the
// V cage vertices like the others; Green refuses points outside the cage (green.h). An FFD kind
// is refused (std::invalid_argument: it needs a lattice).
Embedding bindToCage(const std::vector<Vec3>& points, const mesh::TriangleMesh& cage,
                     const EmbeddingMethod& method, const BindOptions& options = {});

}  // namespace sb::cage
