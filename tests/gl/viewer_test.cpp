// isoscope view: a real Qt window under Xvfb, its first frame grabbed.
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
