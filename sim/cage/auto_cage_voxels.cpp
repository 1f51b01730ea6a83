// Voxel solid and its boundary surface: see auto_cage_voxels.h.
#include "sim/cage/auto_cage_voxels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>

namespace sb::cage::detail {

namespace {

class Grid {
 public:
  explicit Grid(const std::array<int, 3>& n) : n_(n), size_(std::size_t(n[0]) * n[1] * n[2]) {}
  std::size_t size() const { return size_; }
  int n(int d) const { return n_[static_cast<std::size_t>(d)]; }
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           std::size_t(n_[0]) * (std::size_t(j) + std::size_t(n_[1]) * std::size_t(k));
  }
  std::array<int, 3> coords(std::size_t v) const {
    const int i = static_cast<int>(v % std::size_t(n_[0]));
    const std::size_t r = v / std::size_t(n_[0]);
    return {i, static_cast<int>(r % std::size_t(n_[1])), static_cast<int>(r / std::size_t(n_[1]))};
  }
  bool onBorder(const std::array<int, 3>& c) const {
    for (int d = 0; d < 3; ++d)
      if (c[d] == 0 || c[d] == n_[d] - 1) return true;
    return false;
  }
  // Calls f(neighbour index) for the 6 face neighbours inside the grid.
  template <typename F>
  void forNeighbours(std::size_t v, const F& f) const {
    const std::array<int, 3> c = coords(v);
    for (int d = 0; d < 3; ++d)
      for (int s = -1; s <= 1; s += 2) {
        std::array<int, 3> e = c;
        e[d] += s;
        if (e[d] < 0 || e[d] >= n_[d]) continue;
        f(index(e[0], e[1], e[2]));
      }
  }

 private:
  std::array<int, 3> n_;
  std::size_t size_;
};

// Marks the voxels whose centre is within radius of triangle (a, b, c) (a point when all equal).
void rasterise(const Grid& g, const Vec& a, const Vec& b, const Vec& c, double radius,
               std::vector<std::uint8_t>& occupied) {
  const Vec lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  std::array<int, 3> from{}, to{};
  for (int d = 0; d < 3; ++d) {
    from[d] = std::max(0, static_cast<int>(std::ceil(lo[d] - radius - 0.5)));
    to[d] = std::min(g.n(d) - 1, static_cast<int>(std::floor(hi[d] + radius - 0.5)));
  }
  for (int k = from[2]; k <= to[2]; ++k)
    for (int j = from[1]; j <= to[1]; ++j)
      for (int i = from[0]; i <= to[0]; ++i) {
        const std::size_t v = g.index(i, j, k);
        if (occupied[v]) continue;
        if (pointTriangleDistance(Vec(i + 0.5, j + 0.5, k + 0.5), a, b, c) <= radius)
          occupied[v] = 1;
      }
}

// solid = not reached from the grid border through non-blocked voxels.
std::vector<std::uint8_t> fillInterior(const Grid& g, const std::vector<std::uint8_t>& blocked) {
  std::vector<std::uint8_t> solid(g.size(), 1);
  std::deque<std::size_t> queue;
  for (std::size_t v = 0; v < g.size(); ++v)
    if (g.onBorder(g.coords(v)) && !blocked[v]) {
      solid[v] = 0;
      queue.push_back(v);
    }
  while (!queue.empty()) {
    const std::size_t v = queue.front();
    queue.pop_front();
    g.forNeighbours(v, [&](std::size_t w) {
      if (solid[w] && !blocked[w]) {
        solid[w] = 0;
        queue.push_back(w);
      }
    });
  }
  return solid;
}

// Labels the 6-connected components of the solid (label −1 outside); returns their count.
int labelComponents(const Grid& g, const std::vector<std::uint8_t>& solid,
                    std::vector<int>& label) {
  label.assign(g.size(), -1);
  int count = 0;
  std::vector<std::size_t> stack;
  for (std::size_t s = 0; s < g.size(); ++s) {
    if (!solid[s] || label[s] >= 0) continue;
    label[s] = count;
    stack.push_back(s);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      g.forNeighbours(v, [&](std::size_t w) {
        if (solid[w] && label[w] < 0) {
          label[w] = count;
          stack.push_back(w);
        }
      });
    }
    ++count;
  }
  return count;
}

// Makes solid the voxels of a shortest 6-connected path from component 0 to the nearest other
// component (breadth-first from all of component 0).
void bridgeFromFirst(const Grid& g, const std::vector<int>& label,
                     std::vector<std::uint8_t>& solid) {
  constexpr std::size_t kNone = ~std::size_t(0);
  std::vector<std::size_t> parent(g.size(), kNone);
  std::deque<std::size_t> queue;
  for (std::size_t v = 0; v < g.size(); ++v)
    if (label[v] == 0) {
      parent[v] = v;
      queue.push_back(v);
    }
  while (!queue.empty()) {
    const std::size_t v = queue.front();
    queue.pop_front();
    std::size_t hit = kNone;
    g.forNeighbours(v, [&](std::size_t w) {
      if (hit != kNone || parent[w] != kNone) return;
      if (label[w] > 0) {
        hit = w;
        return;
      }
      if (g.onBorder(g.coords(w))) return;  // the border stays exterior
      parent[w] = v;
      queue.push_back(w);
    });
    if (hit != kNone) {
      for (std::size_t u = v; label[u] != 0; u = parent[u]) solid[u] = 1;
      return;
    }
  }
}

