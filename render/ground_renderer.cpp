#include "render/ground_renderer.h"

#include <algorithm>
#include <cmath>

namespace sb::render {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec2 aCorner;
uniform mat4 uViewProjection;
uniform float uHeight;
uniform float uExtent;
uniform float uCell;
out vec2 vCell;
void main() {
  vec3 world = vec3(aCorner.x * uExtent, uHeight, aCorner.y * uExtent);
  vCell = world.xz / uCell;  // linear in the plane: exact when interpolated
  gl_Position = uViewProjection * vec4(world, 1.0);
}
)";

// Kept to a few instructions per pixel: on llvmpipe the ground is most of the frame's shading.
const char* kFragment = R"(#version 330 core
in vec2 vCell;
uniform float uInvFadeDepth;
out vec4 fragColour;
void main() {
  vec2 cell = floor(vCell);
  float checker = fract(0.5 * (cell.x + cell.y)) * 2.0;  // 0 or 1
  vec3 colour = mix(vec3(0.36, 0.38, 0.42), vec3(0.46, 0.48, 0.52), checker);
  // Fade into the background with view depth (1 / gl_FragCoord.w), free per pixel.
  float fade = clamp(uInvFadeDepth / gl_FragCoord.w, 0.0, 1.0);
  fragColour = vec4(mix(colour, vec3(0.16, 0.17, 0.20), fade * fade), 1.0);
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
  shader_.set("uExtent", extent);
  // Fully faded at 90 % of the extent beyond the eye's distance to the plane's centre line.
  const float fadeDepth = 0.9f * extent + 0.5f * std::fabs(eye.y - height);
  shader_.set("uInvFadeDepth", 1.0f / std::max(fadeDepth, 1e-6f));
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
