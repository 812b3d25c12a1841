#version 450
#extension GL_GOOGLE_include_directive : require
// VOIT fragment lists: every fragment of a translucent surface in front of
// the opaque depth (early depth test against the G-buffer's depth, no depth
// writes) is appended to its pixel's list: a node from the pool by an
// atomic counter, linked in by exchanging the head-pointer image. A full
// pool counts the fragment as overflow: below the memory cap the renderer
// redraws with a larger pool.
//
// At the cap the farthest fragments are merged (docs/voit.md):
//   OIT_HISTOGRAM  counts each pixel's fragments in OIT_BINS depth bins
//                  (nothing is stored); the pass then picks, per pixel, the
//                  first bin that no longer fits the pixel's share of the pool;
//   OIT_CUT        fragments in or beyond that bin are merged into the
//                  pixel's tail (shaded here: lit without AO, or flat); the
//                  nearer ones are stored, and fit;
//   OIT_MERGE      a fragment that still finds the pool full is merged too
//                  (counted as overflow: then the error bound is the looser one).
#include "std140.glsl"
#include "oit_params.glsl"
#include "oit_common.glsl"
#include "clip.glsl"
#include "lod_pick.glsl"
#ifdef OIT_MERGE
#include "shading.glsl"
#endif
#ifdef PICK_APPEND
#include "pick_common.glsl"   // a pick rides on this frame: translucent fragments in its region are listed
#endif

layout(early_fragment_tests) in;

in vec3 world_normal;
uniform uint object_id;   // per draw

layout(binding = 0, r32ui) coherent uniform uimage2D heads;
#ifdef OIT_HISTOGRAM
layout(std430, binding = 4) buffer OitHistogram { uint oit_histogram[]; };   // per pixel, OIT_BINS counts
#endif
#ifdef OIT_CUT
layout(binding = 1, r32ui) readonly uniform uimage2D cut_bins;               // per pixel: the first merged bin
#endif

int depth_bin() {
    float d = gl_FragCoord.z;   // reversed Z
    float D = near_far.x * near_far.y / (d * (near_far.y - near_far.x) + near_far.x);
    return clamp(int(floor((D - cut_range.x) / (cut_range.y - cut_range.x) * float(OIT_BINS))), 0, OIT_BINS - 1);
}

#ifdef OIT_MERGE
void merge(vec3 n, uint t) {
    vec4 o = oit_objects[object_id];
    vec3 c = flat_shading ? o.rgb : shade(normalize(view_rotation * n), o.rgb, false, 1.0);
    atomicAdd(oit_tails[t].count, 1u);
    for (int k = 0; k < 3; ++k) {
        float ck = clamp(c[k], 0.0, 1.0);
        atomicAdd(oit_tails[t].color[k], uint(round(o.a * ck * OIT_TAIL_ONE)));
        atomicMax(oit_tails[t].lo_complement[k], 65535u - uint(floor(ck * 65535.0)));
        atomicMax(oit_tails[t].hi[k], uint(ceil(ck * 65535.0)));
    }
    atomicAdd(oit_tails[t].alpha, uint(round(o.a * OIT_TAIL_ONE)));
    atomicAdd(oit_tails[t].optical, uint(round(min(-log2(max(1.0 - o.a, exp2(-OIT_TAIL_LOG_MAX))), OIT_TAIL_LOG_MAX) * OIT_TAIL_LOG_ONE)));
}
#endif

void main() {
    clip_fragment();
    vec3 n = normalize(world_normal);
    if (!gl_FrontFacing) n = -n;   // two-sided, as the opaque surfaces
    uint t = uint(gl_FragCoord.y) * uint(image_size.x) + uint(gl_FragCoord.x);
#ifdef OIT_HISTOGRAM
    atomicAdd(oit_histogram[t * uint(OIT_BINS) + uint(depth_bin())], 1u);
    return;
#endif
#ifdef PICK_APPEND
    pick_append(object_id, oit_objects[object_id].a);
#endif
#ifdef OIT_CUT
    if (uint(depth_bin()) >= imageLoad(cut_bins, ivec2(gl_FragCoord.xy)).r) {
        atomicAdd(oit_cut_merged, 1u);
        merge(n, t);
        return;
    }
#endif
    uint index = atomicAdd(oit_count, 1u);
    if (index >= capacity) {
        atomicAdd(oit_overflow, 1u);
#ifdef OIT_MERGE
        merge(n, t);
#endif
        return;
    }
    oit_nodes[index].depth = gl_FragCoord.z;
    oit_nodes[index].object = object_id;
    oit_nodes[index].primitive = mesh_triangle();
    oit_nodes[index].normal = pack_normal(n);
    oit_nodes[index].next = imageAtomicExchange(heads, ivec2(gl_FragCoord.xy), index);
}
