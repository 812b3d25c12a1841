#version 450
#extension GL_GOOGLE_include_directive : require
// VOIT resolve: per pixel, the list's fragments front to back (sorted by
// depth; ties by object and primitive, so the order is deterministic),
// shaded as the opaque surfaces are (or flat: the albedo), composited in
// linear light over the opaque image, stopping as soon as the remaining
// transmittance is below epsilon: fragments that cannot change the pixel
// are never shaded. Short lists (up to LOCAL_NODES) are sorted in a local
// array; longer ones are merge-sorted in place in the node pool.
#include "std140.glsl"
#include "oit_params.glsl"
#include "oit_common.glsl"
#include "shading.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, r32ui) readonly uniform uimage2D heads;
layout(binding = 1, rgba8) uniform image2D color;   // opaque result in, composite out (sRGB-encoded RGBA8)
// Per pixel, written for the statistics: fragments in the list, fragments shaded.
layout(std430, binding = 3) buffer OitStats { uint stat_max_list; uint stat_shaded; uint stat_lists; };

#ifndef LOCAL_NODES
#define LOCAL_NODES 32
#endif

// Is fragment a in front of b? Nearer first; ties broken by object, then primitive.
bool in_front(float da, uvec2 ka, float db, uvec2 kb) {
    return da > db || (da == db && (ka.x < kb.x || (ka.x == kb.x && ka.y < kb.y)));
}
uvec2 key_of(uint i) { return uvec2(oit_nodes[i].object, oit_nodes[i].primitive); }

vec3 fragment_color(uint i) {
    vec4 o = oit_objects[oit_nodes[i].object];
    if (flat_shading) return o.rgb;
    return shade(normalize(world_to_view * unpack_normal(oit_nodes[i].normal)), o.rgb, false, 1.0);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    uint head = imageLoad(heads, p).r;
    if (head == OIT_END) return;   // nothing translucent here: the opaque result stays
    vec4 under = imageLoad(color, p);
    vec3 acc = vec3(0.0);
    float transmittance = 1.0;
    uint shaded = 0u;

    // Gather up to LOCAL_NODES into a local array, counting the list.
    uint idx[LOCAL_NODES];
    float dep[LOCAL_NODES];
    uvec2 key[LOCAL_NODES];
    uint n = 0u, length = 0u;
    for (uint i = head; i != OIT_END; i = oit_nodes[i].next) {
        if (n < LOCAL_NODES) {
            idx[n] = i;
            dep[n] = oit_nodes[i].depth;
            key[n] = key_of(i);
            ++n;
        }
        ++length;
    }
    if (length <= LOCAL_NODES) {
        // Insertion sort, nearest first.
        for (uint a = 1u; a < n; ++a) {
            uint ti = idx[a];
            uvec2 tk = key[a];
            float td = dep[a];
            int b = int(a) - 1;
            while (b >= 0 && in_front(td, tk, dep[b], key[b])) {
                idx[b + 1] = idx[b];
                dep[b + 1] = dep[b];
                key[b + 1] = key[b];
                --b;
            }
            idx[b + 1] = ti;
            dep[b + 1] = td;
            key[b + 1] = tk;
        }
        for (uint a = 0u; a < n && transmittance >= epsilon; ++a) {
            float alpha = oit_objects[oit_nodes[idx[a]].object].a;
            acc += transmittance * alpha * fragment_color(idx[a]);
            transmittance *= 1.0 - alpha;
            ++shaded;
        }
    } else {
        // Long list: sort it in place, relinking the nodes (bottom-up merge
        // sort of a linked list: O(n log n) steps, no extra memory, stable),
        // then composite from the front. A selection walk would take n^2
        // steps, and llvmpipe stops any shader after 65535 loop iterations in
        // all (LP_MAX_TGSI_LOOP_ITERATIONS): this keeps about 2500 fragments
        // per pixel within it; a GPU has no such limit.
        uint list = head;
        for (uint width = 1u;; width *= 2u) {
            uint p = list, tail = OIT_END, merges = 0u;
            list = OIT_END;
            while (p != OIT_END) {
                ++merges;
                uint q = p, psize = 0u;
                for (uint i = 0u; i < width && q != OIT_END; ++i) {
                    ++psize;
                    q = oit_nodes[q].next;
                }
                uint qsize = width;
                while (psize > 0u || (qsize > 0u && q != OIT_END)) {
                    uint e;
                    bool take_q = psize == 0u ||
                                  (qsize > 0u && q != OIT_END && in_front(oit_nodes[q].depth, key_of(q), oit_nodes[p].depth, key_of(p)));
                    if (take_q) {
                        e = q;
                        q = oit_nodes[q].next;
                        --qsize;
                    } else {
                        e = p;
                        p = oit_nodes[p].next;
                        --psize;
                    }
                    if (tail == OIT_END)
                        list = e;
                    else
                        oit_nodes[tail].next = e;
                    tail = e;
                }
                p = q;
            }
            oit_nodes[tail].next = OIT_END;
            if (merges <= 1u) break;
        }
        for (uint i = list; i != OIT_END && transmittance >= epsilon; i = oit_nodes[i].next) {
            float alpha = oit_objects[oit_nodes[i].object].a;
            acc += transmittance * alpha * fragment_color(i);
            transmittance *= 1.0 - alpha;
            ++shaded;
        }
    }
    vec3 result = acc + transmittance * srgb_to_linear(under.rgb);
    float alpha = 1.0 - transmittance * (1.0 - under.a);
    imageStore(color, p, vec4(srgb(result), alpha));
    atomicMax(stat_max_list, length);
    atomicAdd(stat_shaded, shaded);
    atomicAdd(stat_lists, 1u);
}
