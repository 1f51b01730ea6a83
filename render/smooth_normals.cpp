#include "render/smooth_normals.h"

#include <algorithm>
#include <cmath>

namespace sb::render {

void computeSmoothNormals(const float* positions, std::size_t vertexCount,
                          const std::int32_t* triangles, std::size_t triangleCount,
                          float* normals) {
  std::fill(normals, normals + 3 * vertexCount, 0.0f);
  for (std::size_t k = 0; k < triangleCount; ++k) {
    const std::int32_t* t = triangles + 3 * k;
    if (t[0] < 0 || t[1] < 0 || t[2] < 0) continue;
    if (static_cast<std::size_t>(std::max({t[0], t[1], t[2]})) >= vertexCount) continue;
    const float* a = positions + 3 * t[0];
    const float* b = positions + 3 * t[1];
    const float* c = positions + 3 * t[2];
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    // The cross product's length is twice the area: area weighting comes for free.
    const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
    for (int corner = 0; corner < 3; ++corner) {
      float* out = normals + 3 * t[corner];
      out[0] += n[0];
      out[1] += n[1];
      out[2] += n[2];
    }
  }
  for (std::size_t i = 0; i < vertexCount; ++i) {
    float* n = normals + 3 * i;
    const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length > 0.0f && std::isfinite(length)) {
      n[0] /= length;
      n[1] /= length;
      n[2] /= length;
    } else {
      n[0] = 0.0f;
      n[1] = 1.0f;
      n[2] = 0.0f;
    }
  }
}

}  // namespace sb::render
