// The low-discrepancy sequences and the integer hash that the ray tracers
// (reference.cpp, progressive.cpp) and the jitter of accumulated frames
// (renderer/passes/accumulate.cpp) draw their sample points from.
#pragma once

#include <cstdint>

namespace iso::sequences {

// Radical inverse in base 2 (van der Corput; Hammersley and Halton's first
// coordinate), by bit reversal.
inline double radical_inverse2(std::uint32_t i) {
    i = (i << 16u) | (i >> 16u);
    i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);
    i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);
    i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);
    i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);
    return double(i) * 2.3283064365386963e-10;
}

// Radical inverse in any base (Halton's other coordinates).
inline double radical_inverse(std::uint32_t i, std::uint32_t base) {
    double r = 0, f = 1.0 / base;
    for (; i > 0; i /= base, f /= base) r += f * double(i % base);
    return r;
}

// An integer hash (lowbias32) and it as a number in [0, 1).
inline std::uint32_t mix(std::uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}
inline double unit(std::uint32_t x) { return double(mix(x)) * 2.3283064365386963e-10; }

} // namespace iso::sequences
