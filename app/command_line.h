// Argument handling shared by the mesh sub-commands (bind, deform, cage, ffd; CLI11).
#pragma once

#include <CLI/CLI.hpp>

namespace sb::app {

// Parses argv with app (named after the command). Returns -1 to go on, else the exit code: 0
// after printing --help to stdout, 2 after printing the error and where to find the usage to
// stderr ("ffd: … \nRun 'softbody ffd --help' for usage.").
int parseArguments(CLI::App& app, int argc, char** argv);

}  // namespace sb::app
