// Reads the current framebuffer back and writes it as a PNG (stb_image_write).
#pragma once

#include <string>

namespace sb::render {

// Captures the width × height pixels of the default (back) framebuffer as RGB, flips them so
// the first row is the top of the image, and writes a PNG. Returns false with *error set when
// the file cannot be written.
bool captureFramebufferToPng(int width, int height, const std::string& path, std::string* error);

}  // namespace sb::render
