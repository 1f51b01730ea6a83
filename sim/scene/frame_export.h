// Writing simulated frames to disk for batch runs.
#pragma once

#include <string>

#include "sim/scene/scene.h"

namespace sb {

enum class FrameFormat {
  // Wavefront OBJ: one object ("o NAME") per body, its particles as vertices and, when the
  // particle mesh has faces, those faces. Positions in metres, 9 significant digits.
  Obj,
  // Little-endian binary: "SBFRAME1" (8 bytes), uint32 body count, float64 time (s); then per
  // body: uint32 particle count, particle positions as float32 x, y, z triples (metres).
  Binary,
};

// Writes the scene's current particle positions to `path`. Atomic (sim/base/file_io.h);
// throws FileError (a std::runtime_error) naming the path on failure.
void writeFrame(const Scene& scene, const std::string& path, FrameFormat format);

}  // namespace sb
