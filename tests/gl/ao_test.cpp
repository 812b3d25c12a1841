// Cone-traced AO on a real GL context (EGL + llvmpipe): exact read-back of
// the slicemap voxelization (boxes, nested spherical shells), sphere
// occlusion against a half-space, AO against the Embree reference on the
// bundled CT and the bunny, pass culling and caching, temporal accumulation,
// and stress cases (grazing angles, thin sheets, deep cavities, the near
// plane, an empty scene, a single triangle).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "tests/support/ao_metrics.hpp"
#include "gl_test.hpp"
#include "renderer/ao/reference.hpp"
#include "renderer/core/api.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/gpu/renderer.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/scenes.hpp"
#include "tests/support/slice_map.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using ConeAo = test::GlTest;
using ConeAoStress = test::GlTest;
using test::float_at;
using test::looking;
using test::sphere_mesh;
using test::texel_of;
using test::voxel_at;

namespace {

RenderOptions ao_options(int size, double radius) {
    RenderOptions o;
    o.width = o.height = size;
    o.aov = Aov::Ao;
    o.look.ao = AoMethod::Cone;
    o.look.cone.radius_mm = radius;
    return o;
}

} // namespace

// The suite's name is also that of iso::SliceMap: its fixture alias lives in
// a namespace of its own so that neither name hides the other.
namespace slicemap_suite {
using SliceMap = test::GlTest;

TEST_F(SliceMap, TwoBoxesGiveExactBitPatterns) {
    // Seen from the front (camera on -y looking +y): box A spans depths 480..500, box B 490..520.
    Renderer ren;
    ren.add(test::flat_box_mesh({-20, -20, -20}, {0, 0, 20}), {});
    ren.add(test::flat_box_mesh({0, -10, -20}, {20, 20, 20}), {});
    const Camera cam = looking({0, -500, 0}, {0, 0, 0}, {0, 0, 1});
    auto o = ao_options(128, 100);
    const auto r = ren.render(cam, o, {.read_slicemap = true});
    const auto& sm = r.slicemap;
    ASSERT_EQ(sm.width, 128);
    ASSERT_EQ(sm.bits(), 256);
    EXPECT_FLOAT_EQ(float(sm.z_near), 480.0f) << "nearest visible depth";
    EXPECT_NEAR(sm.z_far, 520.0, 1e-3) << "the scene's far bound (nearer than the farthest visible + R)";
    int checked_a = 0, checked_b = 0, checked_empty = 0;
    for (int y = 0; y < sm.height; ++y)
        for (int x = 0; x < sm.width; ++x) {
            // Classify the texel by the projections of both boxes' front and back faces, with a 1-texel margin.
            auto inside = [&](glm::vec2 lo, glm::vec2 hi, double y0, double y1, int margin) {
                for (double yy : {y0, y1}) {
                    const auto a = texel_of(sm, {lo.x, yy, lo.y}), b = texel_of(sm, {hi.x, yy, hi.y});
                    if (x < a.x + margin || x > b.x - margin || y < a.y + margin || y > b.y - margin) return false;
                }
                return true;
            };
            const bool in_a = inside({-20, -20}, {0, 20}, -20, 0, 1), in_b = inside({0, -20}, {20, 20}, -10, 20, 1);
            const bool near_a = inside({-20, -20}, {0, 20}, -20, 0, -1),
                       near_b = inside({0, -20}, {20, 20}, -10, 20, -1);
            int lo = -1, hi = -1;
            if (in_a && !near_b) {
                lo = voxel_at(sm, 480), hi = voxel_at(sm, 500);
                ++checked_a;
            } else if (in_b && !near_a) {
                lo = voxel_at(sm, 490), hi = voxel_at(sm, 520);
                ++checked_b;
            } else if (!near_a && !near_b) {
                ++checked_empty;
            } else {
                continue;
            }
            for (int b = 0; b < sm.bits(); ++b)
                ASSERT_EQ(sm.bit(x, y, b), b >= lo && b < hi) << "texel " << x << "," << y << " bit " << b;
        }
    EXPECT_EQ(voxel_at(sm, 500), 128);
    EXPECT_GT(checked_a, 100);
    EXPECT_GT(checked_b, 100);
    EXPECT_GT(checked_empty, 1000);
}

TEST_F(SliceMap, NestedSphericalShellsXorToTheirGap) {
    const glm::dvec3 c(5, 0, -3);
    Renderer ren;
    ren.add(sphere_mesh(c, 45, 0.75), {});
    ren.add(sphere_mesh(c, 30, 0.75), {});
    const Camera cam = looking(c + glm::dvec3(0, -400, 0), c, {0, 0, 1});
    auto o = ao_options(96, 200);
    o.look.cone.layers = 4;
    const auto r = ren.render(cam, o, {.read_slicemap = true});
    const auto& sm = r.slicemap;
    ASSERT_EQ(sm.bits(), 512);
    EXPECT_NEAR(sm.z_near, 355.0, 0.2) << "nearest visible: the outer sphere's front";
    EXPECT_NEAR(sm.z_far, 445.0, 0.5) << "the scene's far bound";
    // Columns through texel centres near the axis: analytic entry/exit depths of both shells.
    const double dz = sm.voxel_length();
    int columns = 0;
    for (int y = 40; y < 56; ++y)
        for (int x = 40; x < 56; ++x) {
            // The ray through this texel's centre.
            const double ndc_x = (x + 0.5) / sm.width * 2 - 1, ndc_y = (y + 0.5) / sm.height * 2 - 1;
            const glm::dmat4 inv = glm::inverse(sm.projection * sm.view);
            const glm::dvec4 f = inv * glm::dvec4(ndc_x, ndc_y, 0.5, 1.0);
            const glm::dvec3 dir = glm::normalize(glm::dvec3(f) / f.w - cam.eye);
            const double cos_axis = glm::dot(dir, cam.forward());
            auto hits = [&](double R) { // depths (along the view axis) where the ray enters and leaves the sphere
                const glm::dvec3 oc = cam.eye - c;
                const double b = glm::dot(oc, dir), disc = b * b - (glm::dot(oc, oc) - R * R);
                return std::pair{(-b - std::sqrt(disc)) * cos_axis, (-b + std::sqrt(disc)) * cos_axis};
            };
            const auto [o0, o1] = hits(45);
            const auto [i0, i1] = hits(30);
            for (int b = 0; b < sm.bits(); ++b) {
                const double z = sm.z_near + (b + 0.5) * dz; // voxel centre
                const bool in_gap = (z > o0 && z < i0) || (z > i1 && z < o1);
                // The meshes are within 0.1 mm of the spheres: skip voxels that close to a boundary.
                const double margin =
                    std::min({std::abs(z - o0), std::abs(z - i0), std::abs(z - i1), std::abs(z - o1)});
                if (margin < 0.15) continue;
                ASSERT_EQ(sm.bit(x, y, b), in_gap) << "texel " << x << "," << y << " bit " << b << " depth " << z;
            }
            ++columns;
        }
    EXPECT_EQ(columns, 256);
}

} // namespace slicemap_suite

