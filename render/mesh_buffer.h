// GPU buffers of one triangle mesh whose vertices move every frame: positions and normals in
// dynamic vertex buffers (attribute 0 and 1, 3 floats each), indices in a static element buffer.
#pragma once

#include <cstddef>
#include <cstdint>

#include "render/gl.h"

namespace sb::render {

class MeshBuffer {
 public:
  MeshBuffer();
  ~MeshBuffer();
  MeshBuffer(MeshBuffer&& other) noexcept;
  MeshBuffer& operator=(MeshBuffer&& other) noexcept;
  MeshBuffer(const MeshBuffer&) = delete;
  MeshBuffer& operator=(const MeshBuffer&) = delete;

  // Triangle indices, 3 per triangle (#T×3 row-major ints). Call when the topology changes. The
  // triangles are drawn in another order (cacheFriendlyTriangleOrder), each with its winding.
  void setIndices(const std::int32_t* indices, std::size_t triangleCount);
  // Vertex positions and normals, #V×3 row-major floats each. Call every frame.
  void setVertices(const float* positions, const float* normals, std::size_t vertexCount);

  void draw() const;  // binds the VAO and draws all triangles
  std::size_t triangleCount() const { return triangleCount_; }
  std::size_t vertexCount() const { return vertexCount_; }

 private:
  void release();
  GLuint vao_ = 0, positions_ = 0, normals_ = 0, indices_ = 0;
  std::size_t triangleCount_ = 0, vertexCount_ = 0, capacity_ = 0;
};

}  // namespace sb::render
