// The golden-image helper (image_compare.hpp): its three thresholds at and
// just past their limits, shape mismatches, the files it writes on failure
// and ISOSCOPE_UPDATE_GOLDEN=1; and the image module loaded on first use.
#include "tests/support/image_compare.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "tests/support/test_util.hpp"

using namespace iso;

namespace {

Image grey(int w, int h, std::uint8_t v) {
    Image img;
    img.width = w;
    img.height = h;
    img.channels = 4;
    img.bytes.assign(std::size_t(w) * std::size_t(h) * 4, v);
    for (std::size_t p = 0; p < img.bytes.size(); p += 4) img.bytes[p + 3] = 255;
    return img;
}

constexpr test::ImageTolerance kTol{.off_threshold = 24, .max_off_fraction = 0.01, .max_mean = 2.0};

// Sets (or unsets, with nullopt) ISOSCOPE_UPDATE_GOLDEN for one scope.
class UpdateGolden {
public:
    explicit UpdateGolden(std::optional<std::string> value) {
        if (const char* old = std::getenv("ISOSCOPE_UPDATE_GOLDEN")) old_ = old;
        if (value)
            ::setenv("ISOSCOPE_UPDATE_GOLDEN", value->c_str(), 1);
        else
            ::unsetenv("ISOSCOPE_UPDATE_GOLDEN");
    }
    ~UpdateGolden() {
        if (old_)
            ::setenv("ISOSCOPE_UPDATE_GOLDEN", old_->c_str(), 1);
        else
            ::unsetenv("ISOSCOPE_UPDATE_GOLDEN");
    }

private:
    std::optional<std::string> old_;
};

} // namespace

TEST(ImageCompare, ThresholdsAreInclusiveLimits) {
    const Image g = grey(10, 10, 100); // 100 pixels: one pixel is 1 %
    Image a = g;
    auto c = test::compare_images(a, g, kTol.off_threshold);
    EXPECT_TRUE(c.same_shape);
    EXPECT_EQ(c.off, 0u);
    EXPECT_EQ(c.mean, 0.0);
    EXPECT_TRUE(c.within(kTol));
    // 24/255 in one channel is not off; 25/255 is.
    a.bytes[0] = 124;
    c = test::compare_images(a, g, kTol.off_threshold);
    EXPECT_EQ(c.off, 0u);
    EXPECT_EQ(c.max_diff, 24);
    a.bytes[0] = 125;
    c = test::compare_images(a, g, kTol.off_threshold);
    EXPECT_EQ(c.off, 1u);
    EXPECT_DOUBLE_EQ(c.off_fraction(), 0.01);
    EXPECT_TRUE(c.within(kTol)) << "exactly 1 % off is allowed";
    EXPECT_EQ(c.diff.bytes[0], 200) << "the diff image shows |difference| x 8";
    a.bytes[4 * 57 + 2] = 0; // a second pixel, 100 off
    c = test::compare_images(a, g, kTol.off_threshold);
    EXPECT_EQ(c.off, 2u);
    EXPECT_FALSE(c.within(kTol)) << "2 % off";
    // No pixel off, but a mean of 2.25/255 over all channel values (RGB 3 off, alpha equal).
    Image b = grey(10, 10, 103);
    c = test::compare_images(b, g, kTol.off_threshold);
    EXPECT_EQ(c.off, 0u);
    EXPECT_DOUBLE_EQ(c.mean, 2.25);
    EXPECT_FALSE(c.within(kTol));
    // A mean of exactly 2/255 passes: 2 off in every channel, alpha included.
    for (auto& v : b.bytes) v = std::uint8_t(v == 255 ? 253 : 102);
    c = test::compare_images(b, g, kTol.off_threshold);
    EXPECT_DOUBLE_EQ(c.mean, 2.0);
    EXPECT_TRUE(c.within(kTol));
    // Another size never matches.
    EXPECT_FALSE(test::compare_images(grey(10, 9, 100), g, 255).within({255, 1.0, 255.0}));
}

