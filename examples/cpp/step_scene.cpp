// Steps a scene file with the installed library and prints what `softbody run` prints last: the
// bodies' centres and the state hash.   step_scene SCENE STEPS
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "sim/scene/scene.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: step_scene SCENE STEPS\n");
    return 2;
  }
  try {
    sb::Scene scene = sb::loadScene(argv[1]);
    const int steps = std::atoi(argv[2]);
    for (int s = 0; s < steps; ++s) scene.world.step();
    for (const sb::SceneBody& b : scene.bodies) {
      const sb::Vec3 c = scene.world.centreOfMass(b.handle);
      std::printf("body '%s': centre of mass (%.4f, %.4f, %.4f) m\n",
                  scene.world.name(b.handle).c_str(), c.x(), c.y(), c.z());
    }
    std::printf("state hash %016llx\n", static_cast<unsigned long long>(scene.world.stateHash()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "step_scene: %s\n", e.what());
    return 1;
  }
  return 0;
}
