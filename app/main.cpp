// softbody: the viewer (default), and the headless commands run, bind, deform, cage and ffd.
#include <cstdio>
#include <cstring>
#include <string>

#include "app/commands.h"

namespace {

void printUsage() {
  std::printf(
      "usage:\n"
      "  softbody [SCENE] [viewer options]     open the viewer (default scene when none given)\n"
      "  softbody run SCENE --steps N [...]    step a scene headless, export frames, timings\n"
      "  softbody bind --mesh M --cage C [...] bind a mesh to a cage (mvc, harmonic or rbf)\n"
      "  softbody deform --mesh M --cage C --deformed-cage C2 --out OUT.obj\n"
      "  softbody cage --mesh M --out C [...]   make a cage that encloses a mesh\n"
      "  softbody ffd --mesh M --nodes L,M,N [...] deform a mesh with an FFD lattice\n"
      "Run 'softbody COMMAND --help' for the options of a command.\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2) {
    const std::string first = argv[1];
    if (first == "run") return sb::app::runHeadlessCommand(argc - 1, argv + 1);
    if (first == "bind") return sb::app::runBindCommand(argc - 1, argv + 1);
    if (first == "deform") return sb::app::runDeformCommand(argc - 1, argv + 1);
    if (first == "cage") return sb::app::runCageCommand(argc - 1, argv + 1);
    if (first == "ffd") return sb::app::runFfdCommand(argc - 1, argv + 1);
    if (first == "help" || first == "-h" || first == "--help") {
      printUsage();
      return 0;
    }
  }
  return sb::app::runViewerCommand(argc, argv);
}
