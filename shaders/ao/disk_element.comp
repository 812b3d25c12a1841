#version 450
#extension GL_GOOGLE_include_directive : require
// Disk AO element pass (docs/ao.md; disk_element_passes in
// renderer/ao/disk_hierarchy.cpp): one invocation per node; each leaf's
// occlusion at its own disk (centre, normal), each emitter modulated by the
// previous pass's terms (none in the first). Writes the occlusion and the
// term 1 - occlusion; parents are filled by disk_parent.comp afterwards.
#include "std140.glsl"
#include "disk_params.glsl"
#include "disk_geometry.glsl"
#include "disk_traverse.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 4) writeonly buffer DiskTermsOut { float disk_terms_out[]; };
layout(std430, binding = 7) writeonly buffer DiskOcclusion { float disk_occlusion_out[]; }; // this pass's leaf occlusion

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= node_count) return;
    DiskNode e = disk_nodes[i];
    if (e.links.y >= 0) return; // a parent
    float o = disk_occlusion(e.centre_area.xyz, e.normal_bound.xyz, 1.0);
    disk_occlusion_out[i] = o;
    disk_terms_out[i] = 1.0 - o;
}
