// Levels of detail and cluster culling in real frames (docs/lod.md;
// renderer/passes/lod_draw.cpp, shaders/render/lod_cull.comp) on the bundled
// CT's skin and bone, with the size threshold lowered so that they get
// clusters:
//   - culling is exact: at level 0 (a bound no coarser level meets), frames
//     with culling equal frames without, pixel for pixel, for the first
//     frame (no last frame: batches by distance) and the accumulated ones
//     after it (the last frame's visibility), with DSRAA's sub-samples, a
//     zoomed view that culls by the frustum, translucent skin and cone AO;
//     and the counters add up;
//   - picks stay on the full geometry: a pick with levels of detail equals
//     a pick without, triangle for triangle, bit for bit;
//   - coarser levels are drawn where the view allows (a small image), and
//     then the image stays close to the full one;
//   - a moving camera draws to the coarser bound of moving frames, and a
//     massive surface's stand-in where its error projects within it.
#include <cmath>
#include <cstdio>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/lod/cluster_lod.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/image_compare.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using Lod = test::GlTest;

namespace {

core::Scene& head() {
    static core::Scene* s = [] {
        auto* scene = new core::Scene;
        scene->open(test::data("headsq.nhdr"));
        scene->add_isosurfaces({500, 1150});
        return scene;
    }();
    return *s;
}

core::RenderRequest request(int w, int h) {
    core::RenderRequest req;
    req.width = w;
    req.height = h;
    req.annotations = false;
    req.look.lod.min_triangles = 1000; // the head's surfaces get clusters
    return req;
}

void expect_same_image(const Image& a, const Image& b, const char* what) {
    const auto c = test::compare_images(a, b, 0);
    EXPECT_TRUE(c.same_shape) << what;
    EXPECT_EQ(c.off, 0u) << what << ": " << c.off << " pixels differ (largest " << c.max_diff << ")";
}

void expect_counts_add_up(const LodStats& s) {
    EXPECT_TRUE(s.used);
    EXPECT_EQ(s.tested, s.culled_frustum + s.culled_backface + s.culled_occlusion + s.drawn);
    EXPECT_LE(s.triangles_drawn, s.triangles_full);
}

} // namespace

TEST_F(Lod, CullingAtLevelZeroDrawsWhatEveryTriangleDraws) {
    core::Scene& scene = head();
    struct Case {
        const char* name;
        core::RenderRequest req;
    };
    std::vector<Case> cases;
    auto base = request(320, 240);
    base.look.lod.error_px = 0.01; // no coarser level qualifies: level 0, culled
    base.look.aa.frames = 4;       // the first frame (no history) and three with the last one's
    base.look.aa.tolerance = 0.0;
    cases.push_back({"anterior, DSRAA, accumulated", base});
    auto left = base;
    left.view = "left";
    left.look.aa.samples = 1;
    cases.push_back({"left, one sample", left});
    auto zoomed = base;
    Camera cam = scene.camera(PatientView::Anterior, 320.0 / 240.0);
    cam.zoom(3.0);
    zoomed.camera = cam;
    cases.push_back({"zoomed in (frustum)", zoomed});
    auto skin = base;
    skin.look.ao = AoMethod::Cone;
    cases.push_back({"cone AO (voxelized levels)", skin});
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        auto off = c.req;
        off.look.lod.enabled = false;
        const auto a = core::render_image(scene, c.req), b = core::render_image(scene, off);
        expect_same_image(a.image, b.image, c.name);
        expect_counts_add_up(a.lod_first);
        expect_counts_add_up(a.lod);
        EXPECT_EQ(a.lod.triangles_full, b.lod.triangles_full);
        EXPECT_LT(a.lod.triangles_drawn, a.lod.triangles_full) << "culling drew every triangle";
        if (std::string(c.name).find("zoomed") != std::string::npos) {
            EXPECT_GT(a.lod.culled_frustum, 0u);
        }
        if (std::string(c.name).find("anterior") != std::string::npos) {
            EXPECT_GT(a.lod.culled_occlusion, 0u) << "the skin hides the bone";
            EXPECT_EQ(a.lod.phases, 2) << "frames after the first use the last one's visibility";
            EXPECT_EQ(a.lod_first.phases, 16);
        }
    }
}

