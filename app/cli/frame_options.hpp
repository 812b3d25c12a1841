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

// What fixes a frame, shared by `render` and `pick`: a pick's pixel is a
// pixel of the image `render` writes with the same options.
struct FrameArgs {
    std::string in, view = "anterior", size = "1024x1024", series, ao = "off";
    std::vector<double> isos;
    double ao_radius = 10.0;
    int ao_frames = 1;
    iso::ConeAoSettings cone;
    iso::DiskAoSettings disk;
    std::string disk_blend;
    Look look;
    float oit_epsilon = 1.0f / 512.0f;
    double oit_memory = 256;
};

void add_frame_options(CLI::App* c, FrameArgs& a, bool input_required = true);

// The core's request for the frame (--size, --background and --ao-disk-blend
// parsed here: a bad text names its flag).
iso::core::RenderRequest frame_request(const FrameArgs& a);

} // namespace iso::cli
