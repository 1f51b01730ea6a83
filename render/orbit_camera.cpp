#include "render/orbit_camera.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace sb::render {

glm::vec3 OrbitCamera::forward() const {
  const float cp = std::cos(pitch);
  // yaw = 0, pitch = 0: eye on +z looking toward −z.
  return -glm::vec3(cp * std::sin(yaw), std::sin(pitch), cp * std::cos(yaw));
}

glm::vec3 OrbitCamera::eye() const {
  return target - distance * forward();
}

glm::vec3 OrbitCamera::right() const {
  return glm::normalize(glm::cross(forward(), glm::vec3(0.0f, 1.0f, 0.0f)));
}

glm::vec3 OrbitCamera::up() const {
  return glm::cross(right(), forward());
}

glm::mat4 OrbitCamera::view() const {
  return glm::lookAt(eye(), target, up());
}

glm::mat4 OrbitCamera::projection(float aspect) const {
  return glm::perspective(fovY, std::max(aspect, 1e-3f), nearPlane, farPlane);
}

void OrbitCamera::orbit(float dxPixels, float dyPixels) {
  constexpr float kRadiansPerPixel = 0.006f;
  yaw -= dxPixels * kRadiansPerPixel;
  pitch += dyPixels * kRadiansPerPixel;
  pitch = std::clamp(pitch, -1.5f, 1.5f);
}

void OrbitCamera::pan(float dxPixels, float dyPixels, float viewportHeight) {
  // Metres per pixel at the target's depth, so the point under the cursor follows it.
  const float metresPerPixel =
      2.0f * distance * std::tan(0.5f * fovY) / std::max(viewportHeight, 1.0f);
  target += (-dxPixels * right() + dyPixels * up()) * metresPerPixel;
}

void OrbitCamera::zoom(float factor) {
  distance = std::clamp(distance * factor, 0.05f, 0.4f * farPlane);
}

void OrbitCamera::frame(const glm::vec3& boxMin, const glm::vec3& boxMax) {
  target = 0.5f * (boxMin + boxMax);
  const float radius = std::max(0.5f * glm::length(boxMax - boxMin), 0.05f);
  distance = std::clamp(radius / std::sin(0.5f * fovY) * 1.05f, 0.1f, 0.4f * farPlane);
}

Ray OrbitCamera::rayThroughPixel(float x, float y, float width, float height) const {
  const float ndcX = 2.0f * x / std::max(width, 1.0f) - 1.0f;
  const float ndcY = 1.0f - 2.0f * y / std::max(height, 1.0f);
  const float tanHalf = std::tan(0.5f * fovY);
  const float aspect = width / std::max(height, 1.0f);
  Ray ray;
  ray.origin = eye();
  ray.direction =
      glm::normalize(forward() + ndcX * tanHalf * aspect * right() + ndcY * tanHalf * up());
  return ray;
}

bool OrbitCamera::project(const glm::vec3& point, float width, float height,
                          glm::vec2* pixel) const {
  return projectWith(projection(width / std::max(height, 1.0f)) * view(), point, width, height,
                     pixel);
}

}  // namespace sb::render
