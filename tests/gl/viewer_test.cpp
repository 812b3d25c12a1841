// isoscope view: a real Qt window under Xvfb, its first frame grabbed.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "io/image.hpp"
#include "tests/support/image_compare.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;

TEST(Viewer, WindowShowsWhatRenderWritesAndMakesNoGlObjectsWhenStill) {
    // The viewer and `isoscope render` draw the same core Scene with the same
    // camera framing: the window's pixels must match the headless render of
    // the same view and size (both through llvmpipe here; tolerance as for
    // the golden image: 1 % of pixels off by more than 24/255, mean 2/255).
    if (test::run_command("command -v xvfb-run").exit_code != 0)
        GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    test::TempDir dir;
    const std::string shot = dir / "shot.png", rendered = dir / "render.png";
    const auto r = test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " +
                                         test::data("headsq.nhdr") +
                                         " --iso 500 --iso 1150 --view left --ao-frames 8 --screenshot " + shot,
                                     true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto h =
        test::run_command(test::cli() + " render " + test::data("headsq.nhdr") +
                              " --iso 500 --iso 1150 --view left --ao cone --ao-frames 8 --size 800x600 -o " + rendered,
                          true);
    ASSERT_EQ(h.exit_code, 0) << h.out;
    Image img = load_image(shot);
    ASSERT_EQ(img.width, 800);
    ASSERT_EQ(img.height, 600);
    Image ref = load_image(rendered);
    // Qt's grab may carry no alpha channel: compare RGB.
    const auto rgb = [](const Image& in) {
        Image out = in;
        out.channels = 3;
        out.bytes.clear();
        for (std::size_t p = 0; p < std::size_t(in.width) * std::size_t(in.height); ++p)
            for (int c = 0; c < 3; ++c) out.bytes.push_back(in.bytes[p * std::size_t(in.channels) + std::size_t(c)]);
        return out;
    };
    const auto c = test::compare_images(rgb(img), rgb(ref), 24);
    EXPECT_TRUE(c.within({24, 0.01, 2.0}))
        << "mean " << c.mean << ", " << 100 * c.off_fraction() << " % off, largest " << c.max_diff;
    // The picture is the head, not an empty window: a tenth of it differs from the background.
    std::size_t head = 0;
    for (std::size_t p = 0; p < std::size_t(img.width) * std::size_t(img.height); ++p)
        head += std::abs(int(img.bytes[p * std::size_t(img.channels)]) - 80) > 20;
    EXPECT_GT(head, std::size_t(img.width * img.height / 10));
    // At least eight still frames accumulated AO; after the first, no GL object was made.
    int frames = 0;
    unsigned long objects = 99;
    const auto at = r.out.find("view: ");
    ASSERT_NE(at, std::string::npos) << r.out;
    ASSERT_EQ(std::sscanf(r.out.c_str() + at, "view: %d frames; %lu GL objects", &frames, &objects), 2) << r.out;
    EXPECT_GE(frames, 8);
    EXPECT_EQ(objects, 0u) << r.out;
}

TEST(Viewer, AmbientOcclusionConvergesWhileStillAndCanBeOff) {
    if (test::run_command("command -v xvfb-run").exit_code != 0)
        GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    test::TempDir dir;
    auto shot = [&](const std::string& name, const std::string& ao) {
        const std::string path = dir / name;
        const auto r =
            test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " +
                                  test::data("headsq.nhdr") + " --iso 500 --view left " + ao + " --screenshot " + path,
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
        for (int c = 0; c < 3; ++c)
            d = std::max(d, int(off.bytes[p * on.channels + c]) - int(on.bytes[p * on.channels + c]));
        differ += d > 8;
        darkest = std::max(darkest, d);
    }
    EXPECT_GT(differ, n / 200) << "AO on and off look the same";
    EXPECT_GT(darkest, 50) << "no crease is darkened";
    // Bad AO settings are refused before a window opens.
    const auto bad =
        test::run_command(test::cli() + " view " + test::data("headsq.nhdr") + " --iso 500 --ao-cones 0", true);
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_NE(bad.out.find("--ao-cones"), std::string::npos) << bad.out;
}

// `isoscope view --ao raytraced`: the screenshot waits for the refinement
// (every pixel at the standard error asked for) and shows what `isoscope
// render --ao raytraced` writes for the same view, size and settings (the
// same term: same definition, seed and stop rule; the same tolerance as
// the cone comparison above).
TEST(Viewer, RayTracedAoScreenshotShowsWhatRenderWrites) {
    if (test::run_command("command -v xvfb-run").exit_code != 0)
        GTEST_SKIP() << "xvfb-run is not installed (./setup.sh)";
    test::TempDir dir;
    const std::string shot = dir / "shot.png", rendered = dir / "render.png";
    const std::string ao = " --iso 500 --view left --ao raytraced --ao-error 0.03 --ao-rays 256";
    const auto r = test::run_command("xvfb-run -a -s '-screen 0 1024x768x24' " + test::cli() + " view " +
                                         test::data("headsq.nhdr") + ao + " --screenshot " + shot,
                                     true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto h = test::run_command(test::cli() + " render " + test::data("headsq.nhdr") + ao +
                                         " --ao-cache - --size 800x600 -o " + rendered,
                                     true);
    ASSERT_EQ(h.exit_code, 0) << h.out;
    const Image img = load_image(shot), ref = load_image(rendered);
    ASSERT_EQ(img.width, 800);
    ASSERT_EQ(img.height, 600);
    std::size_t off = 0, total = 0;
    for (std::size_t p = 0; p < std::size_t(img.width) * std::size_t(img.height); ++p)
        for (int c = 0; c < 3; ++c) {
            const int d = std::abs(int(img.bytes[p * img.channels + c]) - int(ref.bytes[p * ref.channels + c]));
            off += d > 24;
            total += std::size_t(d);
        }
    EXPECT_LT(off, std::size_t(img.width * img.height * 3 / 100)) << r.out;
    EXPECT_LT(double(total) / (img.width * img.height * 3), 2.0);
}
