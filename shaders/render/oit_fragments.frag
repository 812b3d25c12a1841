#version 450
#extension GL_GOOGLE_include_directive : require
// VOIT fragment lists: every fragment of a translucent surface in front of
// the opaque depth (early depth test against the G-buffer's depth, no depth
// writes) is appended to its pixel's list: a node from the pool by an
// atomic counter, linked in by exchanging the head-pointer image. A full
// pool counts the fragment as overflow and drops it (the renderer redraws
// with a larger pool, up to its memory cap).
#include "std140.glsl"
#include "oit_params.glsl"
#include "oit_common.glsl"

layout(early_fragment_tests) in;

in vec3 world_normal;
uniform uint object_id;   // per draw

layout(binding = 0, r32ui) coherent uniform uimage2D heads;

void main() {
    vec3 n = normalize(world_normal);
    if (!gl_FrontFacing) n = -n;   // two-sided, as the opaque surfaces
    uint index = atomicAdd(oit_count, 1u);
    if (index >= capacity) {
        atomicAdd(oit_overflow, 1u);
        return;
    }
    oit_nodes[index].depth = gl_FragCoord.z;
    oit_nodes[index].object = object_id;
    oit_nodes[index].primitive = uint(gl_PrimitiveID);
    oit_nodes[index].normal = pack_normal(n);
    oit_nodes[index].next = imageAtomicExchange(heads, ivec2(gl_FragCoord.xy), index);
}