TEST_F(ConeAo, SphereOcclusionByAHalfSpaceIsItsVolumeFraction) {
    // A floor (top at z = 0) and a wall filling x > 0, seen from above. With
    // one cone (the whole hemisphere) and one sphere, each floor point's AO is
    // 1 - the fraction of the sphere of radius R/2 above it that lies in the wall.
    const double R = 10;
    Renderer ren;
    ren.add(test::flat_box_mesh({-100, -100, -10}, {0, 100, 0}), {});
    ren.add(test::flat_box_mesh({0, -100, -10}, {100, 100, 40}), {});
    const Camera cam = looking({0, 0, 300}, {0, 0, 0}, {0, 1, 0}, 10, 1000);
    auto o = ao_options(256, R);
    o.look.cone.resolution = 1.0; // the cone pass itself, no upsampling
    o.look.cone.cones = 1;
    o.look.cone.spheres = 1;
    o.look.cone.samples = 32;
    o.look.cone.jitter_sets = 16;
    o.look.cone.temporal = false;
    RenderOptions d = o;
    d.aov = Aov::Depth;
    const auto depth = ren.render(cam, d).image;
    const double th = std::tan(glm::radians(cam.fov_y_degrees) * 0.5);
    const double r = R / 2;
    // Ray weight 0: the sphere's occlusion is the cap's volume fraction o.
    // Ray weight 1: the blocked-ray fraction sqrt(o) (1.15 - 0.15 o); the
    // square root of a noisy estimate is biased low where o is small, so
    // only its mean over a pixel column is held to a bound (0.05).
    for (double weight : {0.0, 1.0}) {
        o.look.cone.ray_weight = weight;
        const auto img = ren.render(cam, o).image;
        // Columns of pixels at several distances from the wall (x < 0 on the floor).
        int tested = 0;
        for (int x = 0; x < 128; ++x) {
            const double px = ((x + 0.5) / 128.0 - 1.0) * th * 300.0; // floor x at this pixel column (depth 300)
            const double dist = -px;
            if (dist > r) continue;
            const double cap = (r - dist) * (r - dist) * (2 * r + dist) / (4 * r * r * r);
            const double expected = 1.0 - (weight == 0 ? cap : std::sqrt(cap) * (1.15 - 0.15 * cap));
            double sum = 0;
            int n = 0;
            for (int y = 48; y < 208; ++y) {
                const int row = 255 - y;
                if (std::abs(depth.floats[std::size_t(row) * 256 + std::size_t(x)] - 300.0f) > 0.01f) continue;
                const float v = float_at(img, x, row);
                if (weight == 0) {
                    EXPECT_NEAR(v, expected, 0.12)
                        << "pixel " << x << "," << row << " at " << dist << " mm from the wall";
                }
                sum += v;
                ++n;
            }
            ASSERT_GT(n, 100);
            // Averaged over the jitter sets, the Poisson estimate is within 0.03 of the volume fraction.
            EXPECT_NEAR(sum / n, expected, weight == 0 ? 0.03 : 0.05)
                << dist << " mm from the wall, ray weight " << weight;
            ++tested;
        }
        EXPECT_GE(tested, 6);
    }
}

