// The WCAG 2.x contrast of an overlay label as drawn in an image
// (tests/gl/label_contrast_test.cpp, the GUI tests): the median relative
// luminance of the text's fully covered pixels against that of the halo
// pixels around them, which pixels are which from the label's own masks
// (LabelBox), the colours read from the image.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "io/image.hpp"
#include "renderer/frame/frame.hpp"
#include "tests/support/pixels.hpp"

namespace iso::test {

// WCAG 2.x relative luminance of an 8-bit sRGB pixel, from the definition.
inline double luminance(Rgb p) {
    const auto lin = [](int v) {
        const double c = v / 255.0;
        return c <= 0.03928 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    };
    return 0.2126 * lin(p.r) + 0.7152 * lin(p.g) + 0.0722 * lin(p.b);
}

inline double median(std::vector<double> v) {
    if (v.empty()) return NAN;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

struct Measured {
    std::size_t text = 0, ring = 0; // pixels of each
    double text_l = NAN, ring_l = NAN, ratio = NAN;
    Rgb text_colour; // the median text pixel's (by luminance)
};

// The pixels come from the image; which pixels are text and which halo comes from the label's own masks.
inline Measured measure_label(const Image& img, const LabelBox& l) {
    Measured m;
    std::vector<double> text, ring;
    std::vector<std::pair<double, Rgb>> text_px;
    const int w = l.hi.x - l.lo.x;
    for (int y = l.lo.y; y < l.hi.y; ++y)
        for (int x = l.lo.x; x < l.hi.x; ++x) {
            if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
            const std::size_t i = std::size_t(y - l.lo.y) * w + std::size_t(x - l.lo.x);
            const Rgb p = rgb_at(img, x, y);
            if (l.coverage[i] == 255) {
                text.push_back(luminance(p));
                text_px.push_back({text.back(), p});
            } else if (l.coverage[i] == 0 && l.halo_alpha[i] == 255) {
                ring.push_back(luminance(p));
            }
        }
    m.text = text.size();
    m.ring = ring.size();
    m.text_l = median(text);
    m.ring_l = median(ring);
    m.ratio = (std::max(m.text_l, m.ring_l) + 0.05) / (std::min(m.text_l, m.ring_l) + 0.05);
    if (!text_px.empty()) {
        std::nth_element(text_px.begin(), text_px.begin() + std::ptrdiff_t(text_px.size() / 2), text_px.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        m.text_colour = text_px[text_px.size() / 2].second;
    }
    return m;
}

} // namespace iso::test
