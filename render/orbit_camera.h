// A camera orbiting a target point: yaw/pitch around the target at a distance, perspective
// projection. Screen coordinates are window pixels with the origin at the top left.
#pragma once

#include <glm/glm.hpp>

namespace sb::render {

struct Ray {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // unit length
};

class OrbitCamera {
 public:
  glm::vec3 target{0.0f};
  float distance = 5.0f;    // metres from target to eye, > 0
  float yaw = 0.6f;         // radians about +y; 0 looks along −z
  float pitch = 0.35f;      // radians above the horizontal, within (−π/2, π/2)
  float fovY = 0.8f;        // vertical field of view, radians
  float nearPlane = 0.02f;  // metres
  float farPlane = 500.0f;  // metres

  glm::vec3 eye() const;
  glm::vec3 forward() const;  // unit, from eye toward target
  glm::vec3 right() const;    // unit, screen +x in world space
  glm::vec3 up() const;       // unit, screen +y (upward) in world space
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;

  // Mouse motion in pixels → rotation / translation of the target in the view plane.
  void orbit(float dxPixels, float dyPixels);
  void pan(float dxPixels, float dyPixels, float viewportHeight);
  // Multiplies the distance by factor (> 0), clamped to a sensible range.
  void zoom(float factor);
  // Places the target at the box centre and the distance so the box fits the view.
  void frame(const glm::vec3& boxMin, const glm::vec3& boxMax);

  // The ray from the eye through pixel (x, y) of a width × height viewport.
  Ray rayThroughPixel(float x, float y, float width, float height) const;
  // Window pixel of a world point; returns false when it is behind the eye.
  bool project(const glm::vec3& point, float width, float height, glm::vec2* pixel) const;
  // The same for many points: viewProjection = projection(width / height) * view(), computed
  // once by the caller (project() recomputes both matrices for every point). Inline: callers
  // project every vertex of every drawn mesh with it (the --stats file's screen bounds).
  static bool projectWith(const glm::mat4& viewProjection, const glm::vec3& point, float width,
                          float height, glm::vec2* pixel) {
    const glm::vec4 clip = viewProjection * glm::vec4(point, 1.0f);
    if (clip.w <= 1e-6f) return false;
    const glm::vec3 ndc = glm::vec3(clip) / clip.w;
    *pixel = glm::vec2((ndc.x + 1.0f) * 0.5f * width, (1.0f - ndc.y) * 0.5f * height);
    return true;
  }
};

}  // namespace sb::render
