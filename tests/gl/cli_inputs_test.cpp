// `isoscope render` and `isoscope view` open their input through the one core
// Scene: a mesh file is a mesh whatever the case of its extension (view used
// to read X.STL as a volume), a volume without --iso is refused naming the
// flag, and the CLI turns the core's setting names into its flags.
#include <filesystem>

#include "io/image.hpp"
#include "test_util.hpp"

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
    if (test::run_command("command -v xvfb-run").exit_code != 0) GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    const auto v = test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " + mesh + " --ao off --screenshot " +
                                         (dir / "v.png"),
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
    const auto r = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") + " -o " + (dir / "x.png"), true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("--iso"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("headsq.nhdr"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir / "x.png"));
    const auto bad_view = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --view sideways -o " +
                                                (dir / "x.png"),
                                            true);
    EXPECT_EQ(bad_view.exit_code, 1);
    EXPECT_NE(bad_view.out.find("--view: unknown view 'sideways'"), std::string::npos) << bad_view.out;
    const auto bad_aov = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --aov colour -o " +
                                               (dir / "x.exr"),
                                           true);
    EXPECT_EQ(bad_aov.exit_code, 1);
    EXPECT_NE(bad_aov.out.find("--aov: unknown AOV 'colour'"), std::string::npos) << bad_aov.out;
}
