#version 450
#extension GL_GOOGLE_include_directive : require
// Overlay colour; markups compare their depth with the frame's nearest
// opaque surface (the G-buffer depth) and are dimmed where it hides them:
// alpha times hidden_alpha, lines dashed. Glyphs decide by their
// point's 3x3 pixel block (hidden only if the surface is in front at all
// nine, so a point on a silhouette or a grazing surface stays whole), lines
// per fragment. Text (labels are 2D: never compared) takes its alpha from
// the glyph atlas: the glyph's coverage, or the halo drawn under it.
#include "std140.glsl"
#include "overlay_params.glsl"
layout(binding = 0) uniform sampler2D depth_tex; // reversed Z, 0 = nothing drawn
layout(binding = 1) uniform sampler2D atlas_tex; // red: glyph coverage, green: halo; rows from the top
in vec4 v_color;
flat in vec2 v_anchor;
flat in float v_hidden_alpha;
in float v_inv_depth;
in float v_along;
in vec2 v_texel;
flat in int v_channel;
layout(location = 0) out vec4 out_color;

// Is the frame's surface at GL pixel p nearer than depth z (mm) by more than the tolerance?
bool surface_in_front(ivec2 p, float z) {
    p = clamp(p, ivec2(0), ivec2(viewport) - 1);
    float d = texelFetch(depth_tex, p, 0).r;
    if (d <= 0.0) return false; // background
    float n = near_far.x, f = near_far.y;
    return n * f / (d * (f - n) + n) < z - tolerance_mm;
}

void main() {
    vec4 c = v_color;
    if (v_channel >= 0) c.a *= texelFetch(atlas_tex, ivec2(floor(v_texel)), 0)[v_channel];
    if (v_inv_depth > 0.0) {
        float z = 1.0 / v_inv_depth;
        bool hidden = true;
        if (v_anchor.x >= 0.0) {
            // Image rows run top-down, GL rows bottom-up.
            ivec2 a = ivec2(floor(v_anchor.x), floor(viewport.y - v_anchor.y));
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) hidden = hidden && surface_in_front(a + ivec2(dx, dy), z);
        } else {
            hidden = surface_in_front(ivec2(gl_FragCoord.xy), z);
        }
        if (hidden) {
            if (v_along >= 0.0 && fract(v_along / dash_period) >= 0.5) discard;
            c.a *= v_hidden_alpha;
        }
    }
    out_color = c;
}
