// Cone AO on thin structures (docs/ao.md "Thin structures"):
// exact read-back of the surface voxels (a sheet thinner than a voxel seen
// face-on sets exactly the voxels around it, where the solid XOR pass alone
// sets nothing; a tilted one keeps voxels, within its depths, in every
// column; a thick block's columns are unchanged), and AO against the Embree
// reference on the thin-structure phantom (tests/bench/thin_phantom.hpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "tests/support/ao_metrics.hpp"
#include "tests/support/thin_phantom.hpp"
#include "gl_test.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/scenes.hpp"
#include "tests/support/slice_map.hpp"
#include "renderer/core/api.hpp"
#include "renderer/gpu/renderer.hpp"

using namespace iso;
using ConeAoThin = test::GlTest;
using test::texel_of;
using test::voxel_at;

namespace {

RenderOptions ao_options(int size, double radius, bool surface) {
    RenderOptions o;
    o.width = o.height = size;
    o.aov = Aov::Ao;
    o.look.ao = AoMethod::Cone;
    o.look.cone.radius_mm = radius;
    o.look.cone.surface_voxels = surface;
    o.look.cone.guard =
        0; // no guard band: the slicemap is the view's grid and its range starts at the nearest visible depth
    return o;
}

// The voxel holding linear depth z.
int voxel_holding(const SliceMap& sm, double z) { return int(std::floor((z - sm.z_near) / sm.voxel_length())); }

// The set bits of a texel's column below voxel `below`.
std::set<int> bits_of(const SliceMap& sm, int x, int y, int below) {
    std::set<int> s;
    for (int b = 0; b < std::min(below, sm.bits()); ++b)
        if (sm.bit(x, y, b)) s.insert(b);
    return s;
}

} // namespace

TEST_F(ConeAoThin, SheetThinnerThanAVoxelSetsExactlyItsVoxel) {
    // Camera 250 mm above, looking down. A 0.02 mm sheet at z = 0 (depth 250),
    // a small block at z 0..20 beside it (the nearest visible depth: 230) and a
    // floor at z = -70..-60 (the far bound): 256 voxels over 230..320, 0.35 mm each.
    const float t = 0.02f;
    Renderer ren;
    ren.add(test::flat_box_mesh({-40, -30, -t}, {0, 30, 0}), {});         // the sheet
    ren.add(test::flat_box_mesh({20, -5, 0}, {30, 5, 20}), {});           // nearest depth 230
    ren.add(test::flat_box_mesh({-100, -100, -70}, {100, 100, -60}), {}); // floor: far bound
    const Camera cam = test::looking({0, 0, 250}, {0, 0, 0}, {0, 1, 0});
    for (const bool surface : {false, true}) {
        const auto r = ren.render(cam, ao_options(128, 30, surface), {.read_slicemap = true});
        const auto& sm = r.slicemap;
        ASSERT_EQ(sm.bits(), 256);
        ASSERT_NEAR(sm.z_near, 230.0, 1e-3);
        // The surface pass sets, on the solid's side, the first voxel whose centre is at or beyond the
        // face towards the camera and the last whose centre is at or before the face away from it.
        const int front = voxel_at(sm, 250.0);
        const int back = int(std::floor((250.0 + t - sm.z_near) / sm.voxel_length() - 0.5));
        const int solid0 = voxel_at(sm, 250.0), solid1 = voxel_at(sm, 250.0 + t); // the XOR pass's [solid0, solid1)
        const int floor_voxel = voxel_holding(sm, 300.0); // compare the columns above the floor (depth 310)
        ASSERT_GT(back, 0);
        ASSERT_LT(front + 2, floor_voxel);
        ASSERT_LE(front - back, 1) << "the sheet lies within one voxel";
        const auto lo = texel_of(sm, {-40, -30, 0}), hi = texel_of(sm, {0, 30, 0});
        int checked = 0;
        for (int y = lo.y + 1; y < hi.y - 1; ++y)
            for (int x = lo.x + 1; x < hi.x - 1; ++x) {
                std::set<int> want;
                for (int b = solid0; b < solid1; ++b) want.insert(b); // a voxel centre between the faces (rare)
                if (surface) want.insert({front, back});
                const std::set<int> got = bits_of(sm, x, y, floor_voxel);
                ASSERT_EQ(got, want) << "texel " << x << "," << y << " surface voxels " << surface << " front voxel "
                                     << front;
                ++checked;
            }
        EXPECT_GT(checked, 200);
        if (!surface && solid0 == solid1) {
            EXPECT_TRUE(bits_of(sm, (lo.x + hi.x) / 2, (lo.y + hi.y) / 2, floor_voxel).empty())
                << "the solid pass alone loses the sheet (the case the surface pass is for)";
        }
    }
}

