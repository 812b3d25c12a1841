#version 450
#extension GL_GOOGLE_include_directive : require
// DSRAA reconstruction (renderer/passes/dsraa.cpp): every visibility
// sub-sample maps to a shaded pixel, its own or a neighbour's of the same
// object with a similar normal (background sub-samples to a background
// pixel); a surface sub-sample that none matches (a vessel thinner than a
// pixel, seen by a sub-sample only) is shaded here from its own normal and
// albedo, without AO, when no translucent layer lies over the frame (else
// it takes its own pixel's colour); the pixel is their mean in linear light.
layout(binding = 0) uniform sampler2D color_tex;      // RGBA8, sRGB-encoded: the frame shaded once per pixel
layout(binding = 1) uniform usampler2D id_tex;        // the shaded sample's object id (0: background)
layout(binding = 2) uniform sampler2D normal_tex;     // and its world normal
layout(binding = 3) uniform usampler2DMS ms_id;       // the visibility sub-samples
layout(binding = 4) uniform sampler2DMS ms_normal;
layout(binding = 5) uniform sampler2DMS ms_albedo;

uniform int samples;
uniform vec2 sample_positions[8]; // in the pixel, from its lower-left corner
uniform float normal_cos;
uniform bool shade_unmatched; // no translucent surface in the frame

layout(location = 0) out vec4 out_color;

#include "std140.glsl"
#include "lighting_params.glsl"
#include "shading.glsl"

// Own pixel first, then the 8 neighbours.
const ivec2 kOffsets[9] = ivec2[9](ivec2(0, 0), ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1), ivec2(1, 1),
                                  ivec2(-1, 1), ivec2(1, -1), ivec2(-1, -1));

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(id_tex, 0);
    vec4 sum = vec4(0.0); // premultiplied linear colour, alpha
    for (int s = 0; s < samples; ++s) {
        uint id = texelFetch(ms_id, p, s).r;
        vec3 n = texelFetch(ms_normal, p, s).xyz;
        vec2 at = vec2(p) + sample_positions[s]; // the sub-sample, in pixels
        int best = -1;
        float best_d = 1e9;
        for (int k = 0; k < 9; ++k) {
            ivec2 q = p + kOffsets[k];
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            if (texelFetch(id_tex, q, 0).r != id) continue;
            if (id != 0u && dot(n, texelFetch(normal_tex, q, 0).xyz) < normal_cos) continue;
            if (k == 0) {   // the pixel's own shaded sample
                best = 0;
                break;
            }
            float d = distance(at, vec2(q) + 0.5);
            if (d < best_d) {
                best_d = d;
                best = k;
            }
        }
        vec4 c = background;
        if (best >= 0) {
            vec4 e = texelFetch(color_tex, p + kOffsets[best], 0);
            c = vec4(srgb_to_linear(e.rgb), e.a);
        } else if (id != 0u && shade_unmatched) {
            vec3 albedo = texelFetch(ms_albedo, p, s).rgb;
            c = vec4(flat_shading ? albedo : shade(normalize(world_to_view * n), albedo, use_ao, 1.0), 1.0);
        } else if (id != 0u) {
            vec4 e = texelFetch(color_tex, p, 0);
            c = vec4(srgb_to_linear(e.rgb), e.a);
        }
        sum += vec4(c.rgb * c.a, c.a);
    }
    sum /= float(samples);
    vec3 rgb = sum.a > 0.0 ? sum.rgb / sum.a : background.rgb;
    out_color = vec4(srgb(clamp(rgb, 0.0, 1.0)), sum.a);
}
