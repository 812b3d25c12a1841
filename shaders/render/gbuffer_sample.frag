#version 450
// DSRAA: each pixel's sample 0 of the visibility sub-samples (multisample
// G-buffer channels) into the ordinary channels, the one sample the pixel
// shades; depth through gl_FragDepth (the depth test passes always).
layout(binding = 0) uniform sampler2DMS ms_depth;
layout(binding = 1) uniform sampler2DMS ms_normal;
layout(binding = 2) uniform usampler2DMS ms_id;
layout(binding = 3) uniform sampler2DMS ms_albedo;

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
    out_normal = texelFetch(ms_normal, p, 0);
    out_id = texelFetch(ms_id, p, 0).r;
    out_albedo = texelFetch(ms_albedo, p, 0);
    gl_FragDepth = texelFetch(ms_depth, p, 0).r;
}