TEST_F(Lod, TranslucentSurfacesAreCulledToTheViewOnly) {
    core::Scene& scene = head();
    scene.info(scene.surfaces()[0]).opacity = 0.4f;
    auto req = request(256, 256);
    req.look.lod.error_px = 0.01;
    req.look.aa.samples = 1;
    req.look.aa.frames = 1;
    auto off = req;
    off.look.lod.enabled = false;
    const auto a = core::render_image(scene, req), b = core::render_image(scene, off);
    scene.info(scene.surfaces()[0]).opacity = 1.0f;
    // Translucent fragments composite in sorted order: equal up to rounding of equal depths' order.
    const auto c = test::compare_images(a.image, b.image, 1);
    EXPECT_EQ(c.off, 0u) << c.off << " pixels differ by more than 1/255";
    expect_counts_add_up(a.lod);
}

TEST_F(Lod, PicksStayOnTheFullGeometry) {
    core::Scene& scene = head();
    auto req = request(200, 160);
    req.look.lod.error_px = 4.0; // coarse levels in the image frames
    auto off = req;
    off.look.lod.enabled = false;
    const auto shown = core::render_image(scene, req);
    ASSERT_LT(shown.lod.triangles_drawn, shown.lod.triangles_full);
    for (const auto& [x, y] : std::vector<std::pair<int, int>>{{100, 40}, {80, 90}, {120, 70}, {60, 120}, {5, 5}}) {
        SCOPED_TRACE(std::to_string(x) + "," + std::to_string(y));
        core::PickRequest p;
        p.x = x;
        p.y = y;
        p.all_layers = true;
        const auto a = core::pick(scene, req, p), b = core::pick(scene, off, p);
        ASSERT_EQ(a.layers.size(), b.layers.size());
        for (std::size_t i = 0; i < a.layers.size(); ++i) {
            EXPECT_EQ(a.layers[i].surface, b.layers[i].surface);
            EXPECT_EQ(a.layers[i].triangle, b.layers[i].triangle);
            EXPECT_EQ(a.layers[i].lps, b.layers[i].lps);
        }
        EXPECT_EQ(a.visible.has_value(), b.visible.has_value());
    }
}

TEST_F(Lod, ASmallViewDrawsCoarserLevelsCloseToTheFullImage) {
    core::Scene& scene = head();
    auto req = request(128, 128);
    Camera cam = scene.camera(PatientView::Anterior, 1.0);
    cam.zoom(0.25); // four times farther: the head spans ~30 px, its triangles far below a pixel
    req.camera = cam;
    req.look.aa.samples = 1;
    req.look.aa.frames = 1;
    req.look.lod.culling = false; // the levels alone
    req.look.lod.error_px = 2.0;
    auto off = req;
    off.look.lod.enabled = false;
    const auto a = core::render_image(scene, req), b = core::render_image(scene, off);
    EXPECT_LT(double(a.lod.triangles_drawn), 0.6 * double(a.lod.triangles_full));
    const auto c = test::compare_images(a.image, b.image, 24);
    std::printf("coarse levels: %llu of %llu triangles; %.4f of the pixels off by more than 24, mean %.3f\n",
                (unsigned long long)a.lod.triangles_drawn, (unsigned long long)a.lod.triangles_full, c.off_fraction(),
                c.mean);
    EXPECT_LT(c.off_fraction(), 0.02);
    EXPECT_LT(c.mean, 1.5);
}

