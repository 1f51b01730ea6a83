// Draws MeshBuffers with smooth Blinn-Phong shading from a headlight plus a fixed key light,
// one flat colour per draw call. Two-sided lighting, so inverted faces still read as surfaces.
#pragma once

#include <glm/glm.hpp>

#include "render/mesh_buffer.h"
#include "render/shader.h"

namespace sb::render {

class MeshRenderer {
 public:
  MeshRenderer();  // needs a current GL context

  // Sets the camera for the following draw() calls.
  void begin(const glm::mat4& view, const glm::mat4& projection, const glm::vec3& eye);
  // colour.a < 1 draws blended (no depth writes).
  void draw(const MeshBuffer& mesh, const glm::vec4& colour, bool wireframe = false);

 private:
  ShaderProgram shader_;
};

}  // namespace sb::render
