#include "sim/world/contact/box_tree.h"

#include <algorithm>
#include <numeric>

namespace sb {

void BoxTree::build(const std::vector<Eigen::AlignedBox3f>& boxes) {
  const int n = static_cast<int>(boxes.size());
  nodes_.clear();
  items_.resize(size_t(n));
  std::iota(items_.begin(), items_.end(), 0);
  centres_.resize(size_t(n));
  for (int i = 0; i < n; ++i) {
    centres_[size_t(i)] = boxes[size_t(i)].center();
    if (!centres_[size_t(i)].allFinite()) return;  // no order to split by: an empty tree
  }
  if (n == 0) return;
  nodes_.reserve(size_t(2 * (n / kLeafSize + 1)));
  nodes_.emplace_back();
  buildNode(0, 0, n, boxes);
}

void BoxTree::refit(const std::vector<Eigen::AlignedBox3f>& boxes) {
  if (nodes_.empty() || items_.size() != boxes.size()) {
    build(boxes);
    return;
  }
  for (const Eigen::AlignedBox3f& b : boxes)
    if (!b.center().allFinite()) {
      nodes_.clear();  // as build: no tree (callers pass over all boxes), built anew next time
      return;
    }
  // Children come after their parent (buildNode appends them), so a backward pass sees every
  // child before its parent.
  for (size_t k = nodes_.size(); k-- > 0;) {
    Node& n = nodes_[k];
    Eigen::AlignedBox3f box;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i)
        box.extend(boxes[size_t(items_[size_t(i)])]);
    } else {
      box = nodes_[size_t(n.first)].box.merged(nodes_[size_t(n.first + 1)].box);
    }
    n.box = box;
  }
}

// Node `node` over items_[begin, end): a leaf, or split at the median of the box centres along
// the longest axis of their spread (ties by box index, so the split does not depend on the
// library's nth_element).
void BoxTree::buildNode(int node, int begin, int end,
                        const std::vector<Eigen::AlignedBox3f>& boxes) {
  Eigen::AlignedBox3f box, spread;
  for (int k = begin; k < end; ++k) {
    box.extend(boxes[size_t(items_[size_t(k)])]);
    spread.extend(centres_[size_t(items_[size_t(k)])]);
  }
  nodes_[size_t(node)].box = box;
  if (end - begin <= kLeafSize) {
    nodes_[size_t(node)].first = begin;
    nodes_[size_t(node)].count = end - begin;
    return;
  }
  int axis = 0;
  spread.sizes().maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                   [&](int a, int b) {
                     const float ca = centres_[size_t(a)][axis], cb = centres_[size_t(b)][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const int left = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[size_t(node)].first = left;
  nodes_[size_t(node)].count = 0;
  buildNode(left, begin, mid, boxes);
  buildNode(left + 1, mid, end, boxes);
}

}  // namespace sb
