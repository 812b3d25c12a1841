// The scenes of the whole-image benchmarks (image_bench, dsraa_bench): the
// bundled head CT with translucent skin, the bunny, a thin-vessel phantom
// and a dense gyroid surface, each with the view it is measured from.
#pragma once

#include <cstddef>
#include <string>

#include "renderer/core/api.hpp"

namespace iso::bench {

struct BenchScene {
    std::string name, view;
    core::Scene scene;
    std::size_t triangles = 0;
};

// head (skin 35 % over bone), bunny, thin (vessels 3.5 .. 0.45 mm in radius
// in front of thin bone), dense (a gyroid of 320^3 voxels, 24.6 M
// triangles; 160^3 when `small`). Throws on an unknown name.
void make_scene(BenchScene& s, const std::string& data_dir, bool small = false);

} // namespace iso::bench
