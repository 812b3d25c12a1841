// VOIT on a real GL context against the exact CPU reference (Embree, every
// hit along each pixel's ray, composited in double precision; flat shading
// so each fragment is its albedo): per-pixel list lengths equal the depth
// complexity, composites match to 8-bit output for nested spheres, 1, 2,
// 255 and 1000 layers (the local-array sort and the long-list fallback),
// coplanar ties, alpha 0, a surface through the near plane; a pool past its
// cap merges what does not fit within its stated error bound and stays
// bounded; the pool grows by redrawing; translucent fragments get their own AO.
#include <algorithm>
#include <cstdio>
#include <cmath>
#include <numeric>
#include <random>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/gpu/renderer.hpp"
#include "tests/support/transparency_reference.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/scenes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using namespace iso::test;
using Voit = test::GlTest;

namespace {

struct Layer {
    Mesh mesh;
    glm::vec3 color;
    float opacity;
};

struct Comparison {
    double rmse = 0, max = 0;
    std::size_t foreground = 0;
};

// Adds the layers to the renderer; the same surfaces for the reference.
std::vector<ReferenceSurface> add_layers(Renderer& ren, const std::vector<Layer>& layers) {
    std::vector<ReferenceSurface> ref;
    for (const auto& l : layers) {
        SceneObject o;
        o.color = l.color;
        o.opacity = l.opacity;
        ren.add(l.mesh, o);
        ref.push_back({&l.mesh, l.color, l.opacity});
    }
    return ref;
}

// Renders the layers (flat shading) and compares with the reference over foreground pixels, in sRGB units [0, 1].
Comparison compare(const std::vector<Layer>& layers, const Camera& cam, int size, RenderResult* out = nullptr,
                   const RenderHooks& hooks = {}) {
    Renderer ren;
    const std::vector<ReferenceSurface> ref = add_layers(ren, layers);
    RenderOptions o;
    o.width = o.height = size;
    o.look.aa.samples = 1; // compositing per pixel centre, as the reference traces it
    o.look.flat_shading = true;
    o.look.oit_epsilon = 0.0f; // composite everything: the reference has no early exit
    auto r = ren.render(cam, o, hooks);
    const auto bg = glm::dvec3(o.look.background);
    const TransparencyImage t = transparency_reference(ref, cam, size, size, bg);
    Comparison c;
    double sum = 0;
    for (std::size_t p = 0; p < t.linear.size(); ++p) {
        if (!t.foreground[p]) continue;
        ++c.foreground;
        for (int k = 0; k < 3; ++k) {
            const double e = std::abs(r.image.bytes[p * 4 + std::size_t(k)] / 255.0 - srgb_encode(t.linear[p][k]));
            sum += e * e;
            c.max = std::max(c.max, e);
        }
    }
    c.rmse = c.foreground ? std::sqrt(sum / double(3 * c.foreground)) : 0.0;
    if (out) *out = std::move(r);
    return c;
}

} // namespace

TEST_F(Voit, ListLengthsAreTheDepthComplexityOfNestedSpheres) {
    std::vector<Layer> layers;
    for (double r : {10.0, 20.0, 30.0}) layers.push_back({sphere_mesh(glm::dvec3(0), r), {0.6f, 0.4f, 0.2f}, 0.3f});
    const Camera cam = anterior(box(30));
    RenderResult r;
    RenderHooks hooks;
    hooks.read_oit_lists = true;
    compare(layers, cam, 64, &r, hooks);
    std::vector<ReferenceSurface> ref;
    for (const auto& l : layers) ref.push_back({&l.mesh, l.color, l.opacity});
    const TransparencyImage t = transparency_reference(ref, cam, 64, 64, glm::dvec3(0));
    ASSERT_EQ(r.oit_lists.size(), t.hits.size());
    std::size_t differ = 0;
    for (std::size_t p = 0; p < t.hits.size(); ++p) differ += r.oit_lists[p] != t.hits[p];
    EXPECT_EQ(r.oit_lists[32 * 64 + 32], 6u) << "three closed spheres: six crossings through the centre";
    EXPECT_EQ(t.hits[32 * 64 + 32], 6u);
    // Rasterizer and ray tracer may disagree only where a pixel centre grazes a silhouette.
    EXPECT_LE(differ, std::size_t(64 * 64 / 100)) << differ << " pixels differ";
    EXPECT_EQ(r.oit.max_list, 6u);
    EXPECT_EQ(r.oit.merged, 0u);
    EXPECT_EQ(r.oit.fragments, std::accumulate(r.oit_lists.begin(), r.oit_lists.end(), std::uint64_t(0)));
}

