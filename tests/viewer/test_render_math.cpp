// Unit tests of the render library's math (no GL context needed): ray/triangle picking, the
// orbit camera's rays and projection, smooth normals, the cache-friendly triangle order.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "render/orbit_camera.h"
#include "render/picking.h"
#include "render/triangle_order.h"

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

// An n×n grid of quads, two triangles each, counter-clockwise seen from +z.
std::vector<std::int32_t> gridTriangles(int n) {
  std::vector<std::int32_t> indices;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const std::int32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      indices.insert(indices.end(), {a, b, d, a, d, c});
    }
  return indices;
}

std::vector<std::int32_t> shuffledTriangles(std::vector<std::int32_t> indices, unsigned seed) {
  std::mt19937 random(seed);
  const std::size_t count = indices.size() / 3;
  for (std::size_t i = count - 1; i > 0; --i) {  // Fisher–Yates on whole triangles
    const std::size_t j = random() % (i + 1);
    for (int k = 0; k < 3; ++k) std::swap(indices[3 * i + k], indices[3 * j + k]);
  }
  return indices;
}

// Each triangle rotated to start at its smallest index (a rotation keeps the winding), sorted.
std::vector<std::array<std::int32_t, 3>> canonicalTriangles(const std::vector<std::int32_t>& in) {
  std::vector<std::array<std::int32_t, 3>> out;
  for (std::size_t t = 0; 3 * t < in.size(); ++t) {
    std::array<std::int32_t, 3> tri{in[3 * t], in[3 * t + 1], in[3 * t + 2]};
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Vertices shaded per triangle with a first-in-first-out cache of `size` vertices: another cache
// model than the least-recently-used one the order is built for.
double verticesShadedPerTriangle(const std::vector<std::int32_t>& indices, std::size_t size) {
  std::deque<std::int32_t> cache;
  std::size_t shaded = 0;
  for (std::int32_t v : indices) {
    if (std::find(cache.begin(), cache.end(), v) != cache.end()) continue;
    ++shaded;
    cache.push_back(v);
    if (cache.size() > size) cache.pop_front();
  }
  return static_cast<double>(shaded) / static_cast<double>(indices.size() / 3);
}

TEST(TriangleOrder, KeepsEveryTriangleWithItsWinding) {
  const std::vector<std::int32_t> mesh = shuffledTriangles(gridTriangles(30), 7);
  const std::vector<std::int32_t> ordered =
      cacheFriendlyTriangleOrder(mesh.data(), mesh.size() / 3);
  ASSERT_EQ(ordered.size(), mesh.size());
  EXPECT_EQ(canonicalTriangles(ordered), canonicalTriangles(mesh));
  EXPECT_NE(ordered, mesh);
}

TEST(TriangleOrder, ShadesAGridVertexAboutOnce) {
  // A grid of n² quads has (n + 1)² vertices for 2n² triangles: at best ~0.5 shaded per triangle.
  const std::vector<std::int32_t> mesh = shuffledTriangles(gridTriangles(40), 11);
  const double before = verticesShadedPerTriangle(mesh, 32);
  const std::vector<std::int32_t> ordered =
      cacheFriendlyTriangleOrder(mesh.data(), mesh.size() / 3);
  const double after = verticesShadedPerTriangle(ordered, 32);
  EXPECT_GT(before, 2.5);  // shuffled: nearly every corner is a new vertex
  EXPECT_LT(after, 0.75);
  // Already in rows: reordering does not make it worse.
  const std::vector<std::int32_t> rows = gridTriangles(40);
  const std::vector<std::int32_t> fromRows =
      cacheFriendlyTriangleOrder(rows.data(), rows.size() / 3);
  EXPECT_LE(verticesShadedPerTriangle(fromRows, 32), verticesShadedPerTriangle(rows, 32));
}

TEST(TriangleOrder, EmptyDegenerateAndLoneTriangles) {
  EXPECT_TRUE(cacheFriendlyTriangleOrder(nullptr, 0).empty());
  // A triangle with a repeated vertex, lone triangles and unused vertex numbers are all kept.
  const std::vector<std::int32_t> soup{5, 5, 6, 0, 1, 2, 9, 8, 7, 3, 4, 3, 12, 10, 11};
  const std::vector<std::int32_t> ordered = cacheFriendlyTriangleOrder(soup.data(), 5);
  EXPECT_EQ(canonicalTriangles(ordered), canonicalTriangles(soup));
}

}  // namespace
}  // namespace sb::render
