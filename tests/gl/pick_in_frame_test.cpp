// The pick of a live view (core::pick_in_frame, core::resolve_pick;
// docs/picking.md "A live view"): a view that draws the scene with its own GL
// context picks on a frame of its own, without uploading the scene again, and
// gets what core::pick (render_image's one-off frame) gives for the same
// camera and image size, field for field. Both resolve through
// core::resolve_pick, so positions agree bit for bit; what could differ is the
// frame: its lists (presented into the view's framebuffer, with AO, after
// other frames) and the camera handed over.
#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "io/error.hpp"
#include "renderer/core/pick.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using PickInFrame = test::GlTest;

namespace {

void expect_same(const core::PickResult& a, const core::PickResult& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.view, b.view);
    EXPECT_EQ(a.projection, b.projection);
    EXPECT_EQ(a.visible, b.visible);
    EXPECT_EQ(a.complete, b.complete);
    ASSERT_EQ(a.layers.size(), b.layers.size());
    for (std::size_t i = 0; i < a.layers.size(); ++i) {
        const auto &x = a.layers[i], &y = b.layers[i];
        SCOPED_TRACE("layer " + std::to_string(i));
        EXPECT_EQ(x.surface, y.surface);
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.triangle, y.triangle);
        EXPECT_EQ(x.lps, y.lps); // the same ray meets the same triangle: bit for bit
        EXPECT_EQ(x.normal, y.normal);
        EXPECT_EQ(x.on_triangle, y.on_triangle);
        EXPECT_EQ(x.depth_mm, y.depth_mm);
        EXPECT_EQ(x.alpha, y.alpha);
        EXPECT_EQ(x.share, y.share);
        EXPECT_EQ(x.value, y.value);
        EXPECT_EQ(x.unit, y.unit);
        EXPECT_EQ(x.voxel, y.voxel);
    }
    EXPECT_EQ(a.rect.x, b.rect.x);
    EXPECT_EQ(a.rect.width, b.rect.width);
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    for (std::size_t i = 0; i < a.triangles.size(); ++i) {
        EXPECT_EQ(a.triangles[i].surface, b.triangles[i].surface);
        EXPECT_EQ(a.triangles[i].triangle, b.triangles[i].triangle);
        EXPECT_EQ(a.triangles[i].pixels, b.triangles[i].pixels);
    }
}

} // namespace

