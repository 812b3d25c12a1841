#version 450
#extension GL_GOOGLE_include_directive : require
// Overlay geometry in pixels (origin top left), coloured per vertex; markup
// vertices carry what the fragment shader compares with the frame's depth,
// text vertices their glyph atlas texel and channel (OverlayVertex in
// renderer/frame/annotations.hpp).
#include "std140.glsl"
#include "overlay_params.glsl"
layout(location = 0) in vec2 pixel;
layout(location = 1) in vec4 color;
layout(location = 2) in vec2 anchor;
layout(location = 3) in float inv_depth;
layout(location = 4) in float along;
layout(location = 5) in float hidden_alpha;
layout(location = 6) in vec2 texel;
layout(location = 7) in float atlas_channel;
out vec4 v_color;
flat out vec2 v_anchor;
flat out float v_hidden_alpha;
out float v_inv_depth; // w = 1: interpolated linearly in the image, exact for 1/depth along a projected segment
out float v_along;
out vec2 v_texel; // one texel per pixel: at a pixel's centre, the centre of its texel
flat out int v_channel;
void main() {
    v_color = color;
    v_anchor = anchor;
    v_hidden_alpha = hidden_alpha;
    v_inv_depth = inv_depth;
    v_along = along;
    v_texel = texel;
    v_channel = int(round(atlas_channel));
    // Text is drawn one atlas texel per pixel (its glyphs are anti-aliased by
    // FreeType); the rest is jittered with the scene, so accumulated frames
    // give lines and glyphs exact coverage.
    vec2 at = pixel + (atlas_channel < 0.0 ? jitter : vec2(0.0));
    gl_Position = vec4(at.x / viewport.x * 2.0 - 1.0, 1.0 - at.y / viewport.y * 2.0, 0.0, 1.0);
}
