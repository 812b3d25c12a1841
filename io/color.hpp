// The sRGB transfer (IEC 61966-2-1) and "#rrggbb" colours: the one place
// where a colour as a user picks or types it (sRGB, 8 bits per channel) and a
// colour the renderer shades with (linear light) meet. The GUI's colour
// picker and slice outlines, sessions and the CLI all convert through here,
// so one hex gives the same surface everywhere and is saved as given.
#pragma once

#include <string>

#include <glm/vec3.hpp>

namespace iso {

// One channel, sRGB-encoded in [0, 1] -> linear light (the exact piecewise
// curve: linear below 0.04045, a 2.4 power above). Clamped to [0, 1].
double linear_from_srgb(double encoded);
// One channel, linear light in [0, 1] -> sRGB-encoded (linear below
// 0.0031308). Clamped to [0, 1].
double srgb_from_linear(double linear);

// "#rrggbb" (sRGB, as colour pickers and CSS give it) -> linear RGB.
// Throws iso::Error("colour", ...) naming the text.
glm::vec3 linear_from_hex(const std::string& text);
// Linear RGB (clamped to [0, 1]) -> "#rrggbb" sRGB, each channel rounded to
// the nearest 8-bit value: hex_from_linear(linear_from_hex(h)) == h.
std::string hex_from_linear(const glm::vec3& linear);

} // namespace iso
