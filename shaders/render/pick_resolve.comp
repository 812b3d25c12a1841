#version 450
#extension GL_GOOGLE_include_directive : require
// The pick's compute step (docs/picking.md): per region pixel, its list of
// fragments sorted front to back in place (nearest first; ties by object,
// then primitive, as the VOIT resolve breaks them), and the transmittance
// in front of each entry accumulated from the opacities: the read-back
// then knows each layer's alpha, share of the pixel and the visible layer.
#include "pick_common.glsl"

layout(local_size_x = 64) in;

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
    uint head = list_sort(pick_heads[q]);
    pick_heads[q] = head;
    float t = 1.0;
    for (uint i = head; i != PICK_END; i = pick_entries[i].next) {
        pick_entries[i].transmittance = t;
        t *= 1.0 - pick_entries[i].alpha;
    }
}
