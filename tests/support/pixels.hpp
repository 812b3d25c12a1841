// Reading iso::Image pixels in the tests: rows from the top as stored,
// channels interleaved; and counting the bytes two images differ in.
#pragma once

#include <cstddef>
#include <cstdint>

#include "io/image.hpp"

namespace iso::test {

inline std::size_t pixel_index(const Image& img, int x, int y, int c) {
    return (std::size_t(y) * std::size_t(img.width) + std::size_t(x)) * std::size_t(img.channels) + std::size_t(c);
}

// Channel c of a float image.
inline float float_at(const Image& img, int x, int y, int c = 0) { return img.floats[pixel_index(img, x, y, c)]; }

// Channel c of an 8-bit image, 0..255.
inline int byte_at(const Image& img, int x, int y, int c = 0) { return img.bytes[pixel_index(img, x, y, c)]; }

struct Rgb {
    int r = 0, g = 0, b = 0;
};

// The first three channels of an 8-bit image.
inline Rgb rgb_at(const Image& img, int x, int y) {
    return {byte_at(img, x, y, 0), byte_at(img, x, y, 1), byte_at(img, x, y, 2)};
}

// How many bytes of two 8-bit images differ; SIZE_MAX when their shapes differ.
inline std::size_t differing(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height || a.channels != b.channels || a.bytes.size() != b.bytes.size())
        return SIZE_MAX;
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.bytes.size(); ++i) n += a.bytes[i] != b.bytes[i];
    return n;
}

} // namespace iso::test
