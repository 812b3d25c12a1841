// The sRGB transfer and "#rrggbb" colours (io/color.hpp).
#include "io/color.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/error.hpp"

namespace iso {

double linear_from_srgb(double encoded) {
    const double c = std::clamp(encoded, 0.0, 1.0);
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

double srgb_from_linear(double linear) {
    const double c = std::clamp(linear, 0.0, 1.0);
    if (c <= 0.0031308) return 12.92 * c;
    // 1.055 p - 0.055 written so that 1 maps to exactly 1 (1.055 - 0.055 is 1 - 2^-53 in doubles).
    const double p = std::pow(c, 1.0 / 2.4);
    return p + 0.055 * (p - 1.0);
}

glm::vec3 linear_from_hex(const std::string& text) {
    unsigned r = 0, g = 0, b = 0;
    char tail = 0;
    if (text.size() != 7 || text[0] != '#' || std::sscanf(text.c_str() + 1, "%2x%2x%2x%c", &r, &g, &b, &tail) != 3 ||
        text.find_first_not_of("0123456789abcdefABCDEF", 1) != std::string::npos)
        throw Error("colour", "expected #rrggbb (sRGB hex), got '" + text + "'");
    const auto lin = [](unsigned v) { return float(linear_from_srgb(v / 255.0)); };
    return {lin(r), lin(g), lin(b)};
}

std::string hex_from_linear(const glm::vec3& linear) {
    const auto enc = [](float v) { return unsigned(std::lround(srgb_from_linear(double(v)) * 255.0)); };
    char b[8];
    std::snprintf(b, sizeof b, "#%02x%02x%02x", enc(linear.r), enc(linear.g), enc(linear.b));
    return b;
}

} // namespace iso