TEST_F(ConeAo, CtSkinAndBunnyAgainstTheEmbreeReference) {
    struct Case {
        std::string input, view;
        std::vector<double> isos;
        double radius, max_rmse;
    };
    // Bounds: the benchmark measures 0.040 (skin) and 0.023 (bunny) RMSE at 512x512 with 1024 rays; at
    // 256x256 with 512 rays the reference's own noise adds ~0.01.
    const Case cases[] = {{test::data("headsq.nhdr"), "left", {500}, 10.0, 0.06},
                          {test::data("bunny.vtp"), "anterior", {}, 0.05, 0.04}};
    for (const auto& k : cases) {
        core::RenderRequest rq;
        rq.isos = k.isos;
        rq.view = k.view;
        rq.width = rq.height = 256;
        rq.aov = Aov::Ao;
        rq.look.ao = AoMethod::Raytraced;
        rq.look.cone.radius_mm = k.radius;
        rq.look.ao_rays = 512;
        rq.cache_dir = "-";
        const auto ref = core::render_input(k.input, rq);
        rq.look.ao = AoMethod::Cone;
        const auto cone = core::render_input(k.input, rq);
        const auto e = ao_error(cone.image, ref.image, rq.look.ao_rays);
        EXPECT_GT(e.pixels, 5000u);
        EXPECT_LE(e.rmse, k.max_rmse) << k.input << ": bias " << e.bias << " MAE " << e.mae << " p95 " << e.p95;
        EXPECT_LE(std::abs(e.bias), 0.03) << k.input;
        // No AO at all is much worse: the comparison resolves AO.
        Image ones = ref.image;
        for (auto& v : ones.floats)
            if (std::isfinite(v)) v = 1;
        EXPECT_GT(ao_error(ones, ref.image).rmse, 1.5 * e.rmse) << k.input;
        EXPECT_EQ(cone.meta.text.at("isoscope:ao_radius_mm"), k.radius == 10.0 ? "10" : "0.05");
        EXPECT_NE(cone.meta.text.at("isoscope:ao_parameters").find("cones 8"), std::string::npos);
    }
}

