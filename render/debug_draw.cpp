#include "render/debug_draw.h"

#include <cstddef>

namespace sb::render {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec4 aColour;
uniform mat4 uViewProjection;
uniform float uPointSize;
out vec4 vColour;
void main() {
  gl_Position = uViewProjection * vec4(aPosition, 1.0);
  gl_PointSize = uPointSize;
  vColour = aColour;
}
)";

const char* kFragment = R"(#version 330 core
in vec4 vColour;
out vec4 fragColour;
void main() { fragColour = vColour; }
)";

}  // namespace

DebugDraw::DebugDraw() : shader_(kVertex, kFragment) {
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<const void*>(offsetof(Vertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<const void*>(offsetof(Vertex, colour)));
  glBindVertexArray(0);
}

DebugDraw::~DebugDraw() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
}

void DebugDraw::point(const glm::vec3& p, const glm::vec4& colour) {
  points_.push_back({p, colour});
}

void DebugDraw::line(const glm::vec3& a, const glm::vec3& b, const glm::vec4& colour) {
  lines_.push_back({a, colour});
  lines_.push_back({b, colour});
}

void DebugDraw::upload(const std::vector<Vertex>& vertices) {
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)),
               vertices.data(), GL_STREAM_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void DebugDraw::flush(const glm::mat4& viewProjection, float pointSize, bool depthTest) {
  if (empty()) return;
  shader_.use();
  shader_.set("uViewProjection", viewProjection);
  shader_.set("uPointSize", pointSize);
  if (depthTest)
    glEnable(GL_DEPTH_TEST);
  else
    glDisable(GL_DEPTH_TEST);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glBindVertexArray(vao_);
  if (!lines_.empty()) {
    upload(lines_);
    glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(lines_.size()));
  }
  if (!points_.empty()) {
    upload(points_);
    glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(points_.size()));
  }
  glBindVertexArray(0);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  points_.clear();
  lines_.clear();
}

}  // namespace sb::render
