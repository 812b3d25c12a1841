// The whole-image benchmark's error (tests/bench/image_error.hpp): RMSE and
// p99 of the per-pixel RGB error in sRGB units, over all pixels and over the
// reference's edge pixels.
#include "tests/bench/image_error.hpp"

#include <gtest/gtest.h>

using namespace iso;

namespace {

Image flat(int w, int h, std::uint8_t v) {
    Image img;
    img.width = w;
    img.height = h;
    img.channels = 4;
    img.bytes.assign(std::size_t(w) * std::size_t(h) * 4, v);
    return img;
}

void set(Image& img, int x, int y, std::uint8_t v) {
    for (int c = 0; c < 3; ++c) img.bytes[(std::size_t(y) * std::size_t(img.width) + std::size_t(x)) * 4 + c] = v;
}

} // namespace

TEST(ImageError, IdenticalImagesHaveNoError) {
    const Image a = flat(10, 10, 100);
    const bench::ImageError e = bench::compare(a, a);
    EXPECT_EQ(e.rmse, 0.0);
    EXPECT_EQ(e.p99, 0.0);
    EXPECT_EQ(e.pixels, 100u);
    EXPECT_EQ(e.edge_pixels, 0u) << "a uniform reference has no edges";
}

TEST(ImageError, RmseAndP99OverAllPixels) {
    const Image ref = flat(10, 10, 0);
    Image a = ref;
    set(a, 3, 3, 255); // one pixel off by 1.0 in every channel: its error is 1
    const bench::ImageError e = bench::compare(a, ref);
    EXPECT_NEAR(e.rmse, std::sqrt(1.0 / 100.0), 1e-12);
    EXPECT_EQ(e.p99, 0.0) << "one pixel in 100 is above the 99th percentile";
    set(a, 4, 4, 255);
    EXPECT_NEAR(bench::compare(a, ref).p99, 1.0, 1e-12) << "two are not";
    Image one_channel = ref;
    one_channel.bytes[0] = 51; // 0.2 in red only: RMS over the 3 channels
    EXPECT_NEAR(bench::compare(one_channel, ref).rmse, std::sqrt(0.04 / 3.0 / 100.0), 1e-12);
}

TEST(ImageError, EdgePixelsAreWhereTheReferenceChanges) {
    Image ref = flat(8, 8, 0);
    for (int y = 0; y < 8; ++y)
        for (int x = 4; x < 8; ++x) set(ref, x, y, 200); // a vertical edge between x = 3 and 4
    const auto edge = bench::edge_pixels(ref);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) EXPECT_EQ(edge[std::size_t(y) * 8 + x], x == 3 || x == 4) << x << "," << y;
    Image a = ref;
    set(a, 3, 5, 100); // off by 100/255 on the edge
    const bench::ImageError e = bench::compare(a, ref);
    EXPECT_EQ(e.edge_pixels, 16u);
    EXPECT_NEAR(e.edge_rmse, 100.0 / 255.0 / 4.0, 1e-12); // one of 16 edge pixels
    EXPECT_NEAR(e.rmse, 100.0 / 255.0 / 8.0, 1e-12);      // one of 64 pixels
    Image ramp = flat(8, 8, 0);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) set(ramp, x, y, std::uint8_t(10 * x)); // smooth shading: 10/255 a pixel
    EXPECT_EQ(bench::compare(ramp, ramp).edge_pixels, 0u) << "below the threshold (0.05)";
    EXPECT_THROW(bench::compare(flat(8, 8, 0), flat(8, 9, 0)), Error);
}