TEST_F(ConeAo, CoarseConePassIsUpsampledAlongSurfacesNotAcrossEdges) {
    // 1. Accuracy: at half resolution the error against the reference stays
    //    within 0.005 of the full-resolution error (the benchmark measures it
    //    a little lower: the bilateral upsampling also averages jitter noise),
    //    and background pixels are exactly those of the full-resolution image.
    const struct {
        std::string input, view;
        std::vector<double> isos;
        double radius;
    } cases[] = {{test::data("headsq.nhdr"), "left", {500}, 10.0}, {test::data("bunny.vtp"), "anterior", {}, 0.05}};
    for (const auto& k : cases) {
        core::RenderRequest rq;
        rq.isos = k.isos;
        rq.view = k.view;
        rq.width = rq.height = 256;
        rq.aov = Aov::Ao;
        rq.look.ao = AoMethod::Raytraced;
        rq.look.cone.radius_mm = k.radius;
        rq.look.ao_rays = 512;
        rq.cache_dir = "-";
        const auto ref = core::render_input(k.input, rq);
        rq.look.ao = AoMethod::Cone;
        rq.look.cone.resolution = 1.0;
        const auto full = core::render_input(k.input, rq);
        rq.look.cone.resolution = 0.5;
        const auto half = core::render_input(k.input, rq);
        const auto ef = ao_error(full.image, ref.image, rq.look.ao_rays),
                   eh = ao_error(half.image, ref.image, rq.look.ao_rays);
        EXPECT_LE(eh.rmse, ef.rmse + 0.005) << k.input << ": full " << ef.rmse << ", half " << eh.rmse;
        std::size_t nan_mismatch = 0;
        for (std::size_t i = 0; i < full.image.floats.size(); ++i)
            nan_mismatch += std::isnan(full.image.floats[i]) != std::isnan(half.image.floats[i]);
        EXPECT_EQ(nan_mismatch, 0u) << k.input;
        EXPECT_NE(half.meta.text.at("isoscope:ao_parameters").find("resolution 0.5"), std::string::npos);
    }
    // 2. Edges: a block standing on a slab, seen from above. The slab is
    //    occluded around the block's foot; the block's top, 40 mm higher, is
    //    an open plane (AO 1 at full resolution). Upsampling must not carry
    //    the slab's darkness onto the top across the silhouette, and must keep
    //    most of the slab's dark ring.
    Renderer ren;
    ren.add(test::flat_box_mesh({-100, -100, -10}, {100, 100, 0}), {});
    const auto block = ren.add(test::flat_box_mesh({-20, -20, 0}, {20, 20, 40}), {});
    const Camera cam = looking({0, 0, 300}, {0, 0, 0}, {0, 1, 0});
    RenderOptions o = ao_options(128, 10.0);
    o.look.cone.temporal = false;
    o.look.cone.resolution = 1.0;
    const Image full = ren.render(cam, o).image;
    for (double res : {0.5, 0.25}) {
        o.look.cone.resolution = res;
        const Image half = ren.render(cam, o).image;
        o.aov = Aov::Id;
        const Image id = ren.render(cam, o).image;
        o.aov = Aov::Ao;
        double top_min = 1, ring_full = 0, ring_half = 0;
        int top = 0, ring = 0;
        for (std::size_t i = 0; i < id.floats.size(); ++i) {
            if (id.floats[i] == float(block)) {
                ++top;
                top_min = std::min(top_min, double(half.floats[i]));
                EXPECT_GE(full.floats[i], 0.999f);
            } else if (std::isfinite(full.floats[i]) && full.floats[i] < 0.9f) {
                ++ring;
                ring_full += 1 - full.floats[i];
                ring_half += 1 - half.floats[i];
            }
        }
        ASSERT_GT(top, 500);
        ASSERT_GT(ring, 100);
        EXPECT_GE(top_min, 0.98) << "resolution " << res << ": slab AO bled onto the block's top";
        // The ring is a few pixels wide and darkest at the foot, where the
        // nearest coarse samples on the slab's side lie farther out (the ones
        // on the block are rejected): coarse AO keeps most of its darkness,
        // not all (measured 78 % at 1/2 and 51 % at 1/4; docs/ao.md, limits).
        EXPECT_LE(ring_half, ring_full * 1.05) << "resolution " << res;
        EXPECT_GE(ring_half, ring_full * (res == 0.5 ? 0.7 : 0.45)) << "resolution " << res;
    }
}

