#version 450
#extension GL_GOOGLE_include_directive : require
// VOIT resolve: per pixel, the list's fragments front to back (sorted by
// depth; ties by object and primitive, so the order is deterministic),
// shaded as the opaque surfaces are (or flat: the albedo), composited in
// linear light over the opaque image, stopping as soon as the remaining
// transmittance is below epsilon: fragments that cannot change the pixel
// are never shaded. Short lists (up to LOCAL_NODES) are sorted in a local
// array; longer ones are merge-sorted in place in the node pool.
//
// Without AO this is one pass. With cone AO on (lit shading), translucent
// fragments get their own AO, traced from each fragment's own point and
// normal through the opaque surfaces' slicemap with the cone AO pass's
// tracer (oit_ao.comp): occlusion by the opaque surfaces, as the opaque
// surfaces' AO has it; translucent surfaces do not occlude. Tracing inside
// this pass would make every SIMD lane wait for its group's longest list
// (7x slower per trace on llvmpipe), so the work is split in three:
//   OIT_SORT    sorts each list and relinks it front to back (new head),
//               and appends the fragments that will be shaded (pixel, node)
//               to a compact list, with the indirect dispatch's size;
//   oit_ao.comp traces one listed fragment per invocation;
//   OIT_SORTED  composites the sorted lists with those AO values.
#include "std140.glsl"
#include "oit_params.glsl"
#include "oit_common.glsl"
#include "shading.glsl"
#include "oit_trace.glsl"
#define LIST_NEXT(i) oit_nodes[i].next
#define LIST_BEFORE(a, b) in_front(oit_nodes[a].depth, key_of(a), oit_nodes[b].depth, key_of(b))
#define LIST_END OIT_END

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef OIT_SORT
layout(binding = 0, r32ui) uniform uimage2D heads;   // the sorted list's head out
#else
layout(binding = 0, r32ui) readonly uniform uimage2D heads;
layout(binding = 1, rgba8) uniform image2D color;   // opaque result in, composite out (sRGB-encoded RGBA8)
#endif
#ifdef OIT_SORTED
layout(std430, binding = 4) readonly buffer OitAo { float oit_ao[]; };   // per node, from oit_ao.comp
#endif
// Per pixel, written for the statistics: fragments in the list, fragments shaded.
// Per pixel, written for the statistics: fragments in the list, fragments
// shaded, pixels with a list; with OIT_MERGE, pixels with merged fragments
// and the largest merged coverage (the error bound; float bits).
layout(std430, binding = 5) buffer OitStats { uint stat_max_list; uint stat_shaded; uint stat_lists; uint stat_merged_pixels; uint stat_merge_bound; };

#ifndef LOCAL_NODES
#define LOCAL_NODES 32
#endif

// Is fragment a in front of b? Nearer first; ties broken by object, then primitive.
bool in_front(float da, uvec2 ka, float db, uvec2 kb) {
    return da > db || (da == db && (ka.x < kb.x || (ka.x == kb.x && ka.y < kb.y)));
}
uvec2 key_of(uint i) { return uvec2(oit_nodes[i].object, oit_nodes[i].primitive); }
#include "list_sort.glsl"

vec3 fragment_color(uint i) {
    vec4 o = oit_objects[oit_nodes[i].object];
    if (flat_shading) return o.rgb;
    vec3 n = normalize(view_rotation * unpack_normal(oit_nodes[i].normal));
#ifdef OIT_SORTED
    return shade(n, o.rgb, true, oit_ao[i]);
#else
    return shade(n, o.rgb, false, 1.0);
#endif
}

vec3 acc = vec3(0.0);
float transmittance = 1.0;
uint shaded = 0u;

#if defined(VOLUME) && !defined(OIT_SORT)
// The volume's pieces between the fragments (volume_march.glsl).
#include "volume_params.glsl"
#include "volume_march.glsl"
bool vol_on = false;
#endif

// The next fragment front to back: shade it (or list it for tracing).
void take(uint i, ivec2 p) {
    float alpha = oit_objects[oit_nodes[i].object].a;
#ifdef OIT_SORT
    oit_trace_append(p, i);
#else
#ifdef VOLUME
    if (vol_on) volume_until(vol_t_of_depth(oit_nodes[i].depth));
#endif
    acc += transmittance * alpha * fragment_color(i);
#endif
    transmittance *= 1.0 - alpha;
    ++shaded;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= image_size.x || p.y >= image_size.y) return;
    uint head = imageLoad(heads, p).r;
#if defined(VOLUME) && !defined(OIT_SORT)
    vol_on = volume_begin(p);
    bool nothing = !vol_on;
