#version 450
#extension GL_GOOGLE_include_directive : require
// Deferred lighting: a key light from the upper left of the viewer and a
// headlight, Lambert diffuse plus a normalized Blinn-Phong highlight, a
// hemispherical ambient term that ambient occlusion modulates, ACES-fitted
// tone mapping and sRGB encoding. With AO the ambient (sky) light is
// stronger and the headlight weaker, so folds and cavities read darker while
// the overall brightness stays about the same.
#include "std140.glsl"
#include "lighting_params.glsl"
#include "shading.glsl"
in vec2 uv;

layout(binding = 0) uniform sampler2D normal_tex;
layout(binding = 1) uniform sampler2D albedo_tex;
layout(binding = 2) uniform sampler2D ao_tex;     // R32F, 1 = unoccluded

layout(location = 0) out vec4 out_color;

void main() {
    vec4 nw = texture(normal_tex, uv);
    if (nw.w < 0.5) {
        out_color = vec4(srgb(background.rgb), background.a);
        return;
    }
    vec3 albedo = texture(albedo_tex, uv).rgb;
    if (flat_shading) {   // each surface is its albedo: compositing checks are exact
        out_color = vec4(srgb(albedo), 1.0);
        return;
    }
    float ao = use_ao ? texelFetch(ao_tex, ivec2(gl_FragCoord.xy), 0).r : 1.0;
    // An AO image made outside the frame (ray traced) may miss a silhouette
    // pixel that the rasterizer covers: NaN there, taken as unoccluded.
    if (isnan(ao)) ao = 1.0;
    out_color = vec4(srgb(shade(normalize(world_to_view * nw.xyz), albedo, use_ao, ao)), 1.0);
}
