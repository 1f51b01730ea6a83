#include "render/triangle_order.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace sb::render {

namespace {

constexpr int kCacheSize = 32;

// How much drawing a triangle with this vertex next is worth.
float vertexScore(int cachePosition, int trianglesLeft) {
  if (trianglesLeft == 0) return -1.0f;  // nothing left to draw with it
  float score = 0.0f;
  if (cachePosition >= 0) {
    // The last triangle's own three vertices get one flat score: favouring the very newest would
    // make thin strips that leave long unfinished edges behind.
    score = cachePosition < 3 ? 0.75f
                              : std::pow(1.0f - static_cast<float>(cachePosition - 3) /
                                                    static_cast<float>(kCacheSize - 3),
                                         1.5f);
  }
  // Vertices with few triangles left are finished early, so that no lone triangles are left to
  // be drawn later when their vertices have long left the cache.
  return score + 2.0f / std::sqrt(static_cast<float>(trianglesLeft));
}

}  // namespace

std::vector<std::int32_t> cacheFriendlyTriangleOrder(const std::int32_t* indices,
                                                     std::size_t triangleCount) {
  std::vector<std::int32_t> ordered;
  ordered.reserve(3 * triangleCount);
  if (triangleCount == 0) return ordered;
  const std::size_t cornerCount = 3 * triangleCount;
  std::int32_t vertexCount = 0;
  for (std::size_t i = 0; i < cornerCount; ++i) {
    assert(indices[i] >= 0);
    vertexCount = std::max(vertexCount, indices[i] + 1);
  }
  const auto vertices = static_cast<std::size_t>(vertexCount);

  // The triangles of each vertex: trianglesOf[first[v] .. first[v] + left[v]) are those not
  // drawn yet (a drawn one is swapped past the end of its vertex's range).
  std::vector<std::int32_t> first(vertices + 1, 0), left(vertices, 0);
  for (std::size_t i = 0; i < cornerCount; ++i) ++first[static_cast<std::size_t>(indices[i]) + 1];
  for (std::size_t v = 0; v < vertices; ++v) first[v + 1] += first[v];
  std::vector<std::int32_t> trianglesOf(cornerCount);
  for (std::size_t i = 0; i < cornerCount; ++i) {
    const auto v = static_cast<std::size_t>(indices[i]);
    trianglesOf[static_cast<std::size_t>(first[v] + left[v]++)] = static_cast<std::int32_t>(i / 3);
  }

  std::vector<int> cachePosition(vertices, -1);
  std::vector<float> score(vertices);
  for (std::size_t v = 0; v < vertices; ++v) score[v] = vertexScore(-1, left[v]);
  std::vector<float> triangleScore(triangleCount, 0.0f);
  for (std::size_t i = 0; i < cornerCount; ++i)
    triangleScore[i / 3] += score[static_cast<std::size_t>(indices[i])];
  std::vector<char> drawn(triangleCount, 0);

  std::vector<std::int32_t> cache, nextCache;
  cache.reserve(kCacheSize + 3);
  nextCache.reserve(kCacheSize + 3);
  std::size_t firstUndrawn = 0;
  auto best = static_cast<std::int64_t>(
      std::max_element(triangleScore.begin(), triangleScore.end()) - triangleScore.begin());
  for (std::size_t count = 0; count < triangleCount; ++count) {
    if (best < 0) {  // the cached vertices have no triangles left: start anew anywhere
      while (drawn[firstUndrawn]) ++firstUndrawn;
      best = static_cast<std::int64_t>(firstUndrawn);
    }
    const auto t = static_cast<std::size_t>(best);
    const std::int32_t* corners = indices + 3 * t;
    ordered.insert(ordered.end(), corners, corners + 3);
    drawn[t] = 1;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(corners[k]);
      std::int32_t* begin = trianglesOf.data() + first[v];
      std::int32_t* end = begin + left[v];
      std::int32_t* at = std::find(begin, end, static_cast<std::int32_t>(t));
      assert(at != end);
      std::swap(*at, *(end - 1));
      --left[v];
    }

    // Least recently used: this triangle's vertices first, then the rest of the cache. Entries
    // past kCacheSize have just fallen out; they stay in the list for the score update only.
    nextCache.clear();
    for (int k = 0; k < 3; ++k)
      if (std::find(nextCache.begin(), nextCache.end(), corners[k]) == nextCache.end())
        nextCache.push_back(corners[k]);
    for (std::int32_t v : cache)
      if (v != corners[0] && v != corners[1] && v != corners[2]) nextCache.push_back(v);
    for (std::size_t i = 0; i < nextCache.size(); ++i) {
      const auto v = static_cast<std::size_t>(nextCache[i]);
      cachePosition[v] = i < kCacheSize ? static_cast<int>(i) : -1;
      const float updated = vertexScore(cachePosition[v], left[v]);
      const float change = updated - score[v];
      score[v] = updated;
      for (std::int32_t j = first[v]; j < first[v] + left[v]; ++j)
        triangleScore[static_cast<std::size_t>(trianglesOf[static_cast<std::size_t>(j)])] += change;
    }
    if (nextCache.size() > kCacheSize) nextCache.resize(kCacheSize);
    cache.swap(nextCache);

    // The next triangle: the best one that uses a cached vertex.
    best = -1;
    float bestScore = -std::numeric_limits<float>::infinity();
    for (std::int32_t v : cache) {
      const auto u = static_cast<std::size_t>(v);
      for (std::int32_t j = first[u]; j < first[u] + left[u]; ++j) {
        const std::int32_t candidate = trianglesOf[static_cast<std::size_t>(j)];
        if (triangleScore[static_cast<std::size_t>(candidate)] > bestScore) {
          bestScore = triangleScore[static_cast<std::size_t>(candidate)];
          best = candidate;
        }
      }
    }
  }
  return ordered;
}

}  // namespace sb::render
