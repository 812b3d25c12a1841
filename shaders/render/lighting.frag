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
in vec2 uv;

layout(binding = 0) uniform sampler2D normal_tex;
layout(binding = 1) uniform sampler2D albedo_tex;
layout(binding = 2) uniform sampler2D ao_tex;     // R32F, 1 = unoccluded

layout(location = 0) out vec4 out_color;

vec3 aces(vec3 x) {
    const float a = 2.51, b = 0.03, c = 2.43, d = 0.59, e = 0.14;
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), 0.0, 1.0);
}

vec3 srgb(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}

void main() {
    vec4 nw = texture(normal_tex, uv);
    if (nw.w < 0.5) {
        out_color = vec4(srgb(background.rgb), background.a);
        return;
    }
    vec3 n = normalize(world_to_view * nw.xyz);   // view space, camera looks down -z
    vec3 v = vec3(0.0, 0.0, 1.0);
    vec3 albedo = texture(albedo_tex, uv).rgb;
    vec3 key = normalize(vec3(-0.45, 0.6, 0.65));
    vec3 head = v;
    float ao = use_ao ? texelFetch(ao_tex, ivec2(gl_FragCoord.xy), 0).r : 1.0;
    float ambient = (use_ao ? 0.42 : 0.12) * (0.6 + 0.4 * n.y) * ao;   // brighter from above
    vec3 color = albedo * ambient;
    for (int i = 0; i < 2; ++i) {
        vec3 l = i == 0 ? key : head;
        float intensity = i == 0 ? 0.75 : (use_ao ? 0.12 : 0.35);
        float ndl = max(dot(n, l), 0.0);
        vec3 h = normalize(l + v);
        float spec = ndl > 0.0 ? pow(max(dot(n, h), 0.0), 48.0) * (48.0 + 8.0) / (8.0 * 3.14159265) : 0.0;
        color += intensity * (albedo * ndl + 0.04 * spec * ndl);
    }
    out_color = vec4(srgb(aces(color)), 1.0);
}
