// Which particles form which shape-matching cluster.
#pragma once

#include <string>
#include <vector>

#include "sim/world/body_def.h"

namespace sb {

// Builds the member lists (particle indices, ascending, within the body) of every cluster.
// Grid: cubic cells of edge def.cellSize laid over the bounding box of the rest positions; a
// cell's cluster holds the particles inside the cell grown by def.overlap on every side. Cells
// with fewer than 4 particles are dropped, and every particle left in no cluster joins the
// cluster whose cell centre is nearest, so each particle belongs to at least one cluster.
// Clusters must hold the body together: a layout whose clusters fall into groups that share no
// particle is rejected (for a grid: an overlap below about half the particle spacing).
// Throws std::invalid_argument with the field name ("clusters.cellSize", ...) and the reason.
std::vector<std::vector<int>> buildClusterMembers(const ClusterDef& def,
                                                  const std::vector<Vec3>& restPositions);

}  // namespace sb
