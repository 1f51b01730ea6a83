#include "render/ground_renderer.h"

namespace sb::render {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec2 aCorner;
uniform mat4 uViewProjection;
uniform float uHeight;
uniform float uExtent;
out vec3 vWorld;
void main() {
  vWorld = vec3(aCorner.x * uExtent, uHeight, aCorner.y * uExtent);
  gl_Position = uViewProjection * vec4(vWorld, 1.0);
}
)";

const char* kFragment = R"(#version 330 core
in vec3 vWorld;
uniform float uCell;
uniform vec3 uEye;
uniform float uExtent;
out vec4 fragColour;
void main() {
  vec2 cell = floor(vWorld.xz / uCell);
  float checker = mod(cell.x + cell.y, 2.0);
  vec3 colour = mix(vec3(0.36, 0.38, 0.42), vec3(0.46, 0.48, 0.52), checker);
  float fade = clamp(length(vWorld.xz - uEye.xz) / (0.9 * uExtent), 0.0, 1.0);
  vec3 background = vec3(0.16, 0.17, 0.20);
  fragColour = vec4(mix(colour, background, fade * fade), 1.0);
}
)";

}  // namespace

GroundRenderer::GroundRenderer() : shader_(kVertex, kFragment) {
  const float corners[] = {-1, -1, 1, -1, 1, 1, -1, -1, 1, 1, -1, 1};
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
  glBindVertexArray(0);
}

GroundRenderer::~GroundRenderer() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
}

void GroundRenderer::draw(const glm::mat4& viewProjection, const glm::vec3& eye, float height,
                          float cellSize, float extent) {
  shader_.use();
  shader_.set("uViewProjection", viewProjection);
  shader_.set("uHeight", height);
  shader_.set("uCell", cellSize);
  shader_.set("uEye", eye);
  shader_.set("uExtent", extent);
  // Drawn first and behind everything (the ground is a collider: nothing goes below it), so no
  // depth test or depth writes: on llvmpipe that saves a depth read and write per pixel.
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, 6);
  glBindVertexArray(0);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
}

}  // namespace sb::render
