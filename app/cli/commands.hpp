// The subcommands of isoscope, one file each; main.cpp lists them in its
// table. Each add function puts its options on the subcommand that main
// made (with the command's name and description) and returns what runs the
// command once the line is parsed. `argv0` is for the commands that start Qt.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "app/cli/common.hpp"

namespace iso::cli {

RunFn add_info(CLI::App& cmd, char* argv0);    // info.cpp
RunFn add_mesh(CLI::App& cmd, char* argv0);    // mesh.cpp
RunFn add_render(CLI::App& cmd, char* argv0);  // render.cpp
RunFn add_view(CLI::App& cmd, char* argv0);    // windows.cpp
RunFn add_pick(CLI::App& cmd, char* argv0);    // pick.cpp
RunFn add_measure(CLI::App& cmd, char* argv0); // measure.cpp
RunFn add_gui(CLI::App& cmd, char* argv0);     // windows.cpp

// The desktop app (docs/gui.md), opening `input` if given (a session: .json).
int run_gui(const std::string& input, char* argv0);

} // namespace iso::cli
