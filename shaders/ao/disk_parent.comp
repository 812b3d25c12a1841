#version 450
#extension GL_GOOGLE_include_directive : require
// Disk AO: the parents of one tree level (deepest first; fill_parent_terms
// in renderer/ao/disk_hierarchy.cpp): each the area-weighted mean of its
// children's terms, which are area-weighted means of their leaves, so a
// parent gets the area-weighted mean of its leaves (the plain mean of the
// leaves when their area is 0). The children of node i are i + 1 and then
// each one's skip, until the parent's own skip.
#include "std140.glsl"
#include "disk_params.glsl"

layout(local_size_x = 64) in;

struct DiskNode {
    vec4 centre_area;
    vec4 normal_bound;
    ivec4 links;
};
layout(std430, binding = 0) readonly buffer DiskNodes { DiskNode disk_nodes[]; };
layout(std430, binding = 4) buffer DiskTerms { float disk_terms[]; };
layout(std430, binding = 5) readonly buffer DiskLevels { int disk_level_nodes[]; };
layout(std430, binding = 6) readonly buffer DiskLeafCounts { float disk_leaf_count[]; }; // leaves below each node

void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= count) return;
    int i = disk_level_nodes[first + k];
    DiskNode e = disk_nodes[i];
    float area = 0.0, weighted = 0.0, leaves = 0.0, plain = 0.0;
    for (int c = e.links.y; c < e.links.x; c = disk_nodes[c].links.x) {
        float a = disk_nodes[c].centre_area.w;
        float term = disk_terms[c];
        area += a;
        weighted += a * term;
        leaves += disk_leaf_count[c];
        plain += disk_leaf_count[c] * term;
    }
    disk_terms[i] = area > 0.0 ? weighted / area : (leaves > 0.0 ? plain / leaves : 1.0);
}
