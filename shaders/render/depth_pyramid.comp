#version 450
// The depth pyramid that the cluster culling tests against
// (lod_cull.comp): level 0 is the farthest depth (reversed Z: the smallest)
// of each 2x2 pixels of the frame (with sub-samples, of all their samples),
// each level above the farthest of the 2x2 texels below it. Texels beyond the image hold the
// nearest depth (1): a culling rectangle is clamped to the image, so they
// never make a cluster look visible or hidden.
layout(local_size_x = 8, local_size_y = 8) in;

#ifdef FROM_DEPTH
#ifdef SAMPLES
layout(binding = 15) uniform sampler2DMS depth;
#else
layout(binding = 15) uniform sampler2D depth;
#endif
uniform ivec2 image_size;
#else
layout(binding = 6, r32f) readonly uniform image2D below;
#endif
layout(binding = 7, r32f) writeonly uniform image2D level_out;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(level_out)))) return;
    float d = 1.0;
#ifdef FROM_DEPTH
    // Level 0 at half the image's resolution: a texel is 2x2 pixels.
    for (int k = 0; k < 4; ++k) {
        ivec2 q = 2 * p + ivec2(k & 1, k >> 1);
        if (any(greaterThanEqual(q, image_size))) continue;
#ifdef SAMPLES
        for (int s = 0; s < SAMPLES; ++s) d = min(d, texelFetch(depth, q, s).r);
#else
        d = min(d, texelFetch(depth, q, 0).r);
#endif
    }
#else
    ivec2 q = 2 * p;
    d = min(min(imageLoad(below, q).r, imageLoad(below, q + ivec2(1, 0)).r),
            min(imageLoad(below, q + ivec2(0, 1)).r, imageLoad(below, q + ivec2(1, 1)).r));
#endif
    imageStore(level_out, p, vec4(d));
}
