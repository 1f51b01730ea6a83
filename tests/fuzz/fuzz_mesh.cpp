// libFuzzer target: one mesh reader (SOFTBODY_FUZZ_FORMAT = Obj, Off, Ply or Stl; both
// encodings of the format come through the same entry), parsing bytes from memory. What parses
// must be a consistent mesh; it then goes through closed-surface validation as a cage would.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sb::mesh;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  TriangleMesh m;
  try {
    m = parseMesh(bytes, MeshFormat::SOFTBODY_FUZZ_FORMAT, "fuzz");
  } catch (const MeshError&) {
    return 0;
  }
  for (const auto& t : m.triangles)
    for (int i : t)
      if (i < 0 || std::size_t(i) >= m.vertices.size()) std::abort();
  for (const auto& v : m.vertices)
    if (!v.allFinite()) std::abort();
  try {
    validateClosedSurface(m, "fuzz");
  } catch (const SurfaceError&) {
  }
  return 0;
}