TEST_F(ConeAo, GuardBandKeepsOccludersJustOffScreen) {
    // A floor seen from above, zoomed in; a wall starts 3 mm beyond the
    // view's right edge and rises 40 mm. Floor points at the edge are within
    // R of it: the Embree reference (whole meshes) sees it, a slicemap cut at
    // the viewport would not. The same floor strip seen with the wall in view
    // gives the cone tracer's own error there, which the guard band must reach.
    const double R = 10;
    const int S = 128;
    const Camera cam = looking({0, 0, 200}, {0, 0, 0}, {0, 1, 0});
    const double x_edge = 200.0 / (cam.projection(1.0))[0][0]; // floor x at NDC x = 1 (the floor's depth is 200)
    std::vector<Mesh> meshes{test::flat_box_mesh({-400, -400, -10}, {400, 400, 0}),
                             test::flat_box_mesh({float(x_edge + 3), -400, 0}, {float(x_edge + 40), 400, 40})};
    Renderer ren;
    for (const auto& m : meshes) ren.add(m, {});
    AoReference reference({&meshes[0], &meshes[1]});
    const double pixel = 2 * x_edge / S;
    // Mean (cone - reference) over floor pixels within 4 pixels of x_edge.
    auto strip_error = [&](const Camera& c, double guard, double* used) {
        RenderOptions d;
        d.width = d.height = S;
        d.aov = Aov::Depth;
        const Image depth = ren.render(c, d).image;
        d.aov = Aov::Normal;
        const Image normal = ren.render(c, d).image;
        AoReferenceOptions ro;
        ro.radius_mm = R;
        ro.rays = 256;
        const Image ref = reference.image(c, depth, normal, ro);
        RenderOptions o = ao_options(S, R);
        o.look.cone.guard = guard;
        o.look.cone.temporal = false;
        const auto r = ren.render(c, o);
        *used = r.ao_guard;
        double e = 0, ref_mean = 0;
        int n = 0;
        for (int y = 0; y < S; ++y)
            for (int x = 0; x < S; ++x) {
                const std::size_t i = std::size_t(y) * S + std::size_t(x);
                const double wx = c.target.x + ((x + 0.5) / S * 2 - 1) * x_edge;
                if (wx < x_edge - 4 * pixel || wx > x_edge || std::abs(depth.floats[i] - 200.0f) > 0.01f) continue;
                e += r.image.floats[i] - ref.floats[i];
                ref_mean += ref.floats[i];
                ++n;
            }
        EXPECT_GT(n, 400);
        EXPECT_LT(ref_mean / n, 0.85) << "the wall occludes the strip";
        return e / n;
    };
    double used = 0;
    const double without = strip_error(cam, 0.0, &used);
    EXPECT_EQ(used, 0.0);
    const double with = strip_error(cam, 0.15, &used);
    const double guard_used = used;
    EXPECT_GT(guard_used, 0.02);
    EXPECT_LE(guard_used, 0.15);
    Camera shifted = cam;
    shifted.eye.x += 30;
    shifted.target.x += 30;
    const double in_view = strip_error(shifted, 0.0, &used);
    std::cout << "strip error (cone - reference): no guard " << without << ", guard " << guard_used << ": " << with
              << ", wall in view " << in_view << "\n";
    EXPECT_GT(without, in_view + 0.1) << "no guard band: the off-screen wall is missed";
    EXPECT_NEAR(with, in_view, 0.03) << "guard band " << guard_used << ": the strip as if the wall were in view";
    // A scene wholly in view needs no guard band.
    Renderer small;
    small.add(test::flat_box_mesh({-20, -20, -20}, {20, 20, 20}), {});
    EXPECT_EQ(small.render(looking({0, -300, 0}, {0, 0, 0}, {0, 0, 1}), ao_options(64, R)).ao_guard, 0.0);
}

