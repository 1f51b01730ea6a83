// libFuzzer target: the scene parser on JSON text from memory (meshes resolve against the
// shipped assets/scenes folder; render-mesh binds go through a bind cache in a temporary folder
// so that they cost a file read after the first).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sim/scene/scene.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  static const std::string dir = "/tmp/softbody-fuzz-cache-" + std::to_string(::getpid());
  ::setenv("SOFTBODY_CACHE_DIR", dir.c_str(), 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    sb::Scene scene = sb::parseScene(text, "fuzz.json", SOFTBODY_ASSET_DIR "/scenes");
    (void)scene.world.stateHash();
  } catch (const sb::SceneError&) {
  }
  return 0;
}
