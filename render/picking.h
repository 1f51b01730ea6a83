// Ray picking against triangle meshes given as plain arrays (#V×3 row-major float positions,
// #T×3 int indices).
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "render/orbit_camera.h"

namespace sb::render {

struct TriangleHit {
  bool hit = false;
  int triangle = -1;            // index into the triangle list
  float distance = 0.0f;        // along the ray (the ray direction is unit length), metres
  glm::vec3 barycentric{0.0f};  // weights of the triangle's three corners, sum 1
  glm::vec3 point{0.0f};        // world position of the hit
};

// Möller–Trumbore ray/triangle test, two-sided. Returns true with the distance t ≥ 0 and the
// barycentric weights (u, v) of corners b and c (corner a gets 1 − u − v).
bool intersectRayTriangle(const Ray& ray, const glm::vec3& a, const glm::vec3& b,
                          const glm::vec3& c, float* t, float* u, float* v);

// The nearest hit of the ray against every triangle of the mesh (no hit: result.hit false).
TriangleHit pickTriangles(const Ray& ray, const float* positions, std::size_t vertexCount,
                          const std::int32_t* triangles, std::size_t triangleCount);

// Index of the point nearest to the ray (perpendicular distance, points in front of the eye
// only), or −1. *distanceToRay receives that distance.
int nearestPointToRay(const Ray& ray, const float* positions, std::size_t count,
                      float* distanceToRay);

// Where the ray meets the plane through planePoint with the given normal; false if parallel or
// behind the origin.
bool intersectRayPlane(const Ray& ray, const glm::vec3& planePoint, const glm::vec3& planeNormal,
                       glm::vec3* hit);

}  // namespace sb::render