TEST_F(Voit, NestedSpheresOverAnOpaqueCoreMatchTheReference) {
    std::vector<Layer> layers;
    layers.push_back({sphere_mesh(glm::dvec3(0), 8), {0.8f, 0.2f, 0.2f}, 1.0f}); // opaque core (albedo exact in 8 bits)
    layers.push_back({sphere_mesh(glm::dvec3(0), 18), {0.2f, 0.6f, 0.9f}, 0.5f});
    layers.push_back({sphere_mesh(glm::dvec3(0), 28), {0.9f, 0.9f, 0.3f}, 0.3f});
    const auto c = compare(layers, anterior(box(28)), 96);
    EXPECT_GT(c.foreground, 2000u);
    EXPECT_LE(c.rmse, 0.003) << "max " << c.max;
    EXPECT_LE(c.max, 0.02) << "rmse " << c.rmse; // silhouette pixels may see one crossing more or less
}

TEST_F(Voit, SortsOneTwoManyAndVeryManyLayers) {
    for (const int n : {1, 2, 32, 33, 255, 1000}) { // 32: the local-array sort's limit; 33 and up: the merge sort
        SCOPED_TRACE(std::to_string(n) + " layers");
        std::vector<Layer> layers;
        // Alpha small enough that all layers reach the pixel (0.996^1000 = 0.018).
        const float alpha = n <= 2 ? 0.5f : 0.004f * (1000.0f / float(n));
        for (int i = 0; i < n; ++i) {
            const float f = float(i) / float(std::max(n - 1, 1));
            layers.push_back({plate(-20.0 + 40.0 * i / std::max(n - 1, 1), 20), {f, 1.0f - f, 0.5f}, alpha});
        }
        // Drawn in a shuffled order: the lists arrive out of depth order.
        std::shuffle(layers.begin(), layers.end(), std::mt19937(7));
        RenderResult r;
        const auto c = compare(layers, anterior(box(20)), 16, &r);
        EXPECT_GT(c.foreground, 50u);
        EXPECT_LE(c.max, 2.0 / 255.0) << "rmse " << c.rmse;
        std::printf(
            "%d layers: foreground %zu, rmse %.5f, max %.5f, max list %u, fragments %llu, shaded %llu, redraws %d\n", n,
            c.foreground, c.rmse, c.max, r.oit.max_list, (unsigned long long)r.oit.fragments,
            (unsigned long long)r.oit.shaded, r.oit.redraws);
        EXPECT_EQ(r.oit.max_list, std::uint32_t(n));
        EXPECT_EQ(r.oit.merged, 0u);
        if (n == 1000) {
            EXPECT_GE(r.oit.redraws, 1) << "75k fragments outgrow the first 64k-node pool: one redraw";
        }
    }
}

TEST_F(Voit, CoplanarLayersAlphaZeroAndTheNearPlane) {
    // Two coplanar plates: the tie goes to the object added first, on both sides.
    std::vector<Layer> layers{{plate(0, 10), {0.9f, 0.1f, 0.1f}, 0.5f},
                              {plate(0, 10), {0.1f, 0.1f, 0.9f}, 0.5f},
                              {plate(-5, 6), {0.0f, 1.0f, 0.0f}, 0.0f}}; // alpha 0: as if absent
    const Camera cam = anterior(box(10));
    auto c = compare(layers, cam, 32);
    EXPECT_LE(c.max, 2.0 / 255.0);
    // A plate reaching through the near plane: the part in front is clipped on both sides.
    Camera near_cut = cam;
    near_cut.near_plane =
        glm::length(cam.eye - cam.target) - 3.0; // the plane at y = -3 lies in front of the near plane
    std::vector<Layer> tilted{{plate(0, 10), {0.9f, 0.6f, 0.2f}, 0.6f}};
    tilted[0].mesh.positions[0].y = -30; // one corner far in front: the plate crosses the near plane
    tilted[0].mesh.positions[3].y = -30;
    c = compare(tilted, near_cut, 32);
    EXPECT_LE(c.max, 2.0 / 255.0);
}