// A moving camera (the 3D view's drag frames and stand-ins: RenderOptions::
// moving) draws to LodSettings::moving_error_px where that is coarser than
// error_px, and to error_px where it is not.
TEST_F(Lod, AMovingCameraDrawsToTheMovingBound) {
    core::Scene& scene = head();
    RenderOptions opt;
    opt.width = 160;
    opt.height = 160;
    opt.look.lod.min_triangles = 1000;
    opt.look.lod.culling = false; // the levels alone
    opt.look.aa.samples = 1;
    opt.look.lod.error_px = 0.5;
    opt.look.lod.moving_error_px = 4.0;
    Camera cam = scene.camera(PatientView::Anterior, 1.0);
    cam.zoom(0.5);
    const auto still = scene.render(cam, opt);
    auto moving_opt = opt;
    moving_opt.moving = true;
    const auto moving = scene.render(cam, moving_opt);
    ASSERT_TRUE(still.lod.used);
    ASSERT_TRUE(moving.lod.used);
    EXPECT_LT(double(moving.lod.triangles_drawn), 0.8 * double(still.lod.triangles_drawn)); // 57 % here
    auto coarse_still = opt;
    coarse_still.look.lod.error_px = 4.0; // the same bound in a still frame: the same levels
    EXPECT_EQ(scene.render(cam, coarse_still).lod.triangles_drawn, moving.lod.triangles_drawn);
    moving_opt.look.lod.moving_error_px = 0.25; // finer than error_px: error_px holds
    EXPECT_EQ(scene.render(cam, moving_opt).lod.triangles_drawn, still.lod.triangles_drawn);
}

// A moving frame draws a massive surface's stand-in (lod::Proxy: vertex
// clustering, for a drag's frames) where the stand-in's error, projected
// at the surface's nearest point, is within the moving bound, and its
// levels where it is not; the stand-in looks like the surface.
TEST_F(Lod, AMovingFrameDrawsTheStandInWhoseErrorProjectsWithinTheBound) {
    Mesh ball = test::sphere_mesh({0.0, 0.0, 0.0}, 60.0, 0.5);
    ASSERT_GE(ball.triangles.size(), 8u * 32768u) << "large enough for the coarsest stand-in";
    const auto levels = lod::build_cluster_lod(ball); // what the scene builds: the same options
    ASSERT_FALSE(levels.proxies.empty());
    const lod::Proxy coarsest = levels.proxies.back();
    core::Scene scene;
    core::SurfaceInfo info;
    info.name = "ball";
    scene.add_mesh(std::move(ball), info);
    RenderOptions opt;
    opt.width = opt.height = 160;
    opt.look.aa.samples = 1;
    const Camera cam = scene.camera(PatientView::Anterior, 1.0);
    // The stand-in's error in pixels at the ball's nearest point (its bounds' face).
    const double d = glm::length(glm::dvec3(cam.eye)) - 60.0;
    const double px = double(coarsest.error) * 160.0 / (2.0 * std::tan(glm::radians(cam.fov_y_degrees) / 2.0)) / d;
    std::printf("the coarsest stand-in: %u triangles, %.3f mm = %.2f px here\n", coarsest.index_count / 3,
                double(coarsest.error), px);
    ASSERT_LT(px, 60.0);
    const auto still = scene.render(cam, opt);
    auto moving = opt;
    moving.moving = true;
    moving.look.lod.moving_error_px = px * 1.02;
    const auto stand_in = scene.render(cam, moving);
    EXPECT_EQ(stand_in.lod.triangles_drawn, coarsest.index_count / 3);
    moving.look.lod.moving_error_px = px * 0.98; // just short: a finer stand-in, or the levels
    EXPECT_NE(scene.render(cam, moving).lod.triangles_drawn, coarsest.index_count / 3);
    const auto c = test::compare_images(stand_in.image, still.image, 24);
    std::printf("stand-in against the still frame: %.4f of the pixels off by more than 24, mean %.3f\n",
                c.off_fraction(), c.mean);
    EXPECT_LT(c.off_fraction(), 0.03);
    EXPECT_LT(c.mean, 2.0);
}
