#version 450
#extension GL_GOOGLE_include_directive : require
// DSRAA: each pixel's sample 0 of the visibility sub-samples (object id and
// octahedral normal, multisample) into the ordinary G-buffer channels, the
// one sample the pixel shades: the albedo from the object table; depth
// through gl_FragDepth (the depth test passes always). Background (id 0)
// keeps the channels' clear values (0). A pixel whose other sub-samples do
// not all show the same object with a similar normal (background on
// background) goes to the edge list with the mask of those that do not:
// DSRAA reconstructs those pixels only (dsraa.comp), every other keeps its
// shaded colour.
#include "octahedral.glsl"
#include "dsraa_edges.glsl"

layout(binding = 0) uniform sampler2DMS ms_depth;
layout(binding = 1) uniform usampler2DMS ms_vis;
// Per object: linear albedo (rgb) and opacity (a), index = object id.
layout(std430, binding = 0) readonly buffer Objects { vec4 objects[]; };

uniform int samples;
uniform float normal_cos;

#ifndef GB_NORMAL
#define GB_NORMAL 0
#define GB_ID 1
#define GB_ALBEDO 2
#endif
layout(location = GB_NORMAL) out vec4 out_normal;
layout(location = GB_ID) out uint out_id;
layout(location = GB_ALBEDO) out vec4 out_albedo;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uvec2 own = texelFetch(ms_vis, p, 0).rg;
    vec3 own_n = unpack_normal(own.y);
    out_id = own.x;
    out_normal = own.x != 0u ? vec4(own_n, 1.0) : vec4(0.0);
    out_albedo = own.x != 0u ? vec4(objects[own.x].rgb, 1.0) : vec4(0.0);
    gl_FragDepth = texelFetch(ms_depth, p, 0).r;
    uint unmatched = 0u;
    for (int s = 1; s < samples; ++s) {
        uvec2 vis = texelFetch(ms_vis, p, s).rg;
        if (vis.x != own.x || (vis.x != 0u && vis.y != own.y && dot(unpack_normal(vis.y), own_n) < normal_cos))
            unmatched |= 1u << s;
    }
    if (unmatched != 0u) {
        uint i = atomicAdd(edge_count, 1u);
        if (i % DSRAA_GROUP == 0u) atomicAdd(edge_groups_x, 1u);
        edges[i] = uvec2(uint(p.x) | (uint(p.y) << 16), unmatched);
    }
}