TEST_F(ConeAoThin, SurfaceVoxelsStayInsideThickSolids) {
    // The surface pass sets voxels on the solid's side of each face only:
    // inside a 20 mm block (depths 230..250 from 250 mm) every column is the
    // solid pass's, with and without it. A
    // face's voxel on the wrong side would add a voxel in front of the block
    // (self-occlusion) or behind it in every column.
    Renderer ren;
    ren.add(test::flat_box_mesh({-40, -30, 0}, {0, 30, 20}), {});
    ren.add(test::flat_box_mesh({-100, -100, -70}, {100, 100, -60}), {});
    const Camera cam = test::looking({0, 0, 250}, {0, 0, 0}, {0, 1, 0});
    const auto off = ren.render(cam, ao_options(128, 30, false), {.read_slicemap = true}).slicemap;
    const auto on = ren.render(cam, ao_options(128, 30, true), {.read_slicemap = true}).slicemap;
    ASSERT_EQ(off.z_near, on.z_near);
    ASSERT_EQ(off.z_far, on.z_far);
    const int floor_voxel = voxel_holding(on, 310.0) - 1;
    // the columns that enter through the top face and leave through the bottom one
    const auto lo = texel_of(on, {-40, -30, 0}), hi = texel_of(on, {0, 30, 0});
    const int first = voxel_at(on, 230.0), last = voxel_at(on, 250.0); // the solid pass's [first, last)
    int checked = 0;
    for (int y = lo.y + 1; y < hi.y - 1; ++y)
        for (int x = lo.x + 1; x < hi.x - 1; ++x) {
            const auto want = bits_of(off, x, y, floor_voxel);
            ASSERT_EQ(int(want.size()), last - first) << "texel " << x << "," << y;
            ASSERT_EQ(bits_of(on, x, y, floor_voxel), want) << "texel " << x << "," << y;
            ++checked;
        }
    EXPECT_GT(checked, 200);
}

TEST_F(ConeAoThin, SurfaceVoxelsKeepTheSlicemapReuse) {
    // The slicemap is still rebuilt only when something it depends on
    // changed: with surface voxels on, a still camera reuses it; turning them
    // on or off rebuilds it (they are in its key).
    Renderer ren;
    ren.add(test::flat_box_mesh({-20, -20, 0}, {20, 20, 10}), {});
    ren.add(test::flat_box_mesh({-100, -100, -10}, {100, 100, 0}), {});
    const Camera cam = test::looking({0, 0, 250}, {0, 0, 0}, {0, 1, 0});
    auto o = ao_options(64, 10, true);
    EXPECT_TRUE(ren.render(cam, o).voxelized);
    EXPECT_FALSE(ren.render(cam, o).voxelized) << "camera, scene and settings unchanged";
    o.look.cone.surface_voxels = false;
    EXPECT_TRUE(ren.render(cam, o).voxelized) << "surface voxels turned off";
    EXPECT_FALSE(ren.render(cam, o).voxelized);
    o.look.cone.surface_voxels = true;
    EXPECT_TRUE(ren.render(cam, o).voxelized) << "surface voxels turned on";
}

