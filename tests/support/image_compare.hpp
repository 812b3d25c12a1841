// Golden-image comparison for 8-bit images with stated thresholds. A pixel
// is "off" when any channel differs by more than `off_threshold`; the
// images match when at most `max_off_fraction` of the pixels are off and the
// mean absolute difference over all channel values is at most `max_mean`.
// On a mismatch the actual image and a difference image (|difference| x 8
// per channel, opaque) are written under golden_failure_dir() and the
// figures are reported; ISOSCOPE_UPDATE_GOLDEN=1 rewrites the golden instead.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "io/error.hpp"
#include "io/image.hpp"

namespace iso::test {

struct ImageTolerance {
    int off_threshold = 0;       // 0..255: a channel differing by more makes its pixel off
    double max_off_fraction = 0; // of all pixels
    double max_mean = 0;         // mean |difference| over all channel values, 0..255
};

struct ImageComparison {
    bool same_shape = false; // width, height and channels
    std::size_t pixels = 0, off = 0;
    double mean = 0;  // mean |difference| over all channel values
    int max_diff = 0; // largest channel difference
    Image diff;       // RGBA8, |difference| x 8, alpha 255 (same shape only)
    double off_fraction() const { return pixels ? double(off) / double(pixels) : 0.0; }
    bool within(const ImageTolerance& t) const {
        return same_shape && off_fraction() <= t.max_off_fraction && mean <= t.max_mean;
    }
};

inline ImageComparison compare_images(const Image& actual, const Image& expected, int off_threshold) {
    ImageComparison c;
    if (actual.is_float || expected.is_float) throw Error("compare_images", "8-bit images only");
    c.same_shape = actual.width == expected.width && actual.height == expected.height &&
                   actual.channels == expected.channels && actual.bytes.size() == expected.bytes.size();
    if (!c.same_shape) return c;
    const int ch = actual.channels;
    c.pixels = std::size_t(actual.width) * std::size_t(actual.height);
    c.diff.width = actual.width;
    c.diff.height = actual.height;
    c.diff.channels = 4;
    c.diff.bytes.assign(c.pixels * 4, 255);
    double sum = 0;
    for (std::size_t p = 0; p < c.pixels; ++p) {
        int worst = 0;
        for (int k = 0; k < ch; ++k) {
            const std::size_t i = p * std::size_t(ch) + std::size_t(k);
            const int d = std::abs(int(actual.bytes[i]) - int(expected.bytes[i]));
            worst = std::max(worst, d);
            sum += d;
            if (k < 3) c.diff.bytes[p * 4 + std::size_t(k)] = std::uint8_t(std::min(255, d * 8));
        }
        c.max_diff = std::max(c.max_diff, worst);
        c.off += worst > off_threshold;
    }
    c.mean = actual.bytes.empty() ? 0.0 : sum / double(actual.bytes.size());
    return c;
}

inline bool updating_golden() {
    const char* v = std::getenv("ISOSCOPE_UPDATE_GOLDEN");
    return v && std::string(v) == "1";
}

inline std::string golden_failure_dir() { return std::string(ISOSCOPE_BINARY_DIR) + "/golden-failures"; }

// EXPECT_TRUE(matches_golden(img, ISOSCOPE_SOURCE_DIR "/tests/golden/x.png", {24, 0.01, 2.0}));
// With ISOSCOPE_UPDATE_GOLDEN=1 the golden is written from `actual` (and the
// result is a success that says so).
inline ::testing::AssertionResult matches_golden(const Image& actual, const std::string& golden_path,
                                                 const ImageTolerance& tol,
                                                 const std::string& failure_dir = golden_failure_dir()) {
    namespace fs = std::filesystem;
    if (updating_golden()) {
        save_image(actual, golden_path);
        return ::testing::AssertionSuccess() << "golden image written: " << golden_path;
    }
    if (!fs::exists(golden_path))
        return ::testing::AssertionFailure() << golden_path << " is missing (ISOSCOPE_UPDATE_GOLDEN=1 writes it)";
    const Image golden = load_image(golden_path);
    const ImageComparison c = compare_images(actual, golden, tol.off_threshold);
    if (c.within(tol)) return ::testing::AssertionSuccess();
    const std::string stem = fs::path(golden_path).stem().string();
    fs::create_directories(failure_dir);
    const std::string actual_path = failure_dir + "/" + stem + "_actual.png",
                      diff_path = failure_dir + "/" + stem + "_diff.png";
    save_image(actual, actual_path);
    std::ostringstream os;
    os << "image differs from " << golden_path << ": ";
    if (!c.same_shape) {
        os << actual.width << "x" << actual.height << "x" << actual.channels << " against " << golden.width << "x"
           << golden.height << "x" << golden.channels;
    } else {
        save_image(c.diff, diff_path);
        os << "mean |diff| " << c.mean << "/255 (at most " << tol.max_mean << "), " << c.off << " of " << c.pixels
           << " pixels (" << 100 * c.off_fraction() << " %) off by more than " << tol.off_threshold << "/255 (at most "
           << 100 * tol.max_off_fraction << " %), largest difference " << c.max_diff << "/255; diff: " << diff_path;
    }
    os << "; actual: " << actual_path;
    return ::testing::AssertionFailure() << os.str();
}

} // namespace iso::test
