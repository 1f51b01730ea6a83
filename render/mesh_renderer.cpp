#include "render/mesh_renderer.h"

namespace sb::render {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
uniform mat4 uView;
uniform mat4 uProjection;
out vec3 vWorld;
out vec3 vNormal;
void main() {
  vWorld = aPosition;
  vNormal = aNormal;
  gl_Position = uProjection * uView * vec4(aPosition, 1.0);
}
)";

const char* kFragment = R"(#version 330 core
in vec3 vWorld;
in vec3 vNormal;
uniform vec3 uEye;
uniform vec4 uColour;
out vec4 fragColour;
void main() {
  vec3 n = normalize(vNormal);
  vec3 v = normalize(uEye - vWorld);
  if (dot(n, v) < 0.0) n = -n;  // two-sided
  vec3 key = normalize(vec3(0.4, 1.0, 0.3));
  float diffuse = 0.55 * max(dot(n, key), 0.0) + 0.35 * max(dot(n, v), 0.0);
  vec3 h = normalize(key + v);
  // x^48 by five squarings and a product: llvmpipe evaluates pow() as exp2(48 log2 x), several
  // times the instructions.
  float s2 = max(dot(n, h), 0.0);
  s2 *= s2;
  float s4 = s2 * s2, s16 = s4 * s4;
  s16 *= s16;
  float s32 = s16 * s16;
  float specular = 0.25 * s32 * s16;
  float hemi = 0.5 + 0.5 * n.y;  // sky/ground ambient
  vec3 colour = uColour.rgb * (0.18 + 0.12 * hemi + diffuse) + vec3(specular);
  fragColour = vec4(colour, uColour.a);
}
)";

}  // namespace

MeshRenderer::MeshRenderer() : shader_(kVertex, kFragment) {}

void MeshRenderer::begin(const glm::mat4& view, const glm::mat4& projection, const glm::vec3& eye) {
  shader_.use();
  shader_.set("uView", view);
  shader_.set("uProjection", projection);
  shader_.set("uEye", eye);
}

void MeshRenderer::draw(const MeshBuffer& mesh, const glm::vec4& colour, bool wireframe) {
  shader_.use();
  shader_.set("uColour", colour);
  const bool blended = colour.a < 1.0f;
  if (blended) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
  }
  if (wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  mesh.draw();
  if (wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  if (blended) {
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }
}

}  // namespace sb::render