TEST_F(ConeAoThin, TiltedSheetThinnerThanAVoxelKeepsItsVoxelsInEveryColumn) {
    // A 0.05 mm sheet tilted 60 degrees from face-on (its depth changes by
    // ~0.9 mm, several voxels, across a texel): the solid pass loses it in
    // most columns (its faces' depths round to the same voxel centre), the
    // surface pass sets, in every column it covers, voxels only within the
    // sheet's depths there (+- half a texel's slope and one voxel).
    const float t = 0.05f;
    Mesh sheet = test::flat_box_mesh({-20, -20, -t}, {20, 20, 0});
    const glm::mat3 tilt = glm::mat3(glm::rotate(glm::mat4(1.0f), glm::radians(60.0f), glm::vec3(0, 1, 0)));
    for (auto& p : sheet.positions) p = tilt * p;
    for (auto& n : sheet.normals) n = tilt * n;
    Renderer ren;
    ren.add(sheet, {});
    ren.add(test::flat_box_mesh({40, -5, -50}, {50, 5, 30}), {});         // nearest visible depth 220
    ren.add(test::flat_box_mesh({-100, -100, -70}, {100, 100, -60}), {}); // floor: far bound
    const Camera cam = test::looking({0, 0, 250}, {0, 0, 0}, {0, 1, 0});
    const glm::dvec3 n = glm::dvec3(tilt * glm::vec3(0, 0, 1));
    for (const bool surface : {false, true}) {
        const auto sm = ren.render(cam, ao_options(128, 30, surface), {.read_slicemap = true}).slicemap;
        const double dz = sm.voxel_length();
        int columns = 0, kept = 0;
        for (int y = 0; y < sm.height; ++y)
            for (int x = 0; x < sm.width; ++x) {
                // the view ray through the texel centre, and where it meets the sheet's top plane
                const glm::dvec4 ndc((x + 0.5) / sm.width * 2 - 1, (y + 0.5) / sm.height * 2 - 1, 0.5, 1);
                glm::dvec4 w = glm::inverse(sm.projection * sm.view) * ndc;
                const glm::dvec3 d = glm::normalize(glm::dvec3(w) / w.w - cam.eye);
                const double s = -glm::dot(cam.eye, n) / glm::dot(d, n);
                const glm::dvec3 hit = cam.eye + s * d;
                const glm::dvec3 local = glm::transpose(glm::dmat3(tilt)) * hit;
                if (std::abs(local.x) > 18 || std::abs(local.y) > 18) continue; // well inside the sheet
                const double depth = glm::dot(hit - cam.eye, glm::normalize(glm::dvec3(cam.target - cam.eye)));
                // its depth across the texel: slope x texel footprint
                const double texel = 2 * depth / (sm.projection[1][1] * sm.height);
                const double spread = 0.5 * texel * std::abs(n.x / n.z) + 2 * dz;
                const auto bits = bits_of(sm, x, y, voxel_holding(sm, 300.0));
                ++columns;
                kept += !bits.empty();
                for (int b : bits) {
                    const double zc = sm.z_near + (b + 0.5) * dz;
                    ASSERT_LE(std::abs(zc - depth), spread)
                        << "texel " << x << "," << y << " bit " << b << " surface " << surface;
                }
            }
        ASSERT_GT(columns, 500);
        if (surface) {
            EXPECT_EQ(kept, columns) << "every column the sheet covers keeps it";
        } else {
            EXPECT_LT(kept, columns / 2) << "the solid pass alone loses most of it (the case the surface pass is for)";
        }
        std::printf("tilted sheet, surface voxels %d: %d of %d columns keep it\n", int(surface), kept, columns);
    }
}

