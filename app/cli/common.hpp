// What the commands of the isoscope command line share: the progress bar,
// the mapping of the core's setting names to flags in error messages, byte
// counts for people, and opening the input of `render`, `pick`, `measure`
// and `view` with its look.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/vec3.hpp>

#include "io/error.hpp"
#include "io/progress.hpp"
#include "renderer/core/scene.hpp"

namespace iso::cli {

// What runs a subcommand once the command line is parsed (its exit status).
using RunFn = std::function<int()>;

// "1.5 MiB".
std::string human_bytes(double b);

// A progress bar on stderr when it is a terminal; silent otherwise.
iso::ProgressFn progress_bar();

// The error as the command line says it: the core's setting or operation
// named by its flag.
std::string cli_message(const iso::Error& e);

// The same for an error's text "WHERE: reason" that reached us as text (an
// MPI rank's message).
std::string cli_text(const std::string& message);

// --memory MiB -> bytes (0: the core's default, a quarter of physical memory).
std::size_t memory_bytes_option(double mib);

// Prints each warning on stderr ("warning: PREFIX: text"; no prefix: "warning: text").
void print_warnings(const std::vector<std::string>& warnings, const std::string& prefix = "");

// How the surfaces of `render` and `view` look: per surface in the order of
// --iso (one each for a mesh), and the frame's background and shading.
struct Look {
    std::vector<double> opacity;
    std::vector<std::string> color;
    std::string background, shading = "lit";
};

void add_look_options(CLI::App* cmd, Look& l);

// A '#rrggbb' option's linear colour; a bad text names the flag.
glm::vec3 hex_option(const std::string& flag, const std::string& text);

// Opens the input of `render` and `view`: a mesh, or a volume and its
// isosurfaces (--iso required), and gives the surfaces their look.
void open_input(iso::core::Scene& scene, const std::string& input, const std::string& series,
                const std::vector<double>& isos, const Look& look, const std::string& command,
                bool volume_rendering = false);

} // namespace iso::cli
