// The triangle of the object's mesh that a fragment belongs to, as picks
// name it (docs/picking.md). A surface with levels of detail
// (renderer/passes/lod_draw.hpp) draws level 0 by cluster: each cluster's
// draw starts at its first triangle (the draw's base instance, passed on by
// gbuffer.vert as primitive_base) and level 0's triangles are the mesh's
// reordered, so triangle_order maps them back.
#ifndef LOD_PICK_GLSL
#define LOD_PICK_GLSL
layout(std430, binding = 7) readonly buffer TriangleOrder { uint triangle_order[]; };
uniform bool reordered;
flat in uint primitive_base;

uint mesh_triangle() {
    uint t = primitive_base + uint(gl_PrimitiveID);
    return reordered ? triangle_order[t] : t;
}
#endif