TEST_F(ConeAoThin, ThinStructurePhantomAgainstTheEmbreeReference) {
    // The vessel tree (radii 3.5 .. 0.45 mm) and thin bone shells of
    // thin_phantom.hpp at iso 150, R = 10 mm, seen from the front, 256x256,
    // ray-traced reference capped at 512 rays (own noise RMS ~0.005). The
    // reference is the geometric-normal definition (docs/ao.md); cone and
    // disk AO work about the interpolated normal, and on this phantom the
    // two definitions differ by 0.037 RMSE (ao_raytraced_bench), which the
    // errors below now include.
    const std::string file =
        (std::filesystem::temp_directory_path() / ("isoscope-thin-phantom-" + std::to_string(::getpid()) + ".nrrd"))
            .string();
    bench::write_thin_phantom(file);
    core::RenderRequest rq;
    rq.isos = {150};
    rq.view = "anterior";
    rq.width = rq.height = 256;
    rq.aov = Aov::Ao;
    rq.look.ao = AoMethod::Raytraced;
    rq.look.cone.radius_mm = 10;
    rq.look.ao_rays = 512;
    rq.cache_dir = "-";
    const auto ref = core::render_input(file, rq);
    rq.look.ao = AoMethod::Cone;
    rq.look.cone.axis_weight = 0; // the estimator without axis probes: spheres only
    const auto cone = core::render_input(file, rq);
    rq.look.cone.surface_voxels = true;
    const auto surface = core::render_input(file, rq);
    rq.look.cone.surface_voxels = false;
    rq.look.cone.ray_weight = 1;
    const auto rw1 = core::render_input(file, rq);
    rq.look.cone.ray_weight = 0.5;
    rq.look.cone = {}; // the defaults: axis probes on
    EXPECT_EQ(rq.look.cone.axis_weight, 1.0);
    const auto axis = core::render_input(file, rq);
    rq.look.ao = AoMethod::Disk; // the other mode, its defaults
    const auto disk = core::render_input(file, rq);
    std::filesystem::remove(file);
    const auto e_axis = ao_error(axis.image, ref.image, rq.look.ao_rays);
    const auto e_disk = ao_error(disk.image, ref.image, rq.look.ao_rays);
    std::printf("thin phantom 256x256: disk RMSE %.4f bias %+.4f p95 %.4f\n", e_disk.rmse, e_disk.bias, e_disk.p95);
    // Disk AO: measured 0.049 (bias +0.001) here against the geometric-normal
    // reference (0.029, bias -0.006, against the former shading-normal one:
    // the definitions' gap in quadrature); the bound leaves room for the
    // reference's noise and other rasterizers. It must beat the cone tracer
    // here (the accurate mode).
    EXPECT_LE(e_disk.rmse, 0.06) << "disk: bias " << e_disk.bias << " p95 " << e_disk.p95;
    EXPECT_LE(std::abs(e_disk.bias), 0.02);
    EXPECT_LT(e_disk.rmse, e_axis.rmse);
    const auto e = ao_error(cone.image, ref.image, rq.look.ao_rays),
               e_surface = ao_error(surface.image, ref.image, rq.look.ao_rays),
               e_rw1 = ao_error(rw1.image, ref.image, rq.look.ao_rays);
    Image ones = ref.image;
    for (auto& v : ones.floats)
        if (std::isfinite(v)) v = 1;
    const auto e_none = ao_error(ones, ref.image);
    std::printf("thin phantom 256x256: cone without axis probes RMSE %.4f bias %+.4f p95 %.4f; surface voxels RMSE "
                "%.4f bias %+.4f; ray weight 1 "
                "RMSE %.4f bias %+.4f; axis probes RMSE %.4f bias %+.4f; no AO %.4f\n",
                e.rmse, e.bias, e.p95, e_surface.rmse, e_surface.bias, e_rw1.rmse, e_rw1.bias, e_axis.rmse, e_axis.bias,
                e_none.rmse);
    EXPECT_GT(e.pixels, 3000u);
    // Bounds: measured 0.086 (bias +0.041) without axis probes, 0.085 with surface voxels, 0.076 (bias
    // +0.017) with ray weight 1, no AO 0.197 against the geometric-normal reference (against the former
    // shading-normal one: 0.082, 0.081, 0.073, 0.193); this machine's llvmpipe, the renders are
    // deterministic, the margin is for other rasterizers and the reference's own noise.
    // Axis probes (axis weight 1, the default): measured 0.080, bias +0.008 (former reference: 0.078, +0.002).
    // The target is 0.06 at 512x512: missed, see docs/ao.md "Thin structures".
    EXPECT_LE(e.rmse, 0.095) << "bias " << e.bias << " MAE " << e.mae << " p95 " << e.p95;
    EXPECT_GT(e.bias, 0.0) << "the cone tracer is too light on thin structures (the known limit)";
    EXPECT_LE(e.bias, 0.05);
    EXPECT_GT(e_none.rmse, 1.5 * e.rmse) << "no AO is much worse: the comparison resolves AO";
    EXPECT_LE(e_surface.rmse, 0.095) << "surface voxels: bias " << e_surface.bias;
    EXPECT_LE(e_rw1.rmse, 0.085) << "ray weight 1: bias " << e_rw1.bias;
    EXPECT_LT(e_rw1.rmse, e.rmse) << "ray weight 1 is the better setting for thin structures (docs/ao.md)";
    EXPECT_LT(std::abs(e_rw1.bias), std::abs(e.bias));
    EXPECT_LE(e_axis.rmse, 0.09) << "axis probes: bias " << e_axis.bias;
    EXPECT_LT(e_axis.rmse, e.rmse) << "axis probes darken what the spheres under-count";
    EXPECT_NE(axis.meta.text.at("isoscope:ao_parameters").find("axis_weight 1"), std::string::npos);
    EXPECT_NE(cone.meta.text.at("isoscope:ao_parameters").find("surface_voxels off"), std::string::npos);
    EXPECT_NE(surface.meta.text.at("isoscope:ao_parameters").find("surface_voxels on"), std::string::npos);
}
