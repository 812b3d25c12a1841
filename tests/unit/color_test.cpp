// The one sRGB pair (io/color.hpp) against the published transfer
// (IEC 61966-2-1): reference values, the exact ends, the two knees, and
// "#rrggbb" colours surviving the trip to linear light and back unchanged.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "io/color.hpp"
#include "io/error.hpp"

using namespace iso;

TEST(Color, PublishedValues) {
    // sRGB 128/255 (#808080) is 0.2158605 in linear light; linear 0.5 is sRGB 0.7353569, 187.5 of 255.
    EXPECT_NEAR(linear_from_srgb(128.0 / 255.0), 0.2158605, 1e-7);
    const glm::vec3 grey = linear_from_hex("#808080");
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(grey[k], 0.2158605, 1e-7);
    EXPECT_NEAR(srgb_from_linear(0.5), 0.7353569, 1e-7);
    EXPECT_EQ(hex_from_linear(glm::vec3(0.5f)), "#bcbcbc");
    // The picker's #1a1a1a: 0.0103298 linear, not the 0.0065 of a plain 2.2 gamma.
    EXPECT_NEAR(linear_from_hex("#1a1a1a").r, 0.0103298, 1e-7);
    // The linear segments: slope 12.92 below the knees.
    EXPECT_EQ(linear_from_srgb(0.02), 0.02 / 12.92);
    EXPECT_EQ(srgb_from_linear(0.001), 12.92 * 0.001);
}

TEST(Color, EndsAreExact) {
    EXPECT_EQ(linear_from_srgb(0.0), 0.0);
    EXPECT_EQ(linear_from_srgb(1.0), 1.0);
    EXPECT_EQ(srgb_from_linear(0.0), 0.0);
    EXPECT_EQ(srgb_from_linear(1.0), 1.0);
    EXPECT_EQ(linear_from_hex("#000000"), glm::vec3(0.0f));
    EXPECT_EQ(linear_from_hex("#ffffff"), glm::vec3(1.0f));
    EXPECT_EQ(hex_from_linear(glm::vec3(0.0f)), "#000000");
    EXPECT_EQ(hex_from_linear(glm::vec3(1.0f)), "#ffffff");
    // Out of range is clamped.
    EXPECT_EQ(srgb_from_linear(-0.5), 0.0);
    EXPECT_EQ(srgb_from_linear(2.0), 1.0);
    EXPECT_EQ(hex_from_linear({-1.0f, 0.5f, 3.0f}), "#00bcff");
}

TEST(Color, KneesAreContinuous) {
    // Either side of each knee (0.04045 encoded, 0.0031308 linear) the two pieces meet within
    // the standard's rounding of its constants (the sRGB side steps down by 3e-8 at 0.0031308).
    const double below_e = 0.04045, above_e = std::nextafter(below_e, 1.0);
    EXPECT_NEAR(linear_from_srgb(below_e), linear_from_srgb(above_e), 1e-8);
    EXPECT_NEAR(linear_from_srgb(below_e), 0.0031308, 1e-7);
    const double below_l = 0.0031308, above_l = std::nextafter(below_l, 1.0);
    EXPECT_NEAR(srgb_from_linear(below_l), srgb_from_linear(above_l), 1e-7);
    EXPECT_NEAR(srgb_from_linear(below_l), 0.04045, 1e-7);
}

TEST(Color, HexSurvivesTheTripToLinearAndBack) {
    for (unsigned v = 0; v < 256; ++v) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "#%02x%02x%02x", v, 255 - v, (v * 7) % 256);
        EXPECT_EQ(hex_from_linear(linear_from_hex(hex)), hex);
    }
    EXPECT_EQ(hex_from_linear(linear_from_hex("#1A1A1A")), "#1a1a1a");
}

TEST(Color, MalformedHexNamesTheColour) {
    for (const std::string bad : {"", "#12345", "#1234567", "123456", "#12345g", "#12 456"}) {
        try {
            linear_from_hex(bad);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const Error& e) {
            EXPECT_EQ(e.where(), "colour");
            EXPECT_NE(e.reason().find("'" + bad + "'"), std::string::npos) << e.reason();
        }
    }
}
