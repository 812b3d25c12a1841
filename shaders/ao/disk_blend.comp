#version 450
#extension GL_GOOGLE_include_directive : require
// Disk AO convergence (chapter, listing 3; disk_element_passes in
// renderer/ao/disk_hierarchy.cpp): every leaf's term is 1 - the weighted
// minimum of its occlusion in the last two passes; parents are then
// recomputed from them (disk_parent.comp).
#include "std140.glsl"
#include "disk_params.glsl"
#include "disk_geometry.glsl"

layout(local_size_x = 64) in;

struct DiskNode {
    vec4 centre_area;
    vec4 normal_bound;
    ivec4 links;
};
layout(std430, binding = 0) readonly buffer DiskNodes { DiskNode disk_nodes[]; };
layout(std430, binding = 4) writeonly buffer DiskTerms { float disk_terms[]; };
layout(std430, binding = 7) readonly buffer DiskOcclusion { float disk_occlusion_last[]; };
layout(std430, binding = 8) readonly buffer DiskOcclusionPrevious { float disk_occlusion_previous[]; };

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= node_count) return;
    if (disk_nodes[i].links.y >= 0) return;
    float o = disk_converge_blend(disk_occlusion_previous[i], disk_occlusion_last[i], min_scale, max_scale);
    disk_terms[i] = 1.0 - clamp(o, 0.0, 1.0);
}