TEST_F(ConeAo, PassesAreCulledWhenOffAndTheSlicemapIsReusedWhenStill) {
    Renderer ren;
    ren.add(test::flat_box_mesh({-20, -20, -20}, {20, 20, 20}), {});
    const Camera cam = looking({30, -300, 40}, {0, 0, 0}, {0, 0, 1});
    RenderOptions o;
    o.width = o.height = 64;
    // AO off: the AO passes are declared (the frame is the same graph) and the
    // graph culls them because nothing reads the AO image.
    const auto culled = [](const graph::FrameStats& s, const std::string& name) {
        int declared = 0;
        for (const auto& p : s.passes)
            if (p.name == name) {
                ++declared;
                EXPECT_FALSE(p.ran) << name;
            }
        return declared == 1;
    };
    auto off = ren.render(cam, o);
    EXPECT_TRUE(culled(off.stats, "voxelize")) << "declared once with AO off";
    EXPECT_TRUE(culled(off.stats, "cone_ao")) << "declared once with AO off";
    o.look.ao = AoMethod::Cone;
    auto a = ren.render(cam, o);
    EXPECT_TRUE(a.voxelized);
    EXPECT_EQ(a.ao_frames, 1);
    auto b = ren.render(cam, o);
    EXPECT_FALSE(b.voxelized) << "camera and scene unchanged";
    EXPECT_EQ(b.ao_frames, 2) << "a still frame accumulates";
    bool ran_cone = false, ran_vox = false;
    for (const auto& p : b.stats.passes) {
        ran_cone |= p.name == "cone_ao" && p.ran;
        ran_vox |= p.name == "voxelize" && p.ran;
    }
    EXPECT_TRUE(ran_cone);
    EXPECT_FALSE(ran_vox);
    // A depth AOV with AO on: the AO passes are declared and culled.
    o.aov = Aov::Depth;
    auto c = ren.render(cam, o);
    EXPECT_TRUE(culled(c.stats, "cone_ao")) << "declared once with a depth AOV";
    o.aov = Aov::None;
    Camera moved = cam;
    moved.orbit(5, 0);
    auto d = ren.render(moved, o);
    EXPECT_TRUE(d.voxelized) << "the camera moved";
    EXPECT_EQ(d.ao_frames, 1);
    ren.object(1).visible = false;
    ren.add(test::flat_box_mesh({-5, -5, 25}, {5, 5, 35}), {});
    EXPECT_TRUE(ren.render(moved, o).voxelized) << "the scene changed";
}

TEST_F(ConeAo, StillFramesConvergeInsteadOfFlickering) {
    Renderer ren;
    ren.add(test::flat_box_mesh({-100, -100, -10}, {100, 100, 0}), {});
    ren.add(test::flat_box_mesh({-10, -10, 0}, {10, 10, 15}), {});
    const Camera cam = looking({40, -120, 160}, {0, 0, 0}, {0, 0, 1});
    auto o = ao_options(128, 10);
    o.look.cone.samples = 4;
    o.look.cone.cones = 4;
    std::vector<Image> frames;
    for (int f = 0; f < 16; ++f) frames.push_back(ren.render(cam, o).image);
    auto change = [&](int f) { // RMS change from frame f-1 to f
        double s = 0;
        std::size_t n = 0;
        for (std::size_t i = 0; i < frames[0].floats.size(); ++i) {
            const double a = frames[std::size_t(f)].floats[i], b = frames[std::size_t(f - 1)].floats[i];
            if (std::isfinite(a) && std::isfinite(b)) {
                s += (a - b) * (a - b);
                ++n;
            }
        }
        return std::sqrt(s / double(n));
    };
    EXPECT_GT(change(1), 0.0) << "a new jitter set each still frame";
    EXPECT_LT(change(15), 0.25 * change(1)) << "running mean: changes shrink like 1/frame";
    o.look.cone.temporal = false;
    const auto x = ren.render(cam, o).image, y = ren.render(cam, o).image;
    EXPECT_EQ(x.floats.size(), y.floats.size());
    for (std::size_t i = 0; i < x.floats.size(); ++i)
        if (std::isfinite(x.floats[i])) {
            ASSERT_EQ(x.floats[i], y.floats[i]) << "temporal off: the same jitter every frame";
        }
}

// ---- stress cases -------------------------------------------------------

