// A linked GLSL program (vertex + fragment), with uniform setters by name.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "render/gl.h"

namespace sb::render {

class ShaderProgram {
 public:
  ShaderProgram() = default;
  // Compiles and links; throws std::runtime_error with the GL info log on failure.
  ShaderProgram(const char* vertexSource, const char* fragmentSource);
  ~ShaderProgram();
  ShaderProgram(ShaderProgram&& other) noexcept;
  ShaderProgram& operator=(ShaderProgram&& other) noexcept;
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  void use() const;
  GLuint id() const { return program_; }
  void set(const char* name, const glm::mat4& value) const;
  void set(const char* name, const glm::vec3& value) const;
  void set(const char* name, const glm::vec4& value) const;
  void set(const char* name, float value) const;

 private:
  GLuint program_ = 0;
};

}  // namespace sb::render
