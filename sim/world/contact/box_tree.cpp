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
