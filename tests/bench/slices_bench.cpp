// Slice views' costs (docs/slices.md "Performance"): reslicing a 512 x 512
// image from a CT-sized int16 volume on an oblique grid in each orientation,
// trilinear and nearest; window/level of that image to RGBA8; with --big also
// a 512 x 512 x 400 volume and a sparse (OpenVDB) one; and the outline of a
// 1.31 M-triangle sphere on a plane. Medians of repeated runs, printed as a
// table; nothing is checked here (tests/unit/slices_test.cpp checks the values).
//
//   slices_bench [--big]
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include <openvdb/openvdb.h>
#include <tbb/task_arena.h>

#include "bench_util.hpp"
#include "io/sparse.hpp"
#include "renderer/core/slices.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "tests/support/meshes.hpp"

using namespace iso;
using namespace iso::core;
using iso::test::oblique_affine;

namespace {

// The oblique grid's centre: not round, far from the origin (as the tests').
const glm::dvec3 kCentre(12.3, -45.6, 78.9);

template <class F> double median_ms(int runs, F f) {
    std::vector<double> t;
    for (int i = 0; i < runs; ++i) {
        const double t0 = bench::now_s();
        f();
        t.push_back(1000.0 * (bench::now_s() - t0));
    }
    return bench::median(t);
}

void reslice_table(bool big) {
    const std::array<std::int64_t, 3> dims =
        big ? std::array<std::int64_t, 3>{512, 512, 400} : std::array<std::int64_t, 3>{256, 256, 200};
    Volume v = Volume::dense(dims, VoxelType::I16, oblique_affine(dims, big ? 0.7 : 1.4, kCentre));
    auto s = v.as<std::int16_t>();
    for (std::size_t i = 0; i < s.size(); ++i) s[i] = std::int16_t((i * 2654435761u) >> 20);
    std::printf("reslice 512x512 from %lldx%lldx%lld int16 (oblique), median of 15, %d TBB threads:\n",
                (long long)dims[0], (long long)dims[1], (long long)dims[2], tbb::this_task_arena::max_concurrency());
    SliceImage img;
    for (auto p : default_planes(v)) {
        zoom_to_fit(p, 512, 512);
        const SliceGrid g = slice_grid(p, 512, 512);
        for (Interp interp : {Interp::Linear, Interp::Nearest}) {
            const double ms = median_ms(15, [&] { reslice(v, g, interp, img); });
            std::printf("  %-8s %-7s %7.2f ms\n", slice_orientation_name(p.orientation),
                        interp == Interp::Linear ? "linear" : "nearest", ms);
        }
    }
    const double wl = median_ms(15, [&] { (void)apply_window(img, {40, 400}, PixelFormat::Rgba8); });
    std::printf("  window/level 512x512 -> RGBA8 %.2f ms\n", wl);
    if (!big) return;
    // Sparse storage goes through Volume::value (an OpenVDB tree lookup per sample).
    const std::array<std::int64_t, 3> sd{256, 256, 200};
    auto grid = openvdb::FloatGrid::create(0.0f);
    auto acc = grid->getAccessor();
    for (int k = 0; k < sd[2]; ++k)
        for (int j = 0; j < sd[1]; ++j)
            for (int i = 0; i < sd[0]; ++i) acc.setValue(openvdb::Coord(i, j, k), float((i * 7 + j * 3 + k) % 1000));
    auto sg = std::make_shared<SparseGrid>();
    sg->grid = grid;
    const Volume sparse = Volume::sparse(sg, sd, oblique_affine(sd, 1.4, kCentre));
    for (auto p : default_planes(sparse)) {
        zoom_to_fit(p, 512, 512);
        const SliceGrid g = slice_grid(p, 512, 512);
        const double ms = median_ms(5, [&] { reslice(sparse, g, Interp::Linear, img); });
        std::printf("  sparse 256x256x200 (all active) %-8s linear %7.2f ms\n", slice_orientation_name(p.orientation),
                    ms);
    }
}

void outline_row() {
    const Mesh sphere = test::uv_sphere({1, 2, 3}, 80, 640, 1024); // 1.31 M triangles
    SlicePlane p;
    p.origin = p.center = {1, 2, 3.3};
    p.pixel_mm = 0.35;
    const SliceGrid g = slice_grid(p, 512, 512);
    std::size_t n = 0;
    const double ms = median_ms(9, [&] { n = mesh_outline(sphere, g).size(); });
    std::printf("outline of %zu triangles: %zu segments, median of 9 %.2f ms (%d TBB threads)\n",
                sphere.triangles.size(), n, ms, tbb::this_task_arena::max_concurrency());
}

} // namespace

int main(int argc, char** argv) {
    bool big = false;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--big") == 0) {
            big = true;
        } else {
            std::fprintf(stderr, "slices_bench: unknown argument '%s' (usage: slices_bench [--big])\n", argv[i]);
            return 2;
        }
    }
    reslice_table(big);
    outline_row();
    return 0;
}
