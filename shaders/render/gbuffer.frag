#version 450
#extension GL_GOOGLE_include_directive : require
// Writes the world normal, the object id and the albedo; depth goes to the
// (reversed-Z, float) depth attachment. With GB_PRIMITIVE (a pick rides on
// this frame), the triangle too (mesh_triangle()): the pick's opaque layer
// (docs/picking.md). With GB_VIS (DSRAA's multisample visibility
// sub-samples), only the object id and the octahedral normal, in one RG32UI
// output: the albedo follows from the id. No side effects, so the depth
// test stays early.
#include "octahedral.glsl"
#include "clip.glsl"
#include "lod_pick.glsl"

in vec3 world_normal;

uniform uint object_id;
uniform vec3 albedo;

#ifdef GB_VIS
layout(location = 0) out uvec2 out_vis; // RG32UI: object id, pack_normal(world normal)
#else
// Locations from the layout table (renderer/passes/gbuffer_layout.hpp)
// through #defines; the fallbacks only serve the build-time validation
// (tests/gl/gbuffer_layout_test.cpp checks the linked locations).
#ifndef GB_NORMAL
#define GB_NORMAL 0
#define GB_ID 1
#define GB_ALBEDO 2
#endif
layout(location = GB_NORMAL) out vec4 out_normal;   // RGBA16F: world normal, w = 1 on geometry
layout(location = GB_ID) out uint out_id;           // R32UI
layout(location = GB_ALBEDO) out vec4 out_albedo;   // RGBA8
#ifdef GB_PRIMITIVE
layout(location = GB_PRIMITIVE) out uint out_primitive;   // R32UI
#endif
#endif

void main() {
    clip_fragment();
    vec3 n = normalize(world_normal);
    // Two-sided: open surfaces (cut by the volume border) show their inside.
    if (!gl_FrontFacing) n = -n;
#ifdef GB_VIS
    out_vis = uvec2(object_id, pack_normal(n));
#else
    out_normal = vec4(n, 1.0);
    out_id = object_id;
    out_albedo = vec4(albedo, 1.0);
#ifdef GB_PRIMITIVE
    out_primitive = mesh_triangle();
#endif
#endif
}
