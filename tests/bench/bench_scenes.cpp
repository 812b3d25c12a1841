#include "bench_scenes.hpp"

#include <cmath>

#include <tbb/parallel_for.h>

#include "tests/support/thin_phantom.hpp"

namespace iso::bench {

namespace {

// A dense surface: a gyroid of period 12 voxels in a cube of `n` voxels
// (0.5 mm), about 24.6 M triangles at n = 320; ~90 per pixel of a 640 x 480
// view, where one sample per pixel shows moire.
Volume gyroid(int n) {
    auto v = Volume::dense({n, n, n}, VoxelType::F32, make_affine({0.5, 0.5, 0.5}, {0, 0, 0}));
    v.meta.source = "gyroid";
    auto s = v.as<float>();
    const double w = 2.0 * M_PI / 12.0;
    tbb::parallel_for(0, n, [&](int k) {
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                s[v.linear_index(i, j, k)] =
                    float(std::sin(w * i) * std::cos(w * j) + std::sin(w * j) * std::cos(w * k) +
                          std::sin(w * k) * std::cos(w * i));
    });
    return v;
}

} // namespace

void make_scene(BenchScene& s, const std::string& data_dir, bool small) {
    if (s.name == "head") { // skin translucent over the bone
        s.scene.open(data_dir + "/headsq.nhdr");
        const auto ids = s.scene.add_isosurfaces({500, 1150});
        s.scene.info(ids[0]).opacity = 0.35f;
        s.view = "left";
    } else if (s.name == "bunny") {
        s.scene.open(data_dir + "/bunny.vtp");
        s.view = "anterior";
    } else if (s.name == "thin") { // vessels 3.5 .. 0.45 mm in radius in front of thin bone
        s.scene.set_volume(thin_phantom(), "thin-structure phantom");
        s.scene.add_isosurfaces({150});
        s.view = "anterior";
    } else if (s.name == "dense") {
        s.scene.set_volume(gyroid(small ? 160 : 320), "gyroid");
        s.scene.add_isosurfaces({0.0});
        s.view = "anterior";
    } else {
        throw Error("bench scenes", "unknown scene '" + s.name + "' (head, bunny, thin, dense)");
    }
    s.triangles = 0;
    for (const auto id : s.scene.surfaces()) s.triangles += s.scene.mesh(id).triangles.size();
}

} // namespace iso::bench
