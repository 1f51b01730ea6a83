// Union-find over indices 0 … n−1 stored as a parent array (parent[i] == i: a root). Used to
// group bodies into islands (the contact solve and sleep).
#pragma once

#include <cstddef>
#include <vector>

namespace sb {

// The root of i's set, halving the path on the way (parent is updated; roots never change).
inline int findRoot(std::vector<int>& parent, int i) {
  while (parent[size_t(i)] != i) {
    parent[size_t(i)] = parent[size_t(parent[size_t(i)])];
    i = parent[size_t(i)];
  }
  return i;
}

}  // namespace sb