TEST_F(ConeAoStress, GrazingViewOfAnOpenPlaneStaysUnoccluded) {
    Renderer ren;
    ren.add(test::flat_box_mesh({-400, -400, -10}, {400, 400, 0}), {});
    // 85 degrees from the normal.
    const double a = glm::radians(85.0);
    const Camera cam = looking({0, -300 * std::sin(a), 300 * std::cos(a)}, {0, 0, 0}, {0, 0, 1});
    const auto img = ren.render(cam, ao_options(128, 10)).image;
    double sum = 0;
    std::size_t n = 0, dark = 0;
    for (float v : img.floats)
        if (std::isfinite(v)) {
            sum += v;
            ++n;
            dark += v < 0.8f;
        }
    ASSERT_GT(n, 1000u);
    EXPECT_GT(sum / double(n), 0.97) << "an open plane is unoccluded (reference: exactly 1)";
    EXPECT_LT(double(dark) / double(n), 0.02);
}

TEST_F(ConeAoStress, ThinSheetAndDeepCavityAgainstTheReference) {
    // Floor, a 0.3 mm sheet standing on it (thinner than a voxel), and a 10 x 10 x 40 mm well built
    // from boxes that share faces.
    std::vector<Mesh> meshes = {
        test::flat_box_mesh({-100, -100, -10}, {100, 100, 0}), test::flat_box_mesh({-40, -30, 0}, {-39.7f, 30, 25}),
        test::flat_box_mesh({20, -5, -50}, {25, 5, 0}),        test::flat_box_mesh({35, -5, -50}, {40, 5, 0}),
        test::flat_box_mesh({20, -10, -50}, {40, -5, 0}),      test::flat_box_mesh({20, 5, -50}, {40, 10, 0}),
        test::flat_box_mesh({20, -10, -60}, {40, 10, -50})};
    // The floor has a hole where the well is: cut it into pieces around x 20..40, y -10..10.
    meshes[0] = test::flat_box_mesh({-100, -100, -10}, {20, 100, 0});
    meshes.push_back(test::flat_box_mesh({40, -100, -10}, {100, 100, 0}));
    meshes.push_back(test::flat_box_mesh({20, -100, -10}, {40, -10, 0}));
    meshes.push_back(test::flat_box_mesh({20, 10, -10}, {40, 100, 0}));
    // The well's walls overlap the floor pieces between z -10 and 0: shorten them to below the floor.
    meshes[2] = test::flat_box_mesh({25, -5, -50}, {35, -5, -50}); // (degenerate: no volume, draws nothing)
    meshes[2] = test::flat_box_mesh({20, -5, -50}, {25, 5, -10});
    meshes[3] = test::flat_box_mesh({35, -5, -50}, {40, 5, -10});
    meshes[4] = test::flat_box_mesh({20, -10, -50}, {40, -5, -10});
    meshes[5] = test::flat_box_mesh({20, 5, -50}, {40, 10, -10});
    Renderer ren;
    std::vector<const Mesh*> ptrs;
    for (const auto& m : meshes) {
        ren.add(m, {});
        ptrs.push_back(&m);
    }
    const Camera cam = looking({0, 0, 250}, {0, 0, 0}, {0, 1, 0});
    const int S = 256;
    const double R = 10;
    auto o = ao_options(S, R);
    o.look.cone.layers = 4;
    const auto cone = ren.render(cam, o).image;
    RenderOptions d = o;
    d.aov = Aov::Depth;
    const auto depth = ren.render(cam, d).image;
    d.aov = Aov::Normal;
    const auto normal = ren.render(cam, d).image;
    AoReference reference(ptrs);
    AoReferenceOptions ro;
    ro.radius_mm = R;
    ro.rays = 256;
    const auto ref = reference.image(cam, depth, normal, ro);
    const auto e = ao_error(cone, ref, ro.rays);
    EXPECT_LE(e.rmse, 0.10) << "bias " << e.bias << " p95 " << e.p95;
    // Camera straight down: pixel x maps to world x = ndc * tan(fov/2) * depth.
    const double th = std::tan(glm::radians(cam.fov_y_degrees) * 0.5);
    double well_cone = 0, well_ref = 0, sheet_cone = 0, sheet_ref = 0;
    int well = 0, sheet = 0;
    for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x) {
            const std::size_t i = std::size_t(y) * S + std::size_t(x);
            const float D = depth.floats[i];
            if (!std::isfinite(cone.floats[i]) || !std::isfinite(ref.floats[i])) continue;
            const double wx = ((x + 0.5) / S * 2 - 1) * th * D, wy = (1 - (y + 0.5) / S * 2) * th * D;
            if (std::abs(D - 300.0f) < 0.01f && wx > 22 && wx < 38 &&
                std::abs(wy) < 3) { // the well's floor, 50 mm down
                well_cone += cone.floats[i];
                well_ref += ref.floats[i];
                ++well;
            }
            if (std::abs(D - 250.0f) < 0.01f && std::abs(wy) < 25 && wx > -50 && wx < -29.7 &&
                std::abs(wx + 39.85) > 0.5) {
                sheet_cone += cone.floats[i]; // the floor within R of the thin sheet
                sheet_ref += ref.floats[i];
                ++sheet;
            }
        }
    ASSERT_GT(well, 10);
    ASSERT_GT(sheet, 100);
    EXPECT_LT(well_ref / well, 0.35) << "reference: the bottom of a deep well is dark";
    // Known limit of volumetric occlusion (docs/ao.md): spheres wider than the well see its opening as
    // open volume, so the cone tracer under-occludes deep narrow cavities (measured 0.22 here).
    EXPECT_NEAR(well_cone / well, well_ref / well, 0.3) << "deep cavity";
    EXPECT_LT(sheet_ref / sheet, 0.9) << "reference: the sheet occludes the floor beside it";
    EXPECT_NEAR(sheet_cone / sheet, sheet_ref / sheet, 0.15) << "thin sheet (0.3 mm, under one voxel)";
    std::printf("well: cone %.3f ref %.3f; beside the sheet: cone %.3f ref %.3f\n", well_cone / well, well_ref / well,
                sheet_cone / sheet, sheet_ref / sheet);
}

