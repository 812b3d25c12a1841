// Surface shading shared by the lighting pass (opaque surfaces) and the VOIT
// resolve (translucent fragments), so both look the same: a key light from
// the viewer's upper left and a headlight, Lambert diffuse plus a normalized
// Blinn-Phong highlight, and a hemispherical ambient term that ambient
// occlusion modulates (stronger, with a weaker headlight, when AO is on).
// Returns display-referred linear RGB: ACES-fitted tone mapping applied.

vec3 aces(vec3 x) {
    const float a = 2.51, b = 0.03, c = 2.43, d = 0.59, e = 0.14;
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), 0.0, 1.0);
}

#include "srgb.glsl"

// n_view: unit normal in view space (the camera looks down -z).
vec3 shade(vec3 n_view, vec3 albedo, bool use_ao, float ao) {
    vec3 n = n_view;
    vec3 v = vec3(0.0, 0.0, 1.0);
    vec3 key = normalize(vec3(-0.45, 0.6, 0.65));
    vec3 head = v;
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
    return aces(color);
}
