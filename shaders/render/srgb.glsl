// The sRGB transfer pair (io/color.hpp's on the CPU).
#ifndef ISO_SRGB_GLSL
#define ISO_SRGB_GLSL
vec3 srgb(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
#endif
