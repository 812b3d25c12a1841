// Picking in the frame's own geometry passes (docs/picking.md): every
// translucent fragment inside the pick region (VOIT list pass) appends
// (depth, object, primitive, alpha) to its region pixel's linked list: an
// entry from a pool by an atomic counter, linked in by exchanging the
// pixel's head. pick_resolve.comp adds the nearest opaque surface from the
// G-buffer (its id and, with a pick, triangle channels), sorts each list
// front to back and writes the transmittance before each entry.
struct PickEntry {
    float depth;          // reversed Z: larger is nearer
    uint object;          // 1-based object id
    uint primitive;       // mesh_triangle(): the triangle in the object's mesh
    float alpha;          // the object's opacity
    uint next;            // the pixel's next entry; 0xFFFFFFFF ends it
    float transmittance;  // before this entry, front to back (pick_resolve.comp)
};
const uint PICK_END = 0xFFFFFFFFu;

layout(std430, binding = 8) coherent buffer PickCounters {
    uint pick_count;      // entries offered (stored or not)
    uint pick_capacity;   // entries the pool holds
};
layout(std430, binding = 9) coherent buffer PickEntries { PickEntry pick_entries[]; };
layout(std430, binding = 10) coherent buffer PickHeads { uint pick_heads[]; };   // per region pixel, row by row from the region's bottom-left

uniform ivec4 pick_rect;   // the region in GL window pixels (bottom-up): x, y, width, height

#ifdef PICK_APPEND
void pick_append(uint object, float alpha) {
    ivec2 q = ivec2(gl_FragCoord.xy) - pick_rect.xy;
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, pick_rect.zw))) return;
    uint k = atomicAdd(pick_count, 1u);
    if (k >= pick_capacity) return;   // counted: the read-back reports how many did not fit
    pick_entries[k].depth = gl_FragCoord.z;
    pick_entries[k].object = object;
    pick_entries[k].primitive = mesh_triangle();
    pick_entries[k].alpha = alpha;
    pick_entries[k].transmittance = 1.0;
    pick_entries[k].next = atomicExchange(pick_heads[uint(q.y) * uint(pick_rect.z) + uint(q.x)], k);
}
#endif
