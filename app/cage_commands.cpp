// TEMPORARY placeholder, replaced by the cage deformer work.
#include <cstdio>
#include "app/commands.h"
namespace sb::app {
int runBindCommand(int, char**) { std::fprintf(stderr, "bind: not built yet\n"); return 2; }
int runDeformCommand(int, char**) { std::fprintf(stderr, "deform: not built yet\n"); return 2; }
}  // namespace sb::app