// Past the cap, what does not fit is merged behind each pixel's list and
// the frame states an error bound; the composite stays within it of the
// exact reference, and the pool within the cap.
TEST_F(Voit, PastTheCapFragmentsAreMergedWithinTheirStatedBound) {
    std::vector<Layer> layers;
    for (int i = 0; i < 200; ++i) {
        const float f = float(i % 7) / 6.0f; // colours vary along depth: the order matters
        layers.push_back({plate(-20.0 + 0.2 * i, 10), {f, 0.5f, 1.0f - f}, 0.02f});
    }
    std::shuffle(layers.begin(), layers.end(),
                 std::mt19937(3)); // added out of depth order: the renderer orders the draws
    Renderer ren;
    const std::vector<ReferenceSurface> ref = add_layers(ren, layers);
    RenderOptions o;
    o.width = o.height = 128;
    o.look.flat_shading = true;
    o.look.oit_epsilon = 0.0f;
    o.look.oit_memory_mib = 1; // 52428 nodes for 200 layers x ~4000 pixels
    const Camera cam = anterior(box(20));
    const auto r = ren.render(cam, o);
    EXPECT_EQ(r.oit.capacity, (std::size_t(1) << 20) / 20);
    EXPECT_GT(r.oit.merged, 0u);
    EXPECT_LE(r.oit.fragments - r.oit.merged, r.oit.capacity) << "what is stored fits";
    EXPECT_GT(r.oit.fragments - r.oit.merged, r.oit.capacity / 2)
        << "and fills the pool to a fair part (whole depth bins)";
    EXPECT_EQ(r.oit.overflowed, 0u) << "the depth cut made room: nothing found the pool full";
    EXPECT_GE(r.oit.redraws, 1) << "the frame that found the cap too small was drawn again with the cut";
    EXPECT_GT(r.oit.merged_pixels, 1000u);
    EXPECT_LE(ren.pool().stats().live_bytes, std::size_t(8) << 20)
        << "the pool stays within the cap plus the frame's images";
    // The bound: the transmittance reaching the merged layers times their
    // coverage; about 0.98^26 x (1 - 0.98^174) where 26 layers are kept.
    EXPECT_GT(r.oit.merge_error_max, 0.3);
    EXPECT_LE(r.oit.merge_error_max, 1.0);
    const TransparencyImage t = transparency_reference(ref, cam, 128, 128, glm::dvec3(o.look.background));
    double worst = 0, sum = 0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < t.linear.size(); ++p) {
        if (!t.foreground[p]) continue;
        for (int k = 0; k < 3; ++k) {
            const double e = std::abs(srgb_decode(r.image.bytes[p * 4 + std::size_t(k)] / 255.0) - t.linear[p][k]);
            worst = std::max(worst, e);
            sum += e;
        }
        ++n;
    }
    std::printf("merged %llu fragments in %llu pixels, stated bound %.3f; linear error max %.4f, mean %.4f\n",
                (unsigned long long)r.oit.merged, (unsigned long long)r.oit.merged_pixels, r.oit.merge_error_max, worst,
                sum / double(3 * n));
    EXPECT_LE(worst, r.oit.merge_error_max + 0.01) << "within the stated bound (plus 8-bit output)";
    // The nearest layers are stored, and only the merged ones' order among
    // themselves is lost: far better than the bound.
    EXPECT_LE(worst, 0.01);
    // The next frame starts with the cut: no redraw.
    const auto again = ren.render(cam, o);
    EXPECT_EQ(again.oit.redraws, 0);
    EXPECT_EQ(again.oit.overflowed, 0u);
    EXPECT_EQ(again.oit.merged, r.oit.merged);
}

TEST_F(Voit, AllOpaqueScenesRunNoListPasses) {
    Renderer ren;
    ren.add(plate(0, 10), {});
    RenderOptions o;
    o.width = o.height = 16;
    const auto r = ren.render(anterior(box(10)), o);
    for (const auto& p : r.stats.passes) EXPECT_TRUE(p.name.rfind("oit_", 0) != 0) << p.name;
    EXPECT_EQ(r.oit.fragments, 0u);
}

