#include "render/capture.h"

#include <cstddef>
#include <cstring>
#include <vector>

#include <stb_image_write.h>

#include "render/gl.h"

namespace sb::render {

bool captureFramebufferToPng(int width, int height, const std::string& path, std::string* error) {
  if (width <= 0 || height <= 0) {
    if (error) *error = "empty framebuffer";
    return false;
  }
  const std::size_t rowBytes = static_cast<std::size_t>(width) * 3;
  std::vector<unsigned char> pixels(rowBytes * static_cast<std::size_t>(height));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
  // OpenGL's first row is the bottom one; PNG's is the top one.
  std::vector<unsigned char> row(rowBytes);
  for (int y = 0; y < height / 2; ++y) {
    unsigned char* a = pixels.data() + static_cast<std::size_t>(y) * rowBytes;
    unsigned char* b = pixels.data() + static_cast<std::size_t>(height - 1 - y) * rowBytes;
    std::memcpy(row.data(), a, rowBytes);
    std::memcpy(a, b, rowBytes);
    std::memcpy(b, row.data(), rowBytes);
  }
  if (!stbi_write_png(path.c_str(), width, height, 3, pixels.data(), static_cast<int>(rowBytes))) {
    if (error) *error = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace sb::render
