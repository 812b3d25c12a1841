#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require
// G-buffer: positions in LPS mm, normals in LPS (world) space.
#include "std140.glsl"
#include "gbuffer_params.glsl"
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;


out vec3 world_normal;
out vec3 world_position;   // the clip's (clip.glsl)
// The draw's first triangle: a cluster's, in indirect draws (lod_pick.glsl).
flat out uint primitive_base;

void main() {
    world_normal = normal;
    world_position = position;
    primitive_base = uint(gl_BaseInstanceARB);
    gl_Position = view_projection * vec4(position, 1.0);
}
