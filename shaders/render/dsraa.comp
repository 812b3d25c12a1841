#version 450
#extension GL_GOOGLE_include_directive : require
// DSRAA reconstruction (renderer/passes/dsraa.cpp) of the edge pixels that
// the sample-0 copy listed (gbuffer_sample.frag; every other pixel keeps
// its shaded colour, copied before): each unmatched visibility sub-sample
// maps to the shaded colour of the neighbour (of the 8) nearest to it that
// shows the same object with a similar normal (background sub-samples to a
// background pixel); a surface sub-sample that none matches (a vessel
// thinner than a pixel, seen by a sub-sample only) is shaded here from its
// own normal and albedo, without AO, when no translucent layer lies over
// the frame (else it takes its own pixel's colour); the matched ones take
// the pixel's own; the pixel is their mean in linear light.
layout(local_size_x = 64) in;

layout(binding = 0) uniform sampler2D color_tex;  // RGBA8, sRGB-encoded: the frame shaded once per pixel
layout(binding = 1) uniform usampler2D id_tex;    // the shaded sample's object id (0: background)
layout(binding = 2) uniform sampler2D normal_tex; // and its world normal
layout(binding = 3) uniform usampler2DMS ms_vis;  // the visibility sub-samples: object id, octahedral normal
layout(binding = 0, rgba8) writeonly uniform image2D out_image;
// Per object: linear albedo (rgb) and opacity (a), index = object id.
layout(std430, binding = 0) readonly buffer Objects { vec4 objects[]; };

uniform int samples;
uniform vec2 sample_positions[8]; // in the pixel, from its lower-left corner
uniform float normal_cos;
uniform bool shade_unmatched; // no translucent surface in the frame

#include "std140.glsl"
#include "lighting_params.glsl"
#include "shading.glsl"
#include "octahedral.glsl"
#include "dsraa_edges.glsl"

const ivec2 kOffsets[8] = ivec2[8](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1), ivec2(1, 1), ivec2(-1, 1),
                                  ivec2(1, -1), ivec2(-1, -1));

vec4 linear_of(ivec2 q) {
    vec4 e = texelFetch(color_tex, q, 0);
    return vec4(srgb_to_linear(e.rgb), e.a);
}

void main() {
    uint e = gl_GlobalInvocationID.x;
    if (e >= edge_count) return;
    ivec2 p = ivec2(edges[e].x & 0xFFFFu, edges[e].x >> 16);
    uint unmatched = edges[e].y;
    // The neighbours' shaded ids and normals, fetched once for all sub-samples.
    uint ids[8];
    vec3 normals[8];
    ivec2 size = textureSize(id_tex, 0);
    for (int k = 0; k < 8; ++k) {
        ivec2 q = p + kOffsets[k];
        bool inside = all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size));
        ids[k] = inside ? texelFetch(id_tex, q, 0).r : 0xFFFFFFFFu; // no object has that id
        normals[k] = inside ? texelFetch(normal_tex, q, 0).xyz : vec3(0.0);
    }
    vec4 own = linear_of(p);
    vec4 sum = vec4(0.0); // premultiplied linear colour, alpha
    for (int s = 0; s < samples; ++s) {
        vec4 c = own;
        if ((unmatched & (1u << s)) != 0u) {
            uvec2 vis = texelFetch(ms_vis, p, s).rg;
            uint id = vis.x;
            vec3 n = unpack_normal(vis.y);
            vec2 at = vec2(p) + sample_positions[s]; // the sub-sample, in pixels
            int best = -1;
            float best_d = 1e9;
            for (int k = 0; k < 8; ++k) {
                if (ids[k] != id || (id != 0u && dot(n, normals[k]) < normal_cos)) continue;
                float d = distance(at, vec2(p + kOffsets[k]) + 0.5);
                if (d < best_d) {
                    best_d = d;
                    best = k;
                }
            }
            if (best >= 0)
                c = linear_of(p + kOffsets[best]);
            else if (id == 0u)
                c = background;
            else if (shade_unmatched) {
                vec3 albedo = objects[id].rgb;
                c = vec4(flat_shading ? albedo : shade(normalize(world_to_view * n), albedo, use_ao, 1.0), 1.0);
            }
            // else: its own pixel's colour (translucent layers lie over the frame)
        }
        sum += vec4(c.rgb * c.a, c.a);
    }
    sum /= float(samples);
    vec3 rgb = sum.a > 0.0 ? sum.rgb / sum.a : background.rgb;
    imageStore(out_image, p, vec4(srgb(clamp(rgb, 0.0, 1.0)), sum.a));
}