TEST_F(PickInFrame, ALiveViewPicksWhatCorePickGivesWithoutUploadingAgain) {
    // The bundled CT, skin at opacity 0.3 over the bone: the visible layer is
    // found through a translucent one (docs/picking.md).
    core::Scene scene;
    scene.open(test::data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    scene.info(ids[0]).opacity = 0.3f;
    constexpr int W = 240, H = 200; // not square: the aspect must be the same in both
    core::RenderRequest req;
    req.width = W;
    req.height = H;
    req.annotations = false;
    // Forehead, cheek, eye, a background corner; one with a rectangle.
    std::vector<core::PickRequest> picks;
    for (const auto& [x, y] : std::vector<std::pair<int, int>>{{120, 55}, {95, 100}, {150, 90}, {3, 3}}) {
        core::PickRequest p;
        p.x = x;
        p.y = y;
        p.all_layers = true;
        picks.push_back(p);
    }
    picks[1].rect = {88, 94, 12, 10};

    // core::pick first: render_image makes its own context current and frees
    // the scene's GPU data at the end of each call.
    std::vector<core::PickResult> expected;
    for (const auto& p : picks) expected.push_back(core::pick(scene, req, p));
    int seen = 0;
    for (const auto& r : expected) seen += r.visible.has_value();
    ASSERT_GE(seen, 3) << "the pixels should see the head";
    EXPECT_FALSE(expected[3].visible) << "the corner is background";

    // The live view: this test's context, the same camera render_image used
    // (the scene's for the view, at the image's aspect), the view's own frame
    // options (presented into its framebuffer, AO on), a frame drawn first.
    test::gl_context().make_current();
    const Camera cam = scene.camera(PatientView::Anterior, double(W) / double(H));
    auto target = gl::Texture::create_2d(GL_RGBA8, W, H);
    auto fb = gl::Framebuffer::create();
    fb.attach(GL_COLOR_ATTACHMENT0, target);
    RenderOptions view;
    view.width = W;
    view.height = H;
    view.present = true;
    view.target_framebuffer = fb.id();
    view.look.ao = AoMethod::Cone;
    scene.render(cam, view);
    for (std::size_t i = 0; i < picks.size(); ++i) {
        SCOPED_TRACE("pixel " + std::to_string(picks[i].x) + "," + std::to_string(picks[i].y));
        const core::PickResult live = core::pick_in_frame(scene, cam, view, picks[i]);
        expect_same(live, expected[i]);
        EXPECT_GT(live.frame_ms, 0.0);
        scene.render(cam, view); // the view's next frame, between picks
    }
    // Picks of one pixel after the first make no GL object: the meshes stay
    // uploaded, the pick's buffers (sized by the region) are reused.
    const std::size_t objects = scene.renderer().gl_objects_created();
    for (int k = 0; k < 3; ++k) {
        const auto again = core::pick_in_frame(scene, cam, view, picks[std::size_t(k) % 2 ? 2 : 0]);
        expect_same(again, expected[std::size_t(k) % 2 ? 2 : 0]);
        scene.render(cam, view);
    }
    EXPECT_EQ(scene.renderer().gl_objects_created(), objects) << "a pick in the live view uploaded or made GL objects";
    // The threshold and the layers asked for apply as in core::pick.
    core::PickRequest front = picks[0];
    front.all_layers = false;
    front.threshold = 0.25;
    const auto r = core::pick_in_frame(scene, cam, view, front);
    ASSERT_TRUE(r.visible);
    EXPECT_EQ(*r.visible, 0u) << "at threshold 0.25 the skin (0.3) is what is seen";
    EXPECT_EQ(r.layers.size(), 1u);
    EXPECT_EQ(r.layers[0].name, "iso 500");
    scene.release_gpu(); // with its context current
}

TEST_F(PickInFrame, ResolveRefusesAListThatCannotAnswer) {
    core::Scene scene;
    Mesh m;
    m.positions = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
    m.triangles = {{0, 1, 2}};
    core::SurfaceInfo info;
    info.name = "triangle";
    scene.add_mesh(m, info);
    const Camera cam = scene.camera(PatientView::Superior, 1.0);
    core::PickRequest p;
    p.x = 5;
    p.y = 6;
    // A frame without a pick, one listing other pixels, a pixel off the image, a bad threshold.
    PickList none;
    EXPECT_THROW(core::resolve_pick(scene, cam, 64, 64, none, p), Error);
    PickList other;
    other.region = {20, 20, 2, 2};
    other.pixels.resize(4);
    EXPECT_THROW(core::resolve_pick(scene, cam, 64, 64, other, p), Error);
    PickList ok;
    ok.region = core::pick_region(p);
    ok.pixels.resize(1);
    EXPECT_NO_THROW(core::resolve_pick(scene, cam, 64, 64, ok, p));
    p.rect = {4, 4, 8, 8}; // the rectangle is not listed
    EXPECT_THROW(core::resolve_pick(scene, cam, 64, 64, ok, p), Error);
    ok.region = core::pick_region(p);
    EXPECT_EQ(ok.region.x, 4);
    EXPECT_EQ(ok.region.width, 8);
    ok.pixels.resize(64);
    EXPECT_NO_THROW(core::resolve_pick(scene, cam, 64, 64, ok, p));
    core::PickRequest off;
    off.x = 64;
    EXPECT_THROW(core::resolve_pick(scene, cam, 64, 64, ok, off), Error);
    core::PickRequest bad = p;
    bad.threshold = 0;
    EXPECT_THROW(core::resolve_pick(scene, cam, 64, 64, ok, bad), Error);
    // The same refusals from the live view's entry point.
    test::gl_context().make_current();
    RenderOptions o;
    o.width = o.height = 64;
    EXPECT_THROW(core::pick_in_frame(scene, cam, o, off), Error);
    const auto hit = core::pick_in_frame(scene, cam, o, p);
    EXPECT_EQ(hit.width, 64);
    scene.release_gpu();
}
