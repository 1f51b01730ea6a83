// Unit tests of the render library's math (no GL context needed): ray/triangle picking, the
// orbit camera's rays and projection, smooth normals.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "render/orbit_camera.h"
#include "render/picking.h"

namespace sb::render {
namespace {

TEST(Picking, RayHitsTriangleWithBarycentricWeights) {
  const glm::vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  Ray ray;
  ray.origin = glm::vec3(0.25f, 0.5f, 2.0f);
  ray.direction = glm::vec3(0, 0, -1);
  float t = 0, u = 0, v = 0;
  ASSERT_TRUE(intersectRayTriangle(ray, a, b, c, &t, &u, &v));
  EXPECT_NEAR(t, 2.0f, 1e-6f);
  // The hit point equals the barycentric blend of the corners.
  const glm::vec3 blend = (1 - u - v) * a + u * b + v * c;
  EXPECT_NEAR(blend.x, 0.25f, 1e-6f);
  EXPECT_NEAR(blend.y, 0.5f, 1e-6f);
  // Two-sided: the same ray from below hits too.
  ray.origin.z = -2.0f;
  ray.direction = glm::vec3(0, 0, 1);
  EXPECT_TRUE(intersectRayTriangle(ray, a, b, c, &t, &u, &v));
}

TEST(Picking, MissesOutsideBehindAndParallel) {
  const glm::vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  float t, u, v;
  Ray outside{glm::vec3(0.8f, 0.8f, 1.0f), glm::vec3(0, 0, -1)};
  EXPECT_FALSE(intersectRayTriangle(outside, a, b, c, &t, &u, &v));
  Ray behind{glm::vec3(0.2f, 0.2f, -1.0f), glm::vec3(0, 0, -1)};
  EXPECT_FALSE(intersectRayTriangle(behind, a, b, c, &t, &u, &v));
  Ray parallel{glm::vec3(0.2f, 0.2f, 0.0f), glm::vec3(1, 0, 0)};
  EXPECT_FALSE(intersectRayTriangle(parallel, a, b, c, &t, &u, &v));
}

TEST(Picking, ScaleInvariant) {
  // The same configuration scaled by 1e-4 and 1e4 gives the same answer.
  for (float s : {1e-4f, 1.0f, 1e4f}) {
    const glm::vec3 a(0, 0, 0), b(s, 0, 0), c(0, s, 0);
    Ray ray{glm::vec3(0.3f * s, 0.3f * s, s), glm::vec3(0, 0, -1)};
    float t, u, v;
    ASSERT_TRUE(intersectRayTriangle(ray, a, b, c, &t, &u, &v)) << "scale " << s;
    EXPECT_NEAR(u, 0.3f, 1e-5f);
    EXPECT_NEAR(v, 0.3f, 1e-5f);
  }
}

TEST(Picking, NearestTriangleOfAMesh) {
  // Two parallel squares at z = 0 and z = 1, each two triangles; a ray from z = 5 down.
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                                        0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  const std::vector<std::int32_t> triangles = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  Ray ray{glm::vec3(0.7f, 0.2f, 5.0f), glm::vec3(0, 0, -1)};
  const TriangleHit hit = pickTriangles(ray, positions.data(), 8, triangles.data(), 4);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.triangle, 2);
  EXPECT_NEAR(hit.distance, 4.0f, 1e-5f);
  EXPECT_NEAR(hit.point.z, 1.0f, 1e-5f);
  EXPECT_NEAR(hit.barycentric.x + hit.barycentric.y + hit.barycentric.z, 1.0f, 1e-6f);
  Ray miss{glm::vec3(2.0f, 2.0f, 5.0f), glm::vec3(0, 0, -1)};
  EXPECT_FALSE(pickTriangles(miss, positions.data(), 8, triangles.data(), 4).hit);
}

TEST(Picking, NearestPointAndPlane) {
  const std::vector<float> points = {0, 0, -5, 0.5f, 0, -5, 0, 0, 5};  // the last is behind
  Ray ray{glm::vec3(0.4f, 0, 0), glm::vec3(0, 0, -1)};
  float d = 0;
  EXPECT_EQ(nearestPointToRay(ray, points.data(), 3, &d), 1);
  EXPECT_NEAR(d, 0.1f, 1e-6f);
  glm::vec3 hit;
  ASSERT_TRUE(intersectRayPlane(ray, glm::vec3(0, 0, -3), glm::vec3(0, 0, 1), &hit));
  EXPECT_NEAR(hit.z, -3.0f, 1e-6f);
  EXPECT_FALSE(intersectRayPlane(ray, glm::vec3(0, 0, 3), glm::vec3(0, 0, 1), &hit));
}

TEST(OrbitCamera, RayThroughProjectedPixelPassesThroughPoint) {
  OrbitCamera camera;
  camera.target = glm::vec3(0.3f, 0.2f, -0.1f);
  camera.distance = 4.0f;
  camera.yaw = 0.7f;
  camera.pitch = 0.4f;
  const float w = 940, h = 720;
  for (const glm::vec3& p :
       {glm::vec3(0.3f, 0.2f, -0.1f), glm::vec3(1, 0, 0), glm::vec3(-0.5f, 0.8f, 0.6f)}) {
    glm::vec2 pixel;
    ASSERT_TRUE(camera.project(p, w, h, &pixel));
    const Ray ray = camera.rayThroughPixel(pixel.x, pixel.y, w, h);
    const glm::vec3 toPoint = p - ray.origin;
    const float along = glm::dot(toPoint, ray.direction);
    EXPECT_NEAR(glm::length(toPoint - along * ray.direction), 0.0f, 1e-4f);
  }
  // The target projects to the viewport centre.
  glm::vec2 centre;
  camera.project(camera.target, w, h, &centre);
  EXPECT_NEAR(centre.x, w / 2, 1e-3f);
  EXPECT_NEAR(centre.y, h / 2, 1e-3f);
  // Screen axes: right is +x in pixels, up is −y in pixels.
  glm::vec2 right, up;
  camera.project(camera.target + 0.1f * camera.right(), w, h, &right);
  camera.project(camera.target + 0.1f * camera.up(), w, h, &up);
  EXPECT_GT(right.x, centre.x);
  EXPECT_LT(up.y, centre.y);
}

TEST(OrbitCamera, PanKeepsDistanceAndFrameFitsBox) {
  OrbitCamera camera;
  const glm::vec3 eye0 = camera.eye();
  camera.pan(10.0f, 0.0f, 720.0f);
  EXPECT_NEAR(glm::length(camera.eye() - camera.target), camera.distance, 1e-4f);
  EXPECT_LT(glm::dot(camera.eye() - eye0, camera.right()), 0.0f);  // content follows the mouse
  camera.frame(glm::vec3(-1), glm::vec3(1));
  for (int corner = 0; corner < 8; ++corner) {
    const glm::vec3 p(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
    glm::vec2 pixel;
    ASSERT_TRUE(camera.project(p, 720, 720, &pixel));
    EXPECT_GE(pixel.x, 0.0f);
    EXPECT_LE(pixel.x, 720.0f);
    EXPECT_GE(pixel.y, 0.0f);
    EXPECT_LE(pixel.y, 720.0f);
  }
}

}  // namespace
}  // namespace sb::render