#else
    const bool nothing = true;
#endif
#if defined(OIT_MERGE) && !defined(OIT_SORT)
    uint t = uint(p.y) * uint(image_size.x) + uint(p.x);
    if (nothing && head == OIT_END && oit_tails[t].count == 0u) return;   // nothing translucent here: the opaque result stays
#else
    if (nothing && head == OIT_END) return;
#endif
#ifdef OIT_SORTED
    for (uint i = head; i != OIT_END && transmittance >= epsilon; i = oit_nodes[i].next) take(i, p);
#else

    // Gather up to LOCAL_NODES into a local array, counting the list. Only
    // the depth and the node index are kept (llvmpipe keeps dynamically
    // indexed arrays in memory: fewer words, less traffic); equal depths,
    // rare, fetch their object and primitive to break the tie.
    uint idx[LOCAL_NODES];
    float dep[LOCAL_NODES];
    uint n = 0u, length = 0u;
    for (uint i = head; i != OIT_END; i = oit_nodes[i].next) {
        if (n < LOCAL_NODES) {
            idx[n] = i;
            dep[n] = oit_nodes[i].depth;
            ++n;
        }
        ++length;
    }
    if (length <= LOCAL_NODES) {
        // Insertion sort, nearest first.
        for (uint a = 1u; a < n; ++a) {
            uint ti = idx[a];
            float td = dep[a];
            int b = int(a) - 1;
            while (b >= 0 && (td > dep[b] || (td == dep[b] && in_front(td, key_of(ti), dep[b], key_of(idx[b]))))) {
                idx[b + 1] = idx[b];
                dep[b + 1] = dep[b];
                --b;
            }
            idx[b + 1] = ti;
            dep[b + 1] = td;
        }
        for (uint a = 0u; a < n && transmittance >= epsilon; ++a) take(idx[a], p);
#ifdef OIT_SORT
        for (uint a = 0u; a + 1u < n; ++a) oit_nodes[idx[a]].next = idx[a + 1u];
        oit_nodes[idx[n - 1u]].next = OIT_END;
        imageStore(heads, p, uvec4(idx[0]));
#endif
    } else {
        // Long list: sorted in place in the pool (list_sort.glsl), then
        // composited from the front.
        uint list = list_sort(head);
        for (uint i = list; i != OIT_END && transmittance >= epsilon; i = oit_nodes[i].next) take(i, p);
#ifdef OIT_SORT
        imageStore(heads, p, uvec4(list));
#endif
    }
    if (length > 0u) {
        atomicMax(stat_max_list, length);
        atomicAdd(stat_shaded, shaded);
        atomicAdd(stat_lists, 1u);
    }
#endif
#ifndef OIT_SORT
#ifdef VOLUME
    if (vol_on) {
        volume_until(vol_t1);   // the volume behind the last fragment, up to the opaque depth
        volume_end();
    }
#endif
#ifdef OIT_MERGE
    // The merged fragments, behind the list: their opacity-weighted mean
    // colour over their total coverage. Merged by the depth cut, they all lie
    // behind the list's fragments, so only their order among themselves is
    // lost: whatever it was, their true contribution is the transmittance
    // reaching them times their coverage times some mean of their colours,
    // so each channel (linear) is off by at most that product times the
    // channel's colour range. Fragments that found the pool full (overflow)
    // may lie anywhere: then by at most their coverage (docs/voit.md).
    if (oit_tails[t].count > 0u) {
        float coverage = 1.0 - exp2(-float(oit_tails[t].optical) / OIT_TAIL_LOG_ONE);
        float alpha_sum = float(oit_tails[t].alpha);
        vec3 mean = alpha_sum > 0.0 ? vec3(oit_tails[t].color[0], oit_tails[t].color[1], oit_tails[t].color[2]) / alpha_sum : vec3(0.0);
        float spread = 0.0;
        for (int k = 0; k < 3; ++k) spread = max(spread, float(oit_tails[t].hi[k] - (65535u - oit_tails[t].lo_complement[k])) / 65535.0);
        float bound = oit_overflow == 0u ? transmittance * coverage * spread : coverage;
        acc += transmittance * coverage * mean;
        transmittance *= 1.0 - coverage;
        atomicAdd(stat_merged_pixels, 1u);
        atomicMax(stat_merge_bound, floatBitsToUint(bound));
    }
#endif
    vec4 under = imageLoad(color, p);
    vec3 result = acc + transmittance * srgb_to_linear(under.rgb);
    float alpha = 1.0 - transmittance * (1.0 - under.a);
    imageStore(color, p, vec4(srgb(result), alpha));
#endif
}
