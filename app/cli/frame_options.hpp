// The options that fix a frame, shared by `render` and `pick` (a pick's
// pixel is a pixel of the image `render` writes with the same options), and
// the cone-AO tunables that `view` shares with them.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/cli/common.hpp"
#include "renderer/core/api.hpp"

namespace iso::cli {

// Cone-AO tunables, shared by `render`, `pick` and `view`.
void add_cone_options(CLI::App* cmd, iso::ConeAoSettings& c);

// Volume rendering's --volume (a preset or value:opacity:#rrggbb,...) and
// --volume-mode, shared by `render`, `pick` and `view`; and the look they
// give (a bad text names its setting, which cli_message maps to the flag).
void add_volume_options(CLI::App* cmd, std::string& volume, std::string& mode);
void apply_volume_options(const std::string& volume, const std::string& mode, iso::VolumeLook& look);

// What fixes a frame, shared by `render` and `pick`: a pick's pixel is a
// pixel of the image `render` writes with the same options. The options are
// bound to the core's request itself (`req`: view, series, iso values, the
// AO settings, transparency's); only what needs parsing is held as text.
struct FrameArgs {
    std::string in, size = "1024x1024", ao = "off", disk_blend;
    Look look; // surface colours and opacities, background, shading
    bool no_aa = false;
    // Volume rendering: a preset or value:opacity:#rrggbb,...; its mode; clips.
    std::string volume, volume_mode = "composite", volume_integration = "preintegrated";
    std::vector<std::string> clip;
    bool no_empty_skipping = false;
    std::string lod = "auto", culling = "on"; // levels of detail (docs/lod.md)
    iso::core::RenderRequest req;
};

void add_frame_options(CLI::App* c, FrameArgs& a, bool input_required = true);

// The core's request for the frame: `req` with --size, --ao, --background,
// --shading and --ao-disk-blend parsed in (a bad text names its flag).
iso::core::RenderRequest frame_request(const FrameArgs& a);

} // namespace iso::cli
