#version 450
#extension GL_GOOGLE_include_directive : require
// Slicemap voxelization (Eisemann & Decoret): the scene drawn into the
// screen-aligned grid with the frame's own projection; depth clamp on, so
// nothing is clipped by the near or far plane.
#include "std140.glsl"
#include "voxelize_params.glsl"
layout(location = 0) in vec3 position;


out float view_depth; // linear depth, mm

void main() {
    view_depth = -(view * vec4(position, 1.0)).z;
    gl_Position = view_projection * vec4(position, 1.0);
}
