// The translucent fragments whose AO oit_ao.comp traces (docs/voit.md):
// written by oit_resolve.comp's OIT_SORT variant, one entry per fragment
// that the composite will shade, with the indirect dispatch's group count
// kept up to date as entries arrive.
#define OIT_TRACE_GROUP 64
layout(std430, binding = 6) coherent buffer OitTrace {
    uint trace_groups_x;    // glDispatchComputeIndirect's (x, y, z): starts at (0, 1, 1)
    uint trace_groups_y;
    uint trace_groups_z;
    uint trace_count;       // entries appended (may pass the capacity: those are dropped)
    uvec2 trace_entries[];  // (node, pixel x | y << 16)
};

void oit_trace_append(ivec2 p, uint node) {
    uint k = atomicAdd(trace_count, 1u);
    if (k >= uint(trace_entries.length())) return;   // cannot happen: one entry per stored node at most
    if (k % uint(OIT_TRACE_GROUP) == 0u) atomicAdd(trace_groups_x, 1u);
    trace_entries[k] = uvec2(node, uint(p.x) | (uint(p.y) << 16));
}
