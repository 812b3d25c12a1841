#version 450
#extension GL_GOOGLE_include_directive : require
// VOIT translucent AO (docs/voit.md): one invocation per fragment that the
// composite will shade (listed by oit_resolve.comp's OIT_SORT variant, so
// the SIMD lanes trace side by side however long each pixel's list is).
// Each traces the cone AO pass's cones from the fragment's own eye-space
// point and normal through the opaque surfaces' slicemap, and stores the AO
// by node for the composite (OIT_SORTED).
#include "std140.glsl"
#include "oit_params.glsl"
#include "oit_common.glsl"
#include "oit_trace.glsl"
#define CONE_SLICEMAP_BINDING 0
#define CONE_ZRANGE_BINDING 4
#define CONE_PATTERN_BINDING 5
#include "ao/ao_common.glsl"
#include "ao/cone_params.glsl"
#include "ao/cone_trace.glsl"

layout(local_size_x = OIT_TRACE_GROUP) in;

layout(std430, binding = 7) writeonly buffer OitAo { float oit_ao[]; };   // per node

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= min(trace_count, uint(trace_entries.length()))) return;
    uvec2 e = trace_entries[k];
    uint i = e.x;
    ivec2 p = ivec2(e.y & 0xFFFFu, e.y >> 16);
    // The fragment's eye-space point, from its reversed-Z depth, as cone.comp
    // recovers a G-buffer pixel's.
    float d = oit_nodes[i].depth;
    vec3 q = eye_point_at_depth(p, image_size, proj_scale, linear_depth(d, near_plane, far_plane));
    vec3 n = normalize(view_rotation * unpack_normal(oit_nodes[i].normal));
    oit_ao[i] = cone_ao(q, n, p);
}