TEST_F(ConeAoStress, NearPlaneEmptySceneAndSingleTriangle) {
    {
        // The near plane cuts through the object: nothing is clipped from the slicemap (depth clamp), values stay finite.
        Renderer ren;
        ren.add(sphere_mesh({0, 0, 0}, 40, 2.0), {});
        ren.add(test::flat_box_mesh({-100, 30, -100}, {100, 40, 100}), {});
        const Camera cam = looking({0, -45, 0}, {0, 0, 0}, {0, 0, 1}, 10, 500);
        const auto img = ren.render(cam, ao_options(96, 20)).image;
        std::size_t finite = 0;
        for (float v : img.floats)
            if (std::isfinite(v)) {
                ++finite;
                ASSERT_GE(v, 0.0f);
                ASSERT_LE(v, 1.0f);
            }
        EXPECT_GT(finite, 1000u);
    }
    {
        Renderer ren;
        const Camera cam = looking({0, -300, 0}, {0, 0, 0}, {0, 0, 1});
        const auto img = ren.render(cam, ao_options(32, 10)).image;
        for (float v : img.floats) ASSERT_TRUE(std::isnan(v)) << "empty scene: all background";
        RenderOptions o;
        o.width = o.height = 32;
        o.look.ao = AoMethod::Cone;
        EXPECT_NO_THROW(ren.render(cam, o));
    }
    {
        Renderer ren;
        Mesh t;
        t.positions = {{-50, 0, -50}, {50, 0, -50}, {0, 0, 50}, {0, 0, 0}};
        t.triangles = {{0, 1, 2}, {3, 3, 3}}; // and a degenerate one
        ren.add(t, {});
        const Camera cam = looking({10, -200, 5}, {0, 0, 0}, {0, 0, 1});
        const auto img = ren.render(cam, ao_options(64, 10)).image;
        std::size_t n = 0;
        for (float v : img.floats)
            if (std::isfinite(v)) {
                ++n;
                EXPECT_GT(v, 0.97f) << "nothing occludes a lone triangle";
            }
        EXPECT_GT(n, 300u);
    }
}
