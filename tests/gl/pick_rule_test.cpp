// Where a click lands (docs/picking.md, "Where a click lands"): the first
// surface along the pixel's ray whose own opacity reaches the threshold,
// else the nearest surface hit; never a layer behind that one. On nested
// shells (translucent only; translucent over opaque; a translucent shell
// above the threshold; an unpickable one) and on the bundled head (skin 500
// at 0.3 over bone 1150): where the ray meets only skin, front and back,
// the click stays on the front skin, not on the back of the head where the
// accumulated opacity of two skins (0.51) first reaches 0.5; where bone
// lies behind, it lands on the bone. The CLI's `pick --json` says the same.
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "gl_test.hpp"
#include "renderer/core/pick.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using PickRule = test::GlTest;
using iso::core::SurfaceId;
using iso::core::SurfaceInfo;

namespace {

// Concentric UV spheres about the origin, radii 30, 20, 10 (outer first).
struct Shells {
    core::Scene scene;
    std::vector<SurfaceId> ids;
    explicit Shells(const std::vector<float>& opacity) {
        const double radius[] = {30, 20, 10};
        for (std::size_t i = 0; i < opacity.size(); ++i) {
            SurfaceInfo info;
            info.name = "shell " + std::to_string(i);
            info.opacity = opacity[i];
            ids.push_back(scene.add_mesh(test::uv_sphere({0, 0, 0}, radius[i], 48, 96), info));
        }
    }
};

core::RenderRequest square_request(int size = 128) {
    core::RenderRequest req;
    req.width = req.height = size;
    req.annotations = false;
    return req;
}

// The pick at the image centre: the ray through every shell.
core::PickResult centre_pick(core::Scene& scene, double threshold = 0.5, bool all = true) {
    core::PickRequest p;
    p.x = p.y = 64;
    p.threshold = threshold;
    p.all_layers = all;
    return core::pick(scene, square_request(), p);
}

std::string visible_name(const core::PickResult& r) {
    return r.visible ? r.layers[*r.visible].name : std::string("(none)");
}

} // namespace

TEST_F(PickRule, OnlyTranslucentShellsTheClickStaysOnTheFrontOne) {
    Shells s({0.3f, 0.3f});
    const auto r = centre_pick(s.scene);
    // Outer front, inner front, inner back, outer back.
    ASSERT_EQ(r.layers.size(), 4u);
    EXPECT_GE(r.layers[1].accumulated_alpha, 0.5) << "the old rule would have landed here, on the inner shell";
    ASSERT_TRUE(r.visible);
    EXPECT_EQ(*r.visible, 0u);
    EXPECT_EQ(visible_name(r), "shell 0");
    EXPECT_NEAR(r.layers[0].depth_mm, r.layers[3].depth_mm - 60.0, 0.5) << "the front of the outer shell";
    // Without all_layers the same answer (the list runs on to find no solid one).
    EXPECT_EQ(centre_pick(s.scene, 0.5, false).visible, r.visible);
}

TEST_F(PickRule, TranslucentOverOpaqueTheClickLandsOnTheOpaqueOne) {
    Shells s({0.3f, 0.3f, 1.0f});
    const auto r = centre_pick(s.scene);
    ASSERT_TRUE(r.visible);
    EXPECT_EQ(visible_name(r), "shell 2") << "seen through two translucent shells";
    EXPECT_EQ(*r.visible + 1, r.layers.size()) << "nothing behind the opaque core is listed";
    // Without all_layers the list stops at the visible one too.
    const auto short_list = centre_pick(s.scene, 0.5, false);
    EXPECT_EQ(short_list.layers.size(), r.layers.size());
}

TEST_F(PickRule, ASolidEnoughShellIsWhereTheClickLandsAndTheThresholdIsASetting) {
    Shells s({0.3f, 0.6f, 1.0f});
    auto r = centre_pick(s.scene);
    EXPECT_EQ(visible_name(r), "shell 1") << "0.6 reaches 0.5: never the core behind it";
    r = centre_pick(s.scene, 0.7);
    EXPECT_EQ(visible_name(r), "shell 2") << "at threshold 0.7 the 0.6 shell is seen through";
    r = centre_pick(s.scene, 0.25);
    EXPECT_EQ(visible_name(r), "shell 0") << "at threshold 0.25 the 0.3 shell stops the click";
    // An unpickable surface is passed through as if absent.
    s.scene.info(s.ids[1]).pickable = false;
    r = centre_pick(s.scene);
    EXPECT_EQ(visible_name(r), "shell 2");
    for (const auto& l : r.layers) EXPECT_NE(l.name, "shell 1");
}

