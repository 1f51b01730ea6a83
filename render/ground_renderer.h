// A large checkerboard ground plane (y = height), drawn as one quad whose fragment shader
// computes the checker and fades it out with distance. Draw it first: it does not touch the
// depth buffer, so everything drawn afterwards appears in front of it.
#pragma once

#include <glm/glm.hpp>

#include "render/gl.h"
#include "render/shader.h"

namespace sb::render {

class GroundRenderer {
 public:
  GroundRenderer();  // needs a current GL context
  ~GroundRenderer();
  GroundRenderer(const GroundRenderer&) = delete;
  GroundRenderer& operator=(const GroundRenderer&) = delete;

  // cellSize: checker square edge in metres; extent: half size of the quad in metres.
  void draw(const glm::mat4& viewProjection, const glm::vec3& eye, float height, float cellSize,
            float extent);

 private:
  ShaderProgram shader_;
  GLuint vao_ = 0, vbo_ = 0;
};

}  // namespace sb::render