// Translucent fragments trace their own AO with the opaque surfaces' cones:
// a slab next to an opaque ball looks the same (to 8 bits, up to the
// slicemap's voxels) whether it is drawn opaque (G-buffer, cone AO pass) or
// at opacity 0.9999 (VOIT, its own AO per fragment); and that AO is real:
// the slab darkens around the ball.
TEST_F(Voit, TranslucentFragmentsGetTheirOwnAo) {
    const Mesh slab = flat_box_mesh({-15, 0, -15}, {15, 6, 15}); // front face y = 0, facing the anterior camera
    const Mesh ball = sphere_mesh(glm::dvec3(0), 4.0, 0.5);
    Mesh near_ball = ball;
    for (auto& p : near_ball.positions) p += glm::vec3(0, -5.5f, 0); // 1.5 mm in front of the slab
    const Mesh backdrop = plate(25, 40);                             // opaque: the same z range in both frames
    const Camera cam = anterior(box(16));
    auto render = [&](float slab_opacity, bool ao, Aov aov = Aov::None) {
        Renderer ren;
        SceneObject s;
        s.color = {0.8f, 0.7f, 0.6f};
        s.opacity = slab_opacity;
        ren.add(slab, s);
        ren.add(near_ball, {});
        ren.add(backdrop, {});
        RenderOptions o;
        o.width = o.height = 96;
        o.look.aa.samples = 1; // the slab's pixels as the id AOV finds them (no blend with the ball's edge)
        o.look.ao = ao ? AoMethod::Cone : AoMethod::Off;
        o.aov = aov;
        o.look.cone.resolution = 1.0; // the cone pass at full size, as the fragments are traced
        o.look.cone.radius_mm = 8.0;
        o.look.cone.strength = 4.0; // the ambient term is small: make its occlusion show in 8 bits
        return ren.render(cam, o);
    };
    const auto ids = render(1.0f, false, Aov::Id);
    const auto opaque = render(1.0f, true), translucent = render(0.9999f, true), no_ao = render(0.9999f, false);
    ASSERT_TRUE(ids.image.is_float);
    EXPECT_GT(translucent.oit.fragments, 1000u);
    std::vector<std::string> names;
    for (const auto& p : translucent.stats.passes) names.push_back(p.name);
    EXPECT_NE(std::find(names.begin(), names.end(), "oit_ao"), names.end());
    // The slab's front face is flat and evenly lit: across it, only AO varies the colour.
    double sum = 0;
    int lo[2] = {255, 255}, hi[2] = {0, 0}; // red channel, with and without AO
    std::size_t n = 0;
    for (std::size_t p = 0; p < std::size_t(96 * 96); ++p) {
        if (ids.image.floats[p * std::size_t(ids.image.channels)] != 1.0f)
            continue; // slab pixels (object 1) not hidden by the ball
        for (int k = 0; k < 3; ++k) {
            const double a = opaque.image.bytes[p * 4 + std::size_t(k)],
                         b = translucent.image.bytes[p * 4 + std::size_t(k)];
            sum += std::abs(a - b);
        }
        int i = 0;
        for (const auto* img : {&translucent.image, &no_ao.image}) {
            lo[i] = std::min(lo[i], int(img->bytes[p * 4]));
            hi[i] = std::max(hi[i], int(img->bytes[p * 4]));
            ++i;
        }
        ++n;
    }
    ASSERT_GT(n, 2000u);
    const double mean = sum / double(3 * n) / 255.0;
    std::printf("slab pixels %zu: mean |opaque - translucent| %.4f; red range with AO %d..%d, without %d..%d\n", n,
                mean, lo[0], hi[0], lo[1], hi[1]);
    EXPECT_LE(mean, 2.0 / 255.0);
    EXPECT_LE(hi[1] - lo[1], 2) << "without AO the face is evenly lit";
    EXPECT_GE(hi[0] - lo[0], 8) << "the ball occludes the slab around it (AO 1 to 0 spans 14 levels here)";
}

// RenderOptions::transparency off (the desktop app's toggle): a translucent
// plate in front of an opaque one is drawn as if it were opaque, byte for
// byte, with no list passes; the object's opacity is left as it was.
TEST_F(Voit, TransparencyOffDrawsEveryObjectOpaque) {
    auto render = [&](float front_opacity, bool transparency) {
        Renderer ren;
        SceneObject front;
        front.color = {0.8f, 0.3f, 0.2f};
        front.opacity = front_opacity;
        ren.add(plate(0, 10), front);
        ren.add(plate(5, 20), {});
        RenderOptions o;
        o.width = o.height = 48;
        o.look.transparency = transparency;
        auto r = ren.render(anterior(box(20)), o);
        EXPECT_EQ(ren.object(1).opacity, front_opacity);
        return r;
    };
    const auto translucent = render(0.3f, true), forced = render(0.3f, false), opaque = render(1.0f, true);
    EXPECT_GT(translucent.oit.fragments, 100u);
    EXPECT_EQ(forced.oit.fragments, 0u);
    for (const auto& p : forced.stats.passes) EXPECT_TRUE(p.name.rfind("oit_", 0) != 0) << p.name;
    ASSERT_FALSE(forced.image.bytes.empty());
    EXPECT_EQ(forced.image.bytes, opaque.image.bytes);
    EXPECT_NE(forced.image.bytes, translucent.image.bytes);
}
