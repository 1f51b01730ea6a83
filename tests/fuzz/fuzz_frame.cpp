// libFuzzer target: the frame reader (binary when the bytes start with SBFRAME1, else OBJ).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sim/scene/frame_export.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const bool binary = bytes.compare(0, 8, "SBFRAME1") == 0;
  try {
    const sb::Frame f =
        sb::parseFrame(bytes, binary ? sb::FrameFormat::Binary : sb::FrameFormat::Obj, "fuzz");
    for (const sb::FrameBody& b : f.bodies) {
      if (!b.positions.allFinite()) std::abort();
      for (const auto& t : b.triangles)
        for (int i : t)
          if (i < 0 || i >= b.positions.rows()) std::abort();
    }
  } catch (const sb::FrameError&) {
  }
  return 0;
}