TEST_F(PickRule, OnTheHeadSkinOnlyRaysStayOnTheFaceAndBoneIsSeenThroughSkin) {
    core::Scene scene;
    scene.open(test::data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    scene.info(ids[0]).opacity = 0.3f;
    const auto req = square_request(256);
    // One frame lists rows 100 to 160 (the orbits, the cheeks, the mouth);
    // each pixel of three rows is resolved from it, as core::pick would.
    const Camera cam = core::frame_camera(scene, req);
    RenderOptions opt = core::frame_options(req);
    opt.pick = PickRegion{0, 100, 256, 61};
    opt.image = false;
    const RenderResult frame = scene.render(cam, opt);
    scene.release_gpu();
    int skin_only = 0, bone_behind = 0, through_head = 0;
    for (int y : {100, 130, 160})
        for (int x = 0; x < 256; x += 2) {
            core::PickRequest p;
            p.x = x;
            p.y = y;
            p.all_layers = true;
            const auto r = core::resolve_pick(scene, cam, 256, 256, frame.pick, p);
            if (r.layers.empty()) continue;
            SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
            ASSERT_TRUE(r.visible) << "a hit is never 'nothing'";
            const core::PickLayer& seen = r.layers[*r.visible];
            std::optional<std::size_t> first_bone;
            for (std::size_t i = 0; i < r.layers.size(); ++i)
                if (r.layers[i].surface == ids[1] && !first_bone) first_bone = i;
            if (first_bone) {
                EXPECT_EQ(*r.visible, *first_bone) << "bone lies behind the skin: the click lands on it";
                ++bone_behind;
            } else if (r.layers.size() >= 2) {
                EXPECT_EQ(*r.visible, 0u) << "only skin: the front skin";
                // Anterior view: the face is the smallest y (LPS: P grows backwards).
                for (const auto& l : r.layers) EXPECT_LE(seen.lps.y, l.lps.y + 1e-9);
                ++skin_only;
                // A ray through the whole head (not one grazing its side):
                // the old rule landed on the second skin layer, far behind.
                if (r.layers.back().lps.y - seen.lps.y > 60.0) {
                    EXPECT_GE(r.layers[1].accumulated_alpha, 0.5);
                    ++through_head;
                }
            }
        }
    EXPECT_GE(skin_only, 5) << "rays through the cheeks beside the bone";
    EXPECT_GE(through_head, 3) << "rays through the whole head, skin only";
    EXPECT_GE(bone_behind, 20);
}

TEST_F(PickRule, TheCliSaysTheSameAsTheCore) {
    // The left cheek beside the face bones (256 px anterior): skin only.
    core::Scene scene;
    scene.open(test::data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    scene.info(ids[0]).opacity = 0.3f;
    for (const auto& [x, y] : std::vector<std::pair<int, int>>{{128, 70}, {40, 160}, {216, 160}}) {
        core::PickRequest p;
        p.x = x;
        p.y = y;
        p.all_layers = true;
        const auto core_r = core::pick(scene, square_request(256), p);
        const auto cli = test::run_command(test::cli() + " pick " + test::data("headsq.nhdr") +
                                               " --iso 500 --iso 1150 --opacity 0.3 --size 256x256 --at " +
                                               std::to_string(x) + "," + std::to_string(y) + " --all-layers --json",
                                           false);
        ASSERT_EQ(cli.exit_code, 0) << cli.out;
        const auto j = nlohmann::json::parse(cli.out);
        SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
        ASSERT_EQ(j["layers"].size(), core_r.layers.size());
        if (!core_r.visible) {
            EXPECT_TRUE(j["visible"].is_null());
            continue;
        }
        ASSERT_TRUE(j["visible"].is_number());
        EXPECT_EQ(j["visible"].get<std::size_t>(), *core_r.visible);
        const auto lps = j["layers"][*core_r.visible]["lps"];
        EXPECT_NEAR(lps[1].get<double>(), core_r.layers[*core_r.visible].lps.y, 1e-6);
    }
}