// For each 8-voxel configuration around a grid corner (bit dx + 2·dy + 4·dz set = solid): true
// when the surface is a single disc there (or absent), i.e. the solid voxels and the exterior
// voxels are each face-connected within the 2×2×2 block.
std::array<bool, 256> manifoldTable() {
  const auto connected = [](int set) {
    if (set == 0) return true;
    int seen = set & -set, grew = 1;
    while (grew) {
      grew = 0;
      for (int b = 0; b < 8; ++b)
        if ((seen >> b) & 1)
          for (int d = 0; d < 3; ++d) {
            const int nb = b ^ (1 << d);
            if (((set >> nb) & 1) && !((seen >> nb) & 1)) {
              seen |= 1 << nb;
              grew = 1;
            }
          }
    }
    return seen == set;
  };
  std::array<bool, 256> table{};
  for (int m = 0; m < 256; ++m)
    table[static_cast<std::size_t>(m)] = connected(m) && connected(~m & 255);
  return table;
}

// Makes solid the 8 voxels around every non-manifold interior grid corner; returns whether any
// voxel changed.
bool closeNonManifoldCorners(const Grid& g, std::vector<std::uint8_t>& solid) {
  static const std::array<bool, 256> table = manifoldTable();
  bool changed = false;
  for (int k = 1; k < g.n(2); ++k)
    for (int j = 1; j < g.n(1); ++j)
      for (int i = 1; i < g.n(0); ++i) {
        int mask = 0;
        for (int b = 0; b < 8; ++b)
          if (solid[g.index(i - 1 + (b & 1), j - 1 + ((b >> 1) & 1), k - 1 + ((b >> 2) & 1))])
            mask |= 1 << b;
        if (table[static_cast<std::size_t>(mask)]) continue;
        for (int b = 0; b < 8; ++b) {
          const std::array<int, 3> c{i - 1 + (b & 1), j - 1 + ((b >> 1) & 1),
                                     k - 1 + ((b >> 2) & 1)};
          if (g.onBorder(c)) continue;
          std::uint8_t& s = solid[g.index(c[0], c[1], c[2])];
          if (!s) {
            s = 1;
            changed = true;
          }
        }
      }
  return changed;
}

}  // namespace

mesh::TriangleMesh voxelSurface(const std::vector<Vec>& vertices, const std::vector<Tri>& triangles,
                                const std::array<int, 3>& cells, double radius) {
  const Grid g(cells);
  std::vector<std::uint8_t> solid(g.size(), 0);
  for (const Vec& v : vertices) rasterise(g, v, v, v, radius, solid);
  for (const Tri& t : triangles)
    rasterise(g, vertices[static_cast<std::size_t>(t[0])], vertices[static_cast<std::size_t>(t[1])],
              vertices[static_cast<std::size_t>(t[2])], radius, solid);
  // Fill, bridge and close until nothing changes: bridging and closing only add voxels, but may
  // enclose exterior pockets, which the next fill makes solid.
  std::vector<int> label;
  for (;;) {
    solid = fillInterior(g, solid);
    if (labelComponents(g, solid, label) > 1) {
      bridgeFromFirst(g, label, solid);
      continue;
    }
    if (!closeNonManifoldCorners(g, solid)) break;
  }

  mesh::TriangleMesh out;
  const std::array<int, 3> nodes{g.n(0) + 1, g.n(1) + 1, g.n(2) + 1};
  std::vector<int> nodeId(static_cast<std::size_t>(nodes[0]) * nodes[1] * nodes[2], -1);
  const auto node = [&](const std::array<int, 3>& c) {
    int& id = nodeId[std::size_t(c[0]) +
                     std::size_t(nodes[0]) *
                         (std::size_t(c[1]) + std::size_t(nodes[1]) * std::size_t(c[2]))];
    if (id < 0) {
      id = static_cast<int>(out.vertices.size());
      out.vertices.emplace_back(c[0], c[1], c[2]);
    }
    return id;
  };
  for (std::size_t v = 0; v < g.size(); ++v) {
    if (!solid[v]) continue;
    const std::array<int, 3> c = g.coords(v);
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        std::array<int, 3> e = c;
        e[d] += s ? 1 : -1;
        if (solid[g.index(e[0], e[1], e[2])]) continue;
        // The face between voxel c and its exterior neighbour, counter-clockwise seen from the
        // exterior: axes u, v with u × v = +axis d.
        const int u = (d + 1) % 3, w = (d + 2) % 3;
        std::array<int, 3> p0 = c;
        p0[d] += s;
        std::array<int, 3> p1 = p0, p2 = p0, p3 = p0;
        p1[u] += 1;
        p2[u] += 1;
        p2[w] += 1;
        p3[w] += 1;
        std::array<int, 4> q{node(p0), node(p1), node(p2), node(p3)};
        if (!s) std::swap(q[1], q[3]);
        out.triangles.push_back({q[0], q[1], q[2]});
        out.triangles.push_back({q[0], q[2], q[3]});
      }
  }
  return out;
}

}  // namespace sb::cage::detail
