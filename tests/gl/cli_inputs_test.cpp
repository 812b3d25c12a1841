// `isoscope render` and `isoscope view` open their input through the one core
// Scene: a mesh file is a mesh whatever the case of its extension (view used
// to read X.STL as a volume), a volume without --iso is refused naming the
// flag, and the CLI turns the core's setting names into its flags.
#include <cstdio>
#include <filesystem>

#include "io/image.hpp"
#include "renderer/core/scene.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

TEST(CliInputs, UpperCaseMeshExtensionsRenderAndView) {
    TempDir dir;
    const std::string mesh = dir / "BUNNY.VTP";
    fs::copy_file(test::data("bunny.vtp"), mesh);
    const auto r = test::run_command(test::cli() + " render " + mesh + " --size 64x64 -o " + (dir / "b.png"), true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_EQ(load_image(dir / "b.png").width, 64);
    if (test::run_command("command -v xvfb-run").exit_code != 0)
        GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    const auto v = test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " + mesh +
                                         " --ao off --screenshot " + (dir / "v.png"),
                                     true);
    ASSERT_EQ(v.exit_code, 0) << v.out;
    const Image shot = load_image(dir / "v.png");
    // The bunny is in the middle of the window: something other than the background there.
    std::size_t lit = 0;
    for (int y = shot.height / 3; y < 2 * shot.height / 3; ++y)
        for (int x = shot.width / 3; x < 2 * shot.width / 3; ++x) {
            const auto* p = &shot.bytes[(std::size_t(y) * shot.width + x) * shot.channels];
            lit += int(p[0]) + p[1] + p[2] > 3 * 110;
        }
    EXPECT_GT(lit, std::size_t(shot.width * shot.height / 40)) << "the bunny is not drawn";
}

TEST(CliInputs, VolumeWithoutIsoAndSettingNamesAreReportedAsFlags) {
    TempDir dir;
    const auto v = test::run_command(test::cli() + " view " + test::data("headsq.nhdr"), true);
    EXPECT_EQ(v.exit_code, 1) << v.out;
    EXPECT_NE(v.out.find("--iso"), std::string::npos) << v.out;
    const auto r =
        test::run_command(test::cli() + " render " + test::data("headsq.nhdr") + " -o " + (dir / "x.png"), true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("--iso"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("headsq.nhdr"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir / "x.png"));
    const auto bad_view = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") +
                                                " --iso 500 --view sideways -o " + (dir / "x.png"),
                                            true);
    EXPECT_EQ(bad_view.exit_code, 1);
    EXPECT_NE(bad_view.out.find("--view: unknown view 'sideways'"), std::string::npos) << bad_view.out;
    const auto bad_aov = test::run_command(
        test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --aov colour -o " + (dir / "x.exr"), true);
    EXPECT_EQ(bad_aov.exit_code, 1);
    EXPECT_NE(bad_aov.out.find("--aov: unknown AOV 'colour'"), std::string::npos) << bad_aov.out;
}

TEST(CliInputs, SurfaceColourOpacityBackgroundAndFlatShading) {
    TempDir dir;
    // Flat shading: the bone is exactly its colour, the background exactly its colour.
    const auto r = test::run_command(
        test::cli() + " render " + test::data("headsq.nhdr") +
            " --iso 1150 --color '#33cc66' --background '#102030' --shading flat --no-annotations --size 64x64 -o " +
            (dir / "flat.png"),
        true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    ImageMetadata meta;
    const Image img = load_image(dir / "flat.png", &meta);
    const auto px = [&](int x, int y) { return &img.bytes[(std::size_t(y) * img.width + x) * img.channels]; };
    EXPECT_EQ(int(px(0, 0)[0]), 0x10);
    EXPECT_EQ(int(px(0, 0)[1]), 0x20);
    EXPECT_EQ(int(px(0, 0)[2]), 0x30);
    std::size_t bone = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const auto* p = px(x, y);
            // The albedo passes an 8-bit linear G-buffer: within 2/255 of the colour after sRGB encoding.
            bone +=
                std::abs(int(p[0]) - 0x33) <= 2 && std::abs(int(p[1]) - 0xcc) <= 2 && std::abs(int(p[2]) - 0x66) <= 2;
        }
    EXPECT_GT(bone, 300u);
    EXPECT_EQ(meta.text["isoscope:shading"], "flat (albedo only)");
    EXPECT_NE(meta.text["isoscope:surfaces"].find("iso 1150"), std::string::npos);
    // Translucent skin over the bone: the skin's opacity is the first --opacity (the order of --iso, not sorted).
    const auto t = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") +
                                         " --iso 1150 --iso 500 --opacity 1 --opacity 0.3 --stats --size 64x64 -o " +
                                         (dir / "glass.png"),
                                     true);
    ASSERT_EQ(t.exit_code, 0) << t.out;
    EXPECT_NE(t.out.find("oit_resolve"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("transparency: "), std::string::npos) << t.out;
    ImageMetadata gm;
    load_image(dir / "glass.png", &gm);
    // The skin has the palette's first colour (core::surface_color: skin, bone) and the first opacity.
    const glm::vec3 skin = core::surface_color(0, 2);
    char want[128];
    std::snprintf(want, sizeof want, "iso 500: albedo %.6g %.6g %.6g, opacity 0.3", skin.r, skin.g, skin.b);
    EXPECT_NE(gm.text["isoscope:surfaces"].find(want), std::string::npos) << gm.text["isoscope:surfaces"];
    // Bad values name the flag, and nothing is written.
    for (const auto& [args, flag] : std::vector<std::pair<std::string, std::string>>{
             {" --iso 500 --opacity 1.5", "--opacity"},
             {" --iso 500 --opacity 0.5 --opacity 0.5", "--opacity: 2 given for 1 surface(s)"},
             {" --iso 500 --color red", "--color: expected #rrggbb"},
             {" --iso 500 --background '#12345'", "--background: expected #rrggbb"},
             {" --iso 500 --shading toon", "--shading"},
             {" --iso 500 --oit-memory 0", "--oit-memory"}}) {
        const auto b = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") + args +
                                             " --size 16x16 -o " + (dir / "bad.png"),
                                         true);
        EXPECT_NE(b.exit_code, 0) << args;
        EXPECT_NE(b.out.find(flag), std::string::npos) << args << ": " << b.out;
        EXPECT_FALSE(fs::exists(dir / "bad.png")) << args;
    }
}
