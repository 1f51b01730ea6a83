// Entry points of the softbody sub-commands. Each parses its own arguments (argv[0] is the
// command name), prints errors to stderr and returns the process exit code.
#pragma once

namespace sb::app {

int runHeadlessCommand(int argc, char** argv);  // run_command.cpp
int runBindCommand(int argc, char** argv);      // cage_commands.cpp
int runDeformCommand(int argc, char** argv);    // cage_commands.cpp
int runCageCommand(int argc, char** argv);      // cage_commands.cpp
int runFfdCommand(int argc, char** argv);       // ffd_command.cpp
int runViewerCommand(int argc, char** argv);    // viewer_main.cpp (falls back to headless)

}  // namespace sb::app
