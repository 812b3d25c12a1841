// Ray-traced AO in the GL frame (docs/ao.md, "Ray-traced AO in the shaded
// image"): an AO image made outside the frame is uploaded (rows flipped to
// GL's order) and read back exactly as the ao AOV, lights the colour image
// where it says, lines up with the depth AOV; core::render_image traces it
// once, before the frame, caches it and writes what it did in the metadata.
#include <cmath>

#include <gtest/gtest.h>

#include "gl_test.hpp"
#include "renderer/ao/progressive.hpp"
#include "renderer/core/api.hpp"
#include "renderer/gpu/renderer.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/scenes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using RaytracedAo = test::GlTest;

namespace {

// A slab seen from above, filling the view.
struct Slab {
    Renderer ren;
    Mesh mesh = test::box_mesh({-100, -100, -10}, {100, 100, 0});
    Camera cam = test::looking({0, 0, 150}, {0, 0, 0}, {0, 1, 0});
    Slab() { ren.add(mesh, {}); }
};

Image ao_image(int w, int h, float top, float bottom) {
    Image img;
    img.width = w;
    img.height = h;
    img.channels = 1;
    img.is_float = true;
    img.floats.resize(std::size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) img.floats[std::size_t(y) * w + x] = y < h / 2 ? top : bottom;
    return img;
}

} // namespace

TEST_F(RaytracedAo, TheImageIsUploadedAsGivenAndLightsWhereItSays) {
    Slab s;
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.look.ao = AoMethod::Raytraced;
    Image ao = ao_image(o.width, o.height, 0.0f, 1.0f); // the image's top half fully occluded
    ao.floats[5] = 0.25f;
    ao.floats[o.width * 40 + 7] = NAN;
    o.ao_image = &ao;
    o.aov = Aov::Ao;
    const Image back = s.ren.render(s.cam, o).image;
    ASSERT_EQ(back.floats.size(), ao.floats.size());
    for (std::size_t i = 0; i < ao.floats.size(); ++i) {
        if (std::isnan(ao.floats[i]))
            EXPECT_TRUE(std::isnan(back.floats[i]));
        else
            ASSERT_EQ(back.floats[i], ao.floats[i]) << "pixel " << i;
    }
    // The colour image: dark at the top (ambient light occluded), lit at the
    // bottom, the NaN pixel lit as unoccluded.
    o.aov = Aov::None;
    const Image lit = s.ren.render(s.cam, o).image;
    const auto px = [&](int x, int y) { return int(lit.bytes[(std::size_t(y) * o.width + x) * 4]); };
    EXPECT_LT(px(30, 5), px(30, 40) - 10) << "occluded rows read darker";
    EXPECT_EQ(px(7, 40), px(8, 40)) << "NaN is taken as unoccluded";
    // A still frame draws nothing new: the import's texture comes from the pool.
    const auto before = s.ren.gl_objects_created();
    s.ren.render(s.cam, o);
    EXPECT_EQ(s.ren.gl_objects_created(), before);
    // The wrong size is refused, naming the method.
    Image small = ao_image(8, 8, 1, 1);
    o.ao_image = &small;
    try {
        s.ren.render(s.cam, o);
        ADD_FAILURE() << "an AO image of another size was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("ray-traced AO"), std::string::npos) << e.what();
    }
}

// The ray-traced image's rows are the depth AOV's: the background (NaN)
// where the depth is infinite, pixel for pixel but the silhouette.
TEST_F(RaytracedAo, RowsLineUpWithTheDepthAov) {
    Renderer ren;
    const Mesh m = test::box_mesh({-20, -10, 0}, {20, 30, 10}); // off centre: a flip would show
    ren.add(m, {});
    const Camera cam = test::looking({0, 0, 150}, {0, 0, 0}, {0, 1, 0});
    RenderOptions o;
    o.width = 80;
    o.height = 60;
    o.aov = Aov::Depth;
    const Image depth = ren.render(cam, o).image;
    const AoReference tracer({&m});
    ProgressiveAoOptions po;
    po.max_rays = 8;
    ProgressiveAo ao(tracer, cam, o.width, o.height, po);
    ao.add_batch();
    const Image img = ao.image();
    std::size_t fg = 0, hits = 0, agree = 0;
    for (std::size_t i = 0; i < depth.floats.size(); ++i) {
        const bool a = std::isfinite(depth.floats[i]), b = !std::isnan(img.floats[i]);
        fg += a;
        hits += b;
        agree += a == b;
    }
    EXPECT_GT(fg, 500u);
    // A flipped image would miss the off-centre box's rows by hundreds of pixels.
    EXPECT_GE(agree + 2 * (o.width + o.height) / 4, depth.floats.size()) << "at most the silhouette differs";
    EXPECT_NEAR(double(hits), double(fg), 0.5 * (o.width + o.height));
    // And the hit points' depth along the view axis is the depth AOV's.
    int compared = 0;
    for (std::size_t i = 0; i < depth.floats.size(); ++i)
        if (const auto sf = ao.surface(i); sf && std::isfinite(depth.floats[i])) {
            const double d = glm::dot(sf->first - cam.eye, cam.forward());
            if (std::abs(d - depth.floats[i]) < 0.05) ++compared;
        }
    EXPECT_GE(compared, int(fg) - 2 * (o.width + o.height));
}

// core::render_image with raytraced AO: the colour image lit with it, the
// term cached (the second call hits), the metadata says what was traced.
TEST_F(RaytracedAo, RenderImageTracesOnceCachesAndRecords) {
    test::TempDir dir;
    core::Scene scene;
    scene.add_mesh(test::box_mesh({-100, -100, -10}, {100, 100, 0}), {});
    scene.add_mesh(test::box_mesh({-20, -20, 0}, {20, 20, 40}), {});
    core::RenderRequest rq;
    rq.width = 64;
    rq.height = 64;
    rq.view = "superior";
    rq.annotations = false;
    rq.look.ao = AoMethod::Raytraced;
    rq.look.cone.radius_mm = 20;
    rq.look.ao_rays = 256;
    rq.look.ao_error = 0.02;
    // One sample per pixel: the ring is counted pixel by pixel (anti-aliasing
    // blends the block's edge pixels with the ring).
    rq.look.aa.samples = 1;
    rq.look.aa.frames = 1;
    rq.cache_dir = dir / "cache";
    const auto first = core::render_image(scene, rq);
    EXPECT_FALSE(first.ao_cache_hit);
    const auto second = core::render_image(scene, rq);
    EXPECT_TRUE(second.ao_cache_hit);
    EXPECT_EQ(first.image.bytes, second.image.bytes);
    EXPECT_EQ(first.meta.text.at("isoscope:ao_rays_traced"), second.meta.text.at("isoscope:ao_rays_traced"));
    EXPECT_NE(second.meta.text.at("isoscope:ao_parameters").find("from the cache"), std::string::npos);
    rq.look.ao = AoMethod::Off;
    const auto off = core::render_image(scene, rq);
    EXPECT_NE(first.image.bytes, off.image.bytes) << "the ray-traced term lit the image";
    // The slab's ring around the block's foot is darker with it.
    std::size_t darker = 0;
    for (std::size_t i = 0; i < off.image.bytes.size(); i += 4) darker += first.image.bytes[i] + 6 < off.image.bytes[i];
    EXPECT_GT(darker, 30u);
}
