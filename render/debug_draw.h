// Immediate-style debug drawing: queue coloured points and line segments during a frame, then
// flush them in two draw calls. Used for particles, cage wireframes, clusters, goals, the drag.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "render/gl.h"
#include "render/shader.h"

namespace sb::render {

class DebugDraw {
 public:
  DebugDraw();  // needs a current GL context
  ~DebugDraw();
  DebugDraw(const DebugDraw&) = delete;
  DebugDraw& operator=(const DebugDraw&) = delete;

  void point(const glm::vec3& p, const glm::vec4& colour);
  void line(const glm::vec3& a, const glm::vec3& b, const glm::vec4& colour);
  // Draws everything queued (lines first, then points of pointSize pixels) and clears the queue.
  // With depthTest false the primitives are drawn over the scene.
  void flush(const glm::mat4& viewProjection, float pointSize, bool depthTest);
  bool empty() const { return points_.empty() && lines_.empty(); }

 private:
  struct Vertex {
    glm::vec3 position;
    glm::vec4 colour;
  };
  void upload(const std::vector<Vertex>& vertices);
  std::vector<Vertex> points_, lines_;
  ShaderProgram shader_;
  GLuint vao_ = 0, vbo_ = 0;
};

}  // namespace sb::render
