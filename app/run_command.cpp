// TEMPORARY: replaced by the headless run command shortly.
#include <cstdio>
#include "app/commands.h"
namespace sb::app {
int runHeadlessCommand(int, char**) { std::fprintf(stderr, "run: not built yet\n"); return 2; }
}  // namespace sb::app
