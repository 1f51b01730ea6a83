#include "render/picking.h"

#include <cmath>
#include <limits>

namespace sb::render {

bool intersectRayTriangle(const Ray& ray, const glm::vec3& a, const glm::vec3& b,
                          const glm::vec3& c, float* t, float* u, float* v) {
  const glm::vec3 e1 = b - a, e2 = c - a;
  const glm::vec3 p = glm::cross(ray.direction, e2);
  const float det = glm::dot(e1, p);
  // Relative test: a parallel ray gives det ≈ 0 compared with the triangle's own scale
  // |e1| |e2| (squared on both sides: no square roots in the loop over a mesh's triangles).
  if (!(det * det > 1e-14f * glm::dot(e1, e1) * glm::dot(e2, e2))) return false;
  const float inv = 1.0f / det;
  const glm::vec3 s = ray.origin - a;
  const float uu = glm::dot(s, p) * inv;
  if (uu < 0.0f || uu > 1.0f) return false;
  const glm::vec3 q = glm::cross(s, e1);
  const float vv = glm::dot(ray.direction, q) * inv;
  if (vv < 0.0f || uu + vv > 1.0f) return false;
  const float tt = glm::dot(e2, q) * inv;
  if (tt < 0.0f) return false;
  *t = tt;
  *u = uu;
  *v = vv;
  return true;
}

TriangleHit pickTriangles(const Ray& ray, const float* positions, std::size_t vertexCount,
                          const std::int32_t* triangles, std::size_t triangleCount) {
  TriangleHit best;
  best.distance = std::numeric_limits<float>::infinity();
  auto vertex = [&](std::int32_t i) {
    return glm::vec3(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
  };
  for (std::size_t k = 0; k < triangleCount; ++k) {
    const std::int32_t* tri = triangles + 3 * k;
    if (tri[0] < 0 || tri[1] < 0 || tri[2] < 0 || static_cast<std::size_t>(tri[0]) >= vertexCount ||
        static_cast<std::size_t>(tri[1]) >= vertexCount ||
        static_cast<std::size_t>(tri[2]) >= vertexCount)
      continue;
    float t = 0, u = 0, v = 0;
    if (intersectRayTriangle(ray, vertex(tri[0]), vertex(tri[1]), vertex(tri[2]), &t, &u, &v) &&
        t < best.distance) {
      best.hit = true;
      best.triangle = static_cast<int>(k);
      best.distance = t;
      best.barycentric = glm::vec3(1.0f - u - v, u, v);
    }
  }
  if (best.hit) best.point = ray.origin + best.distance * ray.direction;
  return best;
}

int nearestPointToRay(const Ray& ray, const float* positions, std::size_t count,
                      float* distanceToRay) {
  int best = -1;
  float bestDistance = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 p(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
    const glm::vec3 d = p - ray.origin;
    const float along = glm::dot(d, ray.direction);
    if (along <= 0.0f) continue;
    const float perpendicular = glm::length(d - along * ray.direction);
    if (perpendicular < bestDistance) {
      bestDistance = perpendicular;
      best = static_cast<int>(i);
    }
  }
  if (distanceToRay) *distanceToRay = bestDistance;
  return best;
}

bool intersectRayPlane(const Ray& ray, const glm::vec3& planePoint, const glm::vec3& planeNormal,
                       glm::vec3* hit) {
  const float denom = glm::dot(ray.direction, planeNormal);
  if (std::fabs(denom) < 1e-8f) return false;
  const float t = glm::dot(planePoint - ray.origin, planeNormal) / denom;
  if (t < 0.0f) return false;
  *hit = ray.origin + t * ray.direction;
  return true;
}

}  // namespace sb::render
