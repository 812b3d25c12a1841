#version 450
#extension GL_GOOGLE_include_directive : require
// The pick's compute step (docs/picking.md): per region pixel, the
// G-buffer's nearest opaque surface added to its list of translucent
// fragments sorted front to back in place (nearest first; ties by object,
// then primitive, as the VOIT resolve breaks them), ended at its first
// opaque entry, and the transmittance in front of each entry accumulated
// from the opacities: the read-back
// then knows each layer's alpha, share of the pixel and the visible layer.
#include "pick_common.glsl"

layout(local_size_x = 64) in;

// The G-buffer: each pixel's nearest opaque surface.
layout(binding = 0) uniform sampler2D depth_tex;      // reversed Z, 0 = background
layout(binding = 1) uniform usampler2D id_tex;        // object id, 0 = background
layout(binding = 2) uniform usampler2D primitive_tex; // its triangle

bool pick_before(uint a, uint b) {
    float da = pick_entries[a].depth, db = pick_entries[b].depth;
    uint oa = pick_entries[a].object, ob = pick_entries[b].object;
    return da > db || (da == db && (oa < ob || (oa == ob && pick_entries[a].primitive < pick_entries[b].primitive)));
}
#define LIST_NEXT(i) pick_entries[i].next
#define LIST_BEFORE(a, b) pick_before(a, b)
#define LIST_END PICK_END
#include "list_sort.glsl"

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= uint(pick_rect.z * pick_rect.w)) return;
    // The opaque layer: one entry from the G-buffer (translucent fragments
    // behind it were never listed: the list pass tests against its depth).
    ivec2 p = pick_rect.xy + ivec2(int(q % uint(pick_rect.z)), int(q / uint(pick_rect.z)));
    uint object = texelFetch(id_tex, p, 0).r;
    if (object != 0u) {
        uint k = atomicAdd(pick_count, 1u);
        if (k < pick_capacity) {
            pick_entries[k].depth = texelFetch(depth_tex, p, 0).r;
            pick_entries[k].object = object;
            pick_entries[k].primitive = texelFetch(primitive_tex, p, 0).r;
            pick_entries[k].alpha = 1.0;
            pick_entries[k].transmittance = 1.0;
            pick_entries[k].next = pick_heads[q];
            pick_heads[q] = k;
        }
    }
    uint head = list_sort(pick_heads[q]);
    pick_heads[q] = head;
    // Front to back, ending the list at its first opaque entry: nothing
    // behind it reaches the pixel (a translucent fragment at exactly its
    // depth may sort after it).
    float t = 1.0;
    for (uint i = head; i != PICK_END; i = pick_entries[i].next) {
        pick_entries[i].transmittance = t;
        t *= 1.0 - pick_entries[i].alpha;
        if (pick_entries[i].alpha >= 1.0) {
            pick_entries[i].next = PICK_END;
            break;
        }
    }
}
