#version 450
#extension GL_GOOGLE_include_directive : require
// Overlay geometry in pixels (origin top left), coloured per vertex.
#include "std140.glsl"
#include "overlay_params.glsl"
layout(location = 0) in vec2 pixel;
layout(location = 1) in vec4 color;
out vec4 v_color;
void main() {
    v_color = color;
    gl_Position = vec4(pixel.x / viewport.x * 2.0 - 1.0, 1.0 - pixel.y / viewport.y * 2.0, 0.0, 1.0);
}
