// A session's render (core::open_session + core::session_request +
// core::render_image, which `isoscope render --session` and the desktop
// app's File > Export image both do) equals render_image of a scene built by
// hand in the same state (same surfaces, colours, opacities, camera,
// markups), and the CLI writes the same pixels with the session named in
// the metadata.
#include <filesystem>

#include "io/image.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/session.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::differing;
using iso::test::TempDir;

namespace {

core::Session head_session() {
    core::Session s;
    s.input = std::filesystem::absolute(test::data("headsq.nhdr")).lexically_normal().string();
    core::SessionSurface skin;
    skin.value = 500;
    skin.name = "skin";
    skin.source = s.input;
    skin.color = "#e8b49a";
    skin.opacity = 0.3f;
    core::SessionSurface bone = skin;
    bone.value = 1150;
    bone.name = "bone";
    bone.color = "#f4efe0";
    bone.opacity = 1.0f;
    s.surfaces = {skin, bone};
    core::Scene probe;
    probe.open(s.input);
    probe.add_isosurfaces({500});
    Camera c = probe.camera(PatientView::Anterior, 4.0 / 3.0);
    c.orbit(35, 20);
    s.camera = c;
    s.ao = AoMethod::Off;
    Markup m;
    m.type = MarkupType::Line;
    m.points.resize(2);
    m.points[0].position = c.target + glm::dvec3(-40, 0, 20);
    m.points[1].position = c.target + glm::dvec3(40, 0, -10);
    s.markups = {m};
    return s;
}

} // namespace

TEST(SessionRender, EqualsRenderImageOfTheSameStateAndTheCli) {
    TempDir dir;
    const core::Session s = head_session();
    const std::string file = dir / "s.json";
    core::save_session(s, file);
    core::RenderRequest o;
    o.width = 320;
    o.height = 240;

    // Through the session.
    auto opened = core::open_session(file);
    const auto req = core::session_request(opened.session, file, o);
    const auto a = core::render_image(*opened.scene, req);

    // By hand: the same surfaces, look, camera and markups.
    core::Scene scene;
    scene.open(test::data("headsq.nhdr"));
    const auto skin = scene.add_isosurfaces({500});
    const auto bone = scene.add_isosurfaces({1150});
    scene.info(skin[0]).color = core::linear_from_hex("#e8b49a");
    scene.info(skin[0]).opacity = 0.3f;
    scene.info(bone[0]).color = core::linear_from_hex("#f4efe0");
    scene.info(skin[0]).name = "skin"; // the session's names: the legend shows them
    scene.info(bone[0]).name = "bone";
    core::RenderRequest hand;
    hand.width = 320;
    hand.height = 240;
    hand.camera = s.camera;
    hand.markups = s.markups;
    const auto b = core::render_image(scene, hand);
    EXPECT_EQ(differing(a.image, b.image), 0u);
    // The camera is the session's (near and far fitted to the surfaces).
    EXPECT_EQ(a.camera.eye, s.camera->eye);
    EXPECT_EQ(a.camera.target, s.camera->target);
    EXPECT_EQ(a.camera.up, s.camera->up);
    EXPECT_EQ(a.meta.text.at("isoscope:session"), std::filesystem::absolute(file).string());
    EXPECT_EQ(a.meta.text.at("isoscope:session_sha256"), sha256_of_path(file));
    EXPECT_EQ(b.meta.text.count("isoscope:session"), 0u);
    // Orbited: not the anterior view's picture.
    core::RenderRequest anterior = hand;
    anterior.camera.reset();
    EXPECT_GT(differing(core::render_image(scene, anterior).image, b.image), 1000u);

    // The 3D view's transparency off: every surface opaque, as the hand-built request asks.
    {
        core::Session opaque = s;
        opaque.transparency = false;
        core::save_session(opaque, dir / "opaque.json");
        auto o2 = core::open_session(dir / "opaque.json");
        const auto c = core::render_image(*o2.scene, core::session_request(o2.session, dir / "opaque.json", o));
        core::RenderRequest hand_opaque = hand;
        hand_opaque.look.transparency = false;
        EXPECT_EQ(differing(c.image, core::render_image(scene, hand_opaque).image), 0u);
        EXPECT_GT(differing(c.image, a.image), 1000u); // the skin hides the bone now
        EXPECT_EQ(c.meta.text.count("isoscope:transparency"), 1u);
    }

    // The CLI, as a process, writes the same pixels and names the session.
    const std::string out = dir / "cli.png";
    const auto r = test::run_command(test::cli() + " render --session " + file + " --size 320x240 -o " + out, true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    ImageMetadata meta;
    const Image c = load_image(out, &meta);
    EXPECT_EQ(differing(a.image, c), 0u);
    EXPECT_EQ(meta.text["isoscope:session"], std::filesystem::absolute(file).string());
    EXPECT_EQ(meta.text["isoscope:session_sha256"], sha256_of_path(file));
    EXPECT_NE(meta.text["isoscope:markups_drawn"].find("Line"), std::string::npos);

    // --no-markups leaves them out; --view replaces the session's camera.
    const auto r2 = test::run_command(
        test::cli() + " render --session " + file + " --size 320x240 --no-markups --view anterior -o " + out, true);
    ASSERT_EQ(r2.exit_code, 0) << r2.out;
    core::RenderRequest plain = anterior;
    plain.markups.clear();
    EXPECT_EQ(differing(core::render_image(scene, plain).image, load_image(out)), 0u);
}
