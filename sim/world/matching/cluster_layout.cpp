#include "sim/world/matching/cluster_layout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sb {

namespace {

std::vector<std::vector<int>> gridClusters(const ClusterDef& def, const std::vector<Vec3>& rest) {
  if (!(def.cellSize > 0.0) || !std::isfinite(def.cellSize))
    throw std::invalid_argument("clusters.cellSize: must be a positive number of metres");
  if (!(def.overlap >= 0.0) || !std::isfinite(def.overlap))
    throw std::invalid_argument("clusters.overlap: must be ≥ 0 metres");
  Vec3 lo = rest[0], hi = rest[0];
  for (const Vec3& p : rest) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Eigen::Vector3i cells;
  for (int a = 0; a < 3; ++a) {
    const double n = std::floor((hi[a] - lo[a]) / def.cellSize) + 1.0;
    if (n > 1024.0)
      throw std::invalid_argument(
          "clusters.cellSize: too small for this body (more than 1024 cells along an axis)");
    cells[a] = static_cast<int>(n);
  }
  const long long cellCount = 1LL * cells[0] * cells[1] * cells[2];
  if (cellCount > 4000000)
    throw std::invalid_argument("clusters.cellSize: too small for this body (over 4M cells)");

  // Each particle lands in every cell whose grown box contains it: the cells within
  // `reach` cells of its own along each axis. overlap / cellSize can be as large as 1e12 (both
  // accepted): in double, clamped to the grid's size before it becomes an int, so neither the
  // conversion nor own ± reach overflows.
  const double reachCells = std::ceil(def.overlap / def.cellSize);
  const int reach = reachCells < 1024.0 ? static_cast<int>(reachCells) : 1024;
  // Memberships are bounded too: each particle joins at most this many cells.
  long long perParticle = 1;
  for (int a = 0; a < 3; ++a) perParticle *= std::min<long long>(cells[a], 2LL * reach + 1);
  if (perParticle * static_cast<long long>(rest.size()) > 20000000)
    throw std::invalid_argument(
        "clusters.overlap: too large for this cell size (each particle would join up to " +
        std::to_string(perParticle) + " of the " + std::to_string(cellCount) + " cells)");
  std::vector<std::vector<int>> members(static_cast<size_t>(cellCount));
  auto cellIndex = [&](int i, int j, int k) { return (1LL * k * cells[1] + j) * cells[0] + i; };
  for (int p = 0; p < static_cast<int>(rest.size()); ++p) {
    const Vec3 rel = (rest[p] - lo) / def.cellSize;
    int own[3];
    for (int a = 0; a < 3; ++a)
      own[a] = std::min(cells[a] - 1, std::max(0, static_cast<int>(std::floor(rel[a]))));
    for (int k = std::max(0, own[2] - reach); k <= std::min(cells[2] - 1, own[2] + reach); ++k)
      for (int j = std::max(0, own[1] - reach); j <= std::min(cells[1] - 1, own[1] + reach); ++j)
        for (int i = std::max(0, own[0] - reach); i <= std::min(cells[0] - 1, own[0] + reach);
             ++i) {
          const Vec3 cellLo = lo + def.cellSize * Vec3(i, j, k) - Vec3::Constant(def.overlap);
          const Vec3 cellHi = cellLo + Vec3::Constant(def.cellSize + 2.0 * def.overlap);
          const Vec3& x = rest[p];
          if ((x.array() >= cellLo.array()).all() && (x.array() <= cellHi.array()).all())
            members[static_cast<size_t>(cellIndex(i, j, k))].push_back(p);
        }
  }
  // Keep cells that can define a rotation; remember their centres for orphans.
  std::vector<std::vector<int>> kept;
  std::vector<Vec3> centres;
  for (int k = 0; k < cells[2]; ++k)
    for (int j = 0; j < cells[1]; ++j)
      for (int i = 0; i < cells[0]; ++i) {
        auto& m = members[static_cast<size_t>(cellIndex(i, j, k))];
        if (m.size() >= 4) {
          kept.push_back(std::move(m));
          centres.push_back(lo + def.cellSize * (Vec3(i, j, k) + Vec3::Constant(0.5)));
        }
      }
  if (kept.empty()) {  // too few particles per cell everywhere: one cluster
    std::vector<int> all(rest.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
    return {all};
  }
  std::vector<char> covered(rest.size(), 0);
  for (const auto& m : kept)
    for (int p : m) covered[static_cast<size_t>(p)] = 1;
  for (int p = 0; p < static_cast<int>(rest.size()); ++p) {
    if (covered[static_cast<size_t>(p)]) continue;
    size_t best = 0;
    double bestD = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < centres.size(); ++c) {
      const double d = (centres[c] - rest[p]).squaredNorm();
      if (d < bestD) bestD = d, best = c;
    }
    auto& m = kept[best];
    m.insert(std::upper_bound(m.begin(), m.end(), p), p);
  }
  return kept;
}

// Number of groups of clusters that share no particle with each other (clusters that share a
// particle are joined; union–find over the particles' first clusters).
int disconnectedGroups(const std::vector<std::vector<int>>& clusters, int particleCount) {
  std::vector<int> parent(clusters.size());
  for (size_t c = 0; c < parent.size(); ++c) parent[c] = int(c);
  auto find = [&](int c) {
    while (parent[size_t(c)] != c) c = parent[size_t(c)] = parent[size_t(parent[size_t(c)])];
    return c;
  };
  std::vector<int> firstCluster(static_cast<size_t>(particleCount), -1);
  for (size_t c = 0; c < clusters.size(); ++c)
    for (int p : clusters[c]) {
      int& first = firstCluster[size_t(p)];
      if (first < 0) {
        first = int(c);
      } else {
        const int a = find(first), b = find(int(c));
        if (a != b) parent[size_t(std::max(a, b))] = std::min(a, b);
      }
    }
  int groups = 0;
  for (size_t c = 0; c < parent.size(); ++c) groups += find(int(c)) == int(c);
  return groups;
}

std::vector<std::vector<int>> layoutClusters(const ClusterDef& def, const std::vector<Vec3>& rest) {
  const int n = static_cast<int>(rest.size());
  if (n == 0) throw std::invalid_argument("positions: a body needs at least one particle");
  switch (def.kind) {
    case ClusterDef::Kind::Single: {
      std::vector<int> all(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) all[static_cast<size_t>(i)] = i;
      return {all};
    }
    case ClusterDef::Kind::Grid:
      return gridClusters(def, rest);
    case ClusterDef::Kind::Explicit: {
      if (def.clusters.empty())
        throw std::invalid_argument("clusters.clusters: explicit clustering needs ≥ 1 cluster");
      std::vector<char> covered(static_cast<size_t>(n), 0);
      std::vector<std::vector<int>> out;
      for (size_t c = 0; c < def.clusters.size(); ++c) {
        std::vector<int> m = def.clusters[c];
        const std::string field = "clusters.clusters[" + std::to_string(c) + "]";
        if (m.empty()) throw std::invalid_argument(field + ": empty cluster");
        std::sort(m.begin(), m.end());
        if (std::adjacent_find(m.begin(), m.end()) != m.end())
          throw std::invalid_argument(field + ": a particle is listed twice");
        if (m.front() < 0 || m.back() >= n)
          throw std::invalid_argument(field + ": particle index out of range [0, " +
                                      std::to_string(n) + ")");
        for (int p : m) covered[static_cast<size_t>(p)] = 1;
        out.push_back(std::move(m));
      }
      for (int p = 0; p < n; ++p)
        if (!covered[static_cast<size_t>(p)])
          throw std::invalid_argument("clusters.clusters: particle " + std::to_string(p) +
                                      " is in no cluster");
      return out;
    }
  }
  throw std::invalid_argument("clusters.kind: unknown");
}

}  // namespace

std::vector<std::vector<int>> buildClusterMembers(const ClusterDef& def,
                                                  const std::vector<Vec3>& rest) {
  std::vector<std::vector<int>> clusters = layoutClusters(def, rest);
  // Clusters hold a body together only through the particles they share: a layout that falls
  // into groups sharing none would let the body come apart.
  const int groups = disconnectedGroups(clusters, static_cast<int>(rest.size()));
  if (groups > 1) {
    if (def.kind == ClusterDef::Kind::Grid)
      throw std::invalid_argument(
          "clusters.overlap: the grid's clusters fall into " + std::to_string(groups) +
          " groups that share no particle, so the body would come apart; make the overlap (" +
          std::to_string(def.overlap) + " m) at least about half the particle spacing");
    throw std::invalid_argument("clusters.clusters: the clusters fall into " +
                                std::to_string(groups) +
                                " groups that share no particle, so the body would come apart");
  }
  return clusters;
}

}  // namespace sb