TEST(ImageCompare, FailureWritesActualAndDiffAndReportsTheFigures) {
    UpdateGolden off(std::nullopt);
    test::TempDir dir;
    const std::string golden = dir / "scene.png", failures = dir / "failures";
    const Image g = grey(20, 10, 50);
    save_image(g, golden);
    EXPECT_TRUE(test::matches_golden(g, golden, kTol, failures));
    EXPECT_FALSE(std::filesystem::exists(failures)) << "nothing written when the images match";
    Image a = g;
    for (int p = 0; p < 4; ++p) a.bytes[std::size_t(p) * 4] = 90; // 4 of 200 pixels off by 40: 2 %
    const auto r = test::matches_golden(a, golden, kTol, failures);
    ASSERT_FALSE(r);
    const std::string msg = r.message();
    EXPECT_NE(msg.find("4 of 200 pixels (2 %) off by more than 24/255"), std::string::npos) << msg;
    EXPECT_NE(msg.find("mean |diff| 0.2/255"), std::string::npos) << msg; // 4 x 40 / 800 channel values
    EXPECT_NE(msg.find("largest difference 40/255"), std::string::npos) << msg;
    const Image written = load_image(failures + "/scene_actual.png");
    EXPECT_EQ(written.bytes, a.bytes);
    const Image diff = load_image(failures + "/scene_diff.png");
    EXPECT_EQ(diff.bytes[0], 255) << "40 x 8, clamped";
    EXPECT_EQ(diff.bytes[4 * 4], 0) << "the fifth pixel is equal";
    // A missing golden and a wrong size are failures that say so.
    EXPECT_NE(std::string(test::matches_golden(a, dir / "none.png", kTol, failures).message()).find("missing"),
              std::string::npos);
    EXPECT_NE(std::string(test::matches_golden(grey(5, 5, 50), golden, kTol, failures).message())
                  .find("5x5x4 against 20x10x4"),
              std::string::npos);
}

TEST(ImageCompare, UpdateGoldenRewritesTheGolden) {
    test::TempDir dir;
    const std::string golden = dir / "scene.png";
    save_image(grey(8, 8, 10), golden);
    const Image a = grey(8, 8, 200);
    {
        UpdateGolden on("1");
        EXPECT_TRUE(test::matches_golden(a, golden, kTol, dir / "failures"));
    }
    EXPECT_EQ(load_image(golden).bytes, a.bytes);
    UpdateGolden off(std::nullopt);
    EXPECT_TRUE(test::matches_golden(a, golden, kTol, dir / "failures"));
}

namespace {
// Whether a shared object whose path contains `name` is mapped into this process.
bool mapped(const std::string& name) {
    std::ifstream maps("/proc/self/maps");
    std::string line;
    while (std::getline(maps, line))
        if (line.find(name) != std::string::npos) return true;
    return false;
}
// Taken while the program starts (every library it links is loaded by then,
// whatever test runs first).
const bool kOiioAtStart = mapped("libOpenImageIO");
} // namespace

// OpenImageIO (about 260 shared libraries) is not loaded when a program
// starts, neither here nor in the CLI, only with the image module on the
// first image read or write (io/image_module.hpp).
TEST(ImageModule, OpenImageIOLoadsOnTheFirstImageNotAtStart) {
    EXPECT_FALSE(kOiioAtStart);
    const auto ldd = test::run_command("ldd " ISOSCOPE_CLI);
    ASSERT_EQ(ldd.exit_code, 0) << ldd.out;
    EXPECT_EQ(ldd.out.find("libOpenImageIO"), std::string::npos) << ldd.out;
    EXPECT_NE(ldd.out.find("libvtkCommonCore"), std::string::npos) << ldd.out; // ldd listed the closure

    test::TempDir dir;
    ImageMetadata meta;
    meta.text["isoscope:input"] = "headsq.nhdr";
    meta.float_arrays["isoscope:view"] = {1.5f, -2.25f};
    save_image(grey(6, 4, 77), dir / "a.png", meta);
    EXPECT_TRUE(mapped("libOpenImageIO"));
    EXPECT_TRUE(mapped("libisoscope_image.so"));
    ImageMetadata back;
    const Image img = load_image(dir / "a.png", &back);
    EXPECT_EQ(img.bytes, grey(6, 4, 77).bytes);
    EXPECT_EQ(back.text["isoscope:input"], "headsq.nhdr");
    EXPECT_EQ(back.text["isoscope:view"], "1.5 -2.25");
    EXPECT_GE(image_library_version(), 20000); // 2.x
    // What the module reports still names the file.
    try {
        load_image(dir / "missing.png");
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
    }
}
