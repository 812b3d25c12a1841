#version 450
#extension GL_GOOGLE_include_directive : require
// Accumulation of jittered frames: the running mean of the frames so far in
// linear light, premultiplied by alpha (history, RGBA32F), and this frame's
// result encoded as sRGB for the read-back or the window.
#include "srgb.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D color_tex; // RGBA8, sRGB-encoded: this frame
layout(binding = 0, rgba32f) uniform image2D history;
layout(binding = 1, rgba8) writeonly uniform image2D out_image;
uniform float weight; // this frame's: 1 / (frames in the mean, this one included)
uniform ivec2 size;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, size))) return;
    vec4 c = texelFetch(color_tex, p, 0);
    vec4 linear = vec4(srgb_to_linear(c.rgb) * c.a, c.a);
    vec4 mean = weight >= 1.0 ? linear : mix(imageLoad(history, p), linear, weight);
    imageStore(history, p, mean);
    vec3 rgb = mean.a > 0.0 ? mean.rgb / mean.a : vec3(0.0);
    imageStore(out_image, p, vec4(srgb(clamp(rgb, 0.0, 1.0)), mean.a));
}
