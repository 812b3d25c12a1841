// isoscope view: a real Qt window under Xvfb, its first frame grabbed.
#include <algorithm>
#include <filesystem>

#include "io/image.hpp"
#include "test_util.hpp"

using namespace iso;

TEST(Viewer, WindowUnderXvfbShowsTheSurface) {
    if (test::run_command("command -v xvfb-run").exit_code != 0) GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    test::TempDir dir;
    const std::string shot = dir / "shot.png";
    const auto r = test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " + test::data("headsq.nhdr") +
                                         " --iso 500 --view anterior --screenshot " + shot,
                                     true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const Image img = load_image(shot);
    EXPECT_EQ(img.width, 800);
    EXPECT_EQ(img.height, 600);
    // The head in the middle is lit skin, not the dark background at the corner.
    auto px = [&](int x, int y) { return &img.bytes[(std::size_t(y) * img.width + x) * img.channels]; };
    const auto* centre = px(400, 300);
    const auto* corner = px(5, 300 - 150);
    EXPECT_GT(int(centre[0]) + centre[1] + centre[2], 3 * 150);
    EXPECT_LT(int(corner[0]) + corner[1] + corner[2], 3 * 110);
}

TEST(Viewer, AmbientOcclusionConvergesWhileStillAndCanBeOff) {
    if (test::run_command("command -v xvfb-run").exit_code != 0) GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    test::TempDir dir;
    auto shot = [&](const std::string& name, const std::string& ao) {
        const std::string path = dir / name;
        const auto r = test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " + test::data("headsq.nhdr") +
                                             " --iso 500 --view left " + ao + " --screenshot " + path,
                                         true);
        EXPECT_EQ(r.exit_code, 0) << r.out;
        return load_image(path);
    };
    // The screenshot is taken once the still frames have accumulated.
    const Image on = shot("on.png", "--ao cone --ao-frames 4"), off = shot("off.png", "--ao off");
    ASSERT_EQ(on.bytes.size(), off.bytes.size());
    // AO darkens the creases (the ear, the nostrils): measured ~6700 pixels of
    // 480000 change by more than 8 levels, the ear's fold by up to 87.
    std::size_t differ = 0;
    int darkest = 0;
    const std::size_t n = std::size_t(on.width) * std::size_t(on.height);
    for (std::size_t p = 0; p < n; ++p) {
        int d = 0;
        for (int c = 0; c < 3; ++c) d = std::max(d, int(off.bytes[p * on.channels + c]) - int(on.bytes[p * on.channels + c]));
        differ += d > 8;
        darkest = std::max(darkest, d);
    }
    EXPECT_GT(differ, n / 200) << "AO on and off look the same";
    EXPECT_GT(darkest, 50) << "no crease is darkened";
    // Bad AO settings are refused before a window opens.
    const auto bad = test::run_command(test::cli() + " view " + test::data("headsq.nhdr") + " --iso 500 --ao-cones 0", true);
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_NE(bad.out.find("--ao-cones"), std::string::npos) << bad.out;
}
