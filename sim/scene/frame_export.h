// Writing simulated frames to disk for batch runs, and reading them back (tests, tools).
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

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

// How writeRenderMeshesObj groups the bodies.
enum class ObjObjects {
  // "o NAME" per body: a DCC tool imports one object per body (OBJ sequences).
  PerBody,
  // One object "softbody" with a group "g NAME" per body: the single mesh whose vertices, in
  // this order, a combined point cache moves (sim/scene/point_cache.h).
  One,
};

// Writes render meshes as Wavefront OBJ: meshes[i] holds body i's vertices (one entry per scene
// body, in order, as SceneRunner::renderMeshes gives them), faced with Scene::renderTriangles(i).
// Vertices in body order, unchanged within each body, in metres, each coordinate as the
// shortest decimal that reads back as the same float32. Atomic; throws FileError naming the
// path, std::invalid_argument when meshes does not match the scene.
void writeRenderMeshesObj(const Scene& scene, const std::vector<PointsRowMajor>& meshes,
                          const std::string& path, ObjObjects objects);

// A frame read back: per body its name (OBJ only; "" in binary frames), positions and faces
// (OBJ only; indices within the body, 0-based).
struct FrameBody {
  std::string name;
  PointsRowMajor positions;
  std::vector<std::array<int, 3>> triangles;
};
struct Frame {
  double time = 0;  // s
  std::vector<FrameBody> bodies;
};

class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Largest frame file read: 256 MB (a frame of the large scene is about 100 KB binary).
inline constexpr std::uint64_t kMaxFrameFileBytes = 256ull * 1000 * 1000;

// Reads a frame file written by writeFrame: a regular file of at most kMaxFrameFileBytes,
// binary when it starts with "SBFRAME1", else OBJ. Throws FrameError naming the path and
// reason; a body that does not match its header (counts, truncation, extra bytes), a face
// index outside its object or a non-finite position is refused. Reads writeRenderMeshesObj's
// files too ("g" lines are skipped: ObjObjects::One gives one body).
Frame readFrame(const std::string& path);
// The same on bytes in memory (`name` in messages); bounded by bytes.size() whatever they say.
Frame parseFrame(const std::string& bytes, FrameFormat format, const std::string& name);

}  // namespace sb
