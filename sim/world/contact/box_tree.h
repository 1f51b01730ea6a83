// A bounding-box hierarchy over a fixed set of axis-aligned boxes (an obstacle's triangle boxes):
// visits the boxes near a point, nearer subtrees first, skipping every subtree farther than a
// bound the caller shrinks as it finds closer candidates. Replaces a pass over all boxes when the
// nearest triangle of a whole surface is wanted (the deep contact search): about log₂(#boxes)
// nodes instead of #boxes box tests once a close candidate is known.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "sim/base/types.h"

namespace sb {

class BoxTree {
 public:
  // Leaves hold at most this many boxes.
  static constexpr int kLeafSize = 4;

  // Builds the tree over boxes[0, n) (any n ≥ 0, no empty box). Deterministic: the same boxes
  // give the same tree. A box with a non-finite centre leaves the tree empty (callers then
  // fall back to a pass over all boxes).
  void build(const std::vector<Eigen::AlignedBox3f>& boxes);
  // The same as build(boxes) for the search, at a fraction of its cost, when the boxes are those
  // of the last build moved (a deforming surface): the grouping of boxes into subtrees is kept
  // and only the node boxes are recomputed. visitNear still visits every box within the bound
  // (the grouping only decides how many others it looks at), so a search's result does not
  // change; the tree stays good as long as boxes that were near each other stay near, as the
  // triangles of a shape-matched body do. Builds anew when there is no tree of as many boxes.
  void refit(const std::vector<Eigen::AlignedBox3f>& boxes);
  bool empty() const { return nodes_.empty(); }

  // Calls visit(i) for the boxes i whose subtree box lies within distance² bound() of p (m²), a
  // subtree at a time, nearer subtree first; bound() is read again before each subtree, so a
  // caller that lowers it skips more. Every box whose own distance² to p is ≤ the bound in force
  // when its subtree is reached is visited (a superset: the caller tests the box itself).
  template <typename Bound, typename Visit>
  void visitNear(const Vec3f& p, const Bound& bound, const Visit& visit) const;

 private:
  struct Node {
    Eigen::AlignedBox3f box;  // union of the boxes below
    int first = 0;            // leaf: items_[first, first + count); inner: children first, first+1
    int count = 0;            // boxes in a leaf; 0 for an inner node
  };
  std::vector<Node> nodes_;
  std::vector<int> items_;  // box indices, grouped by leaf
  std::vector<Vec3f> centres_;
  void buildNode(int node, int begin, int end, const std::vector<Eigen::AlignedBox3f>& boxes);

  static float distanceSquared(const Eigen::AlignedBox3f& b, const Vec3f& p) {
    const Vec3f below = (b.min() - p).cwiseMax(0.0f), above = (p - b.max()).cwiseMax(0.0f);
    return (below + above).squaredNorm();
  }
};

template <typename Bound, typename Visit>
void BoxTree::visitNear(const Vec3f& p, const Bound& bound, const Visit& visit) const {
  if (nodes_.empty()) return;
  struct Entry {
    int node;
    float distanceSquared;
  };
  Entry stack[64];  // depth ≤ log₂(#boxes / kLeafSize) + 1 for the median split: 64 is ample
  int top = 0;
  stack[top++] = {0, distanceSquared(nodes_[0].box, p)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.distanceSquared > bound()) continue;
    const Node& n = nodes_[size_t(e.node)];
    if (n.count > 0) {
      for (int k = n.first; k < n.first + n.count; ++k) visit(items_[size_t(k)]);
      continue;
    }
    const float d0 = distanceSquared(nodes_[size_t(n.first)].box, p);
    const float d1 = distanceSquared(nodes_[size_t(n.first + 1)].box, p);
    // The nearer child on top: it is visited first and lowers the bound for the other.
    if (d0 <= d1) {
      stack[top++] = {n.first + 1, d1};
      stack[top++] = {n.first, d0};
    } else {
      stack[top++] = {n.first, d0};
      stack[top++] = {n.first + 1, d1};
    }
  }
}

}  // namespace sb
