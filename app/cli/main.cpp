// isoscope command-line interface: the table of subcommands (one file each,
// commands.hpp) and the one place errors become messages and exit statuses.
// Parses arguments, calls the core API, prints; no algorithms live here.
#include <cstdlib>
#include <functional>
#include <iostream>
#include <string>
#include <unistd.h>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/cli/commands.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/versions.hpp"

namespace {

struct Command {
    const char* name;
    const char* description;
    iso::cli::RunFn (*add)(CLI::App& cmd, char* argv0);
};

const Command kCommands[] = {
    {"info", "Describe a volume: dimensions, type, spacing, range, index->LPS affine", iso::cli::add_info},
    {"mesh", "Extract isosurfaces (or label surfaces) and write them in LPS mm", iso::cli::add_mesh},
    {"render", "Render surfaces of a volume (or a mesh) to an annotated image", iso::cli::add_render},
    {"view", "Open a window showing the surfaces (mouse: orbit, pan, zoom; keys a p l r s i: views)",
     iso::cli::add_view},
    {"pick",
     "What is seen at a pixel of the image `render` writes with the same options: "
     "surface, LPS point, normal, value (HU for CT); every layer through translucent ones",
     iso::cli::add_pick},
    {"measure",
     "Measure surfaces (area, volume, closed/open, components, uncertainty) and points "
     "(distance, angle, value) in LPS mm",
     iso::cli::add_measure},
    {"gui", "Open the desktop app (main window with the 3D and slice views)", iso::cli::add_gui},
};

} // namespace

int main(int argc, char** argv) {
    // No arguments: the desktop app where there is a display, the help otherwise.
    if (argc == 1 && (std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY"))) return iso::cli::run_gui("", argv[0]);
    CLI::App app{"isoscope: inspect CT volumes, reconstruct and render isosurfaces"};
    // isoscope's version, then the libraries' it is built with (a bug report's
    // first lines). Asked for only on --version: OpenImageIO's loads the
    // image module (io/image_module.hpp), which every other command would
    // otherwise pay for at start.
    app.set_version_flag("--version", std::function<std::string()>([] {
                             std::string versions;
                             for (const auto& [name, v] : iso::core::component_versions())
                                 versions += (versions.empty() ? "" : "\n") + name + " " + v;
                             return versions;
                         }));
    app.require_subcommand(1);
    std::vector<std::pair<CLI::App*, iso::cli::RunFn>> commands;
    for (const auto& c : kCommands) {
        CLI::App* cmd = app.add_subcommand(c.name, c.description);
        commands.emplace_back(cmd, c.add(*cmd, argv[0]));
    }
    CLI11_PARSE(app, argc, argv);
    try {
        for (const auto& [cmd, run] : commands)
            if (*cmd) return run();
    } catch (const iso::Error& e) {
        std::cerr << "isoscope: error: " << iso::cli::cli_message(e) << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "isoscope: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
