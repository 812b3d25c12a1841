// The error of an image against a reference, as the whole-image benchmark
// prints it: RMSE and the 99th percentile of the per-pixel error in sRGB
// units (0..1, the 8-bit values / 255), over every pixel and over the edge
// pixels only (where anti-aliasing matters).
//
// - A pixel's error is the RMS of its R, G and B differences: the RMSE is
//   the root of the mean squared pixel error (the RMSE over all channels),
//   the p99 the 99th percentile of the pixel errors (nearest rank).
// - An edge pixel is one whose 3x3 neighbourhood in the reference is not
//   uniform: some neighbour differs from it by more than `edge_threshold` in
//   a channel (default 0.05, about 13/255, well above the pixel-to-pixel
//   change of smooth shading and well below a silhouette's); image borders
//   count only the neighbours inside.
// Both images RGB or RGBA, 8 bits, the same size; alpha is ignored.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "io/error.hpp"
#include "io/image.hpp"

namespace iso::bench {

struct ImageError {
    double rmse = 0, p99 = 0;           // every pixel
    double edge_rmse = 0, edge_p99 = 0; // edge pixels
    std::size_t pixels = 0, edge_pixels = 0;
};

namespace image_error_detail {

inline double p99(std::vector<double> v) {
    if (v.empty()) return 0;
    const std::size_t k = std::min(v.size() - 1, std::size_t(std::ceil(0.99 * double(v.size()))) - 1);
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
    return v[k];
}

inline double rms(const std::vector<double>& v) {
    double s = 0;
    for (double e : v) s += e * e;
    return v.empty() ? 0 : std::sqrt(s / double(v.size()));
}

// Channel c (0..2) of pixel (x, y), 0..255.
inline int at(const Image& img, int x, int y, int c) {
    return img
        .bytes[(std::size_t(y) * std::size_t(img.width) + std::size_t(x)) * std::size_t(img.channels) + std::size_t(c)];
}

} // namespace image_error_detail

// Edge pixels of `ref` (see above), one flag per pixel, rows from the top.
inline std::vector<bool> edge_pixels(const Image& ref, double edge_threshold = 0.05) {
    using image_error_detail::at;
    const int limit = int(std::lround(edge_threshold * 255.0));
    std::vector<bool> edge(std::size_t(ref.width) * std::size_t(ref.height));
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            bool e = false;
            for (int dy = -1; dy <= 1 && !e; ++dy)
                for (int dx = -1; dx <= 1 && !e; ++dx) {
                    const int u = x + dx, v = y + dy;
                    if (u < 0 || v < 0 || u >= ref.width || v >= ref.height) continue;
                    for (int c = 0; c < 3; ++c) e = e || std::abs(at(ref, u, v, c) - at(ref, x, y, c)) > limit;
                }
            edge[std::size_t(y) * std::size_t(ref.width) + std::size_t(x)] = e;
        }
    return edge;
}

inline ImageError compare(const Image& a, const Image& ref, double edge_threshold = 0.05) {
    using image_error_detail::at;
    if (a.is_float || ref.is_float || a.width != ref.width || a.height != ref.height || a.channels < 3 ||
        ref.channels < 3)
        throw Error("image error", "needs two 8-bit RGB(A) images of one size, got " + std::to_string(a.width) + "x" +
                                       std::to_string(a.height) + " and " + std::to_string(ref.width) + "x" +
                                       std::to_string(ref.height));
    const std::vector<bool> edge = edge_pixels(ref, edge_threshold);
    std::vector<double> all, edges;
    all.reserve(edge.size());
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            double s = 0;
            for (int c = 0; c < 3; ++c) {
                const double d = (at(a, x, y, c) - at(ref, x, y, c)) / 255.0;
                s += d * d;
            }
            const double e = std::sqrt(s / 3.0);
            all.push_back(e);
            if (edge[std::size_t(y) * std::size_t(ref.width) + std::size_t(x)]) edges.push_back(e);
        }
    ImageError r;
    r.pixels = all.size();
    r.edge_pixels = edges.size();
    r.rmse = image_error_detail::rms(all);
    r.p99 = image_error_detail::p99(all);
    r.edge_rmse = image_error_detail::rms(edges);
    r.edge_p99 = image_error_detail::p99(edges);
    return r;
}

} // namespace iso::bench
