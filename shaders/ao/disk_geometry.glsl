// Exact geometric kernels of disk-based AO (docs/ao.md, "Disk AO: exact
// kernels"): the GLSL port, line by line, of renderer/ao/disk_geometry.cpp
// (float instantiation). Same names with a disk_ prefix, same guards, same
// conventions (receiver p with unit normal n; a polygon whose front faces p
// has a positive form factor; occlusion terms in [0, 1]).
// tests/gl/disk_ao_test.cpp runs every function here in a compute shader
// (shaders/ao/disk_geometry_check.comp) and compares with the C++ templates.

#ifndef DISK_GEOMETRY_GLSL
#define DISK_GEOMETRY_GLSL

#define DISK_PI 3.14159265358979323846
// Below this a squared length is treated as zero (tiny_squared<float>()).
#define DISK_TINY_SQUARED 1e-30

// snapped_plane_distance: dot(n, v - p), snapped to 0 within epsilon.
float disk_snapped_plane_distance(vec3 p, vec3 n, vec3 v, float epsilon) {
    float s = dot(n, v - p);
    return abs(s) <= epsilon ? 0.0 : s;
}

// clip_to_tangent_plane (the chapter's visibleQuad): the visible part of the
// triangle above the tangent plane as 4 points (a triangle repeats its last
// point, invisible sets all four to p). Returns the count: 0, 3 or 4.
int disk_clip_to_tangent_plane(vec3 p, vec3 n, vec3 v0, vec3 v1, vec3 v2, float epsilon, out vec3 q[4]) {
    vec3 v[3] = vec3[3](v0, v1, v2);
    float s[3] = float[3](disk_snapped_plane_distance(p, n, v0, epsilon), disk_snapped_plane_distance(p, n, v1, epsilon),
                          disk_snapped_plane_distance(p, n, v2, epsilon));
    q[0] = p;
    q[1] = p;
    q[2] = p;
    q[3] = p;
    // No vertex strictly above: no visible area (8 of the 27 sign cases).
    if (!(s[0] > 0.0 || s[1] > 0.0 || s[2] > 0.0)) return 0;
    // One Sutherland-Hodgman step against s >= 0; at most 4 points.
    int k = 0;
    for (int i = 0; i < 3; ++i) {
        int j = i == 2 ? 0 : i + 1;
        if (s[i] >= 0.0) q[k++] = v[i];
        if ((s[i] > 0.0 && s[j] < 0.0) || (s[i] < 0.0 && s[j] > 0.0)) {
            float t = s[i] / (s[i] - s[j]);
            q[k++] = v[i] + t * (v[j] - v[i]);
        }
    }
    if (k == 3) q[3] = q[2];
    return k;
}

// polygon_form_factor: exact form factor from (p, n) to the planar polygon
// q[0..count-1] (count <= 4) by the contour integral; degenerate edges add 0.
float disk_polygon_form_factor(vec3 p, vec3 n, vec3 q[4], int count) {
    float sum = 0.0;
    for (int i = 0; i < count; ++i) {
        int j = i + 1 == count ? 0 : i + 1;
        vec3 ri = q[i] - p;
        vec3 rj = q[j] - p;
        float li2 = dot(ri, ri);
        float lj2 = dot(rj, rj);
        vec3 c = cross(rj, ri);
        float c2 = dot(c, c);
        if (li2 <= DISK_TINY_SQUARED || lj2 <= DISK_TINY_SQUARED || c2 <= 1e-24 * li2 * lj2) continue;
        float cl = sqrt(c2);
        float theta = atan(cl, dot(ri, rj)); // in [0, pi]
        sum += theta * dot(n, c) / cl;
    }
    return sum / (2.0 * DISK_PI);
}

// clipped_triangle_form_factor: visibleQuad, then the polygon's form factor.
float disk_clipped_triangle_form_factor(vec3 p, vec3 n, vec3 v0, vec3 v1, vec3 v2, float epsilon) {
    vec3 q[4];
    int count = disk_clip_to_tangent_plane(p, n, v0, v1, v2, epsilon, q);
    if (count == 0) return 0.0;
    return disk_polygon_form_factor(p, n, q, 4);
}

// disk_form_factor (Bunnell): A cos_e cos_r / (pi d^2 + A), front-facing
// emitters above the tangent plane only; c == p gives 0.
float disk_form_factor(vec3 p, vec3 n, vec3 c, vec3 m, float area) {
    vec3 d = c - p;
    float d2 = max(dot(d, d), DISK_TINY_SQUARED);
    vec3 v = d * (1.0 / sqrt(d2));
    float cos_r = max(dot(n, v), 0.0);
    float cos_e = max(-dot(m, v), 0.0);
    float a = max(area, 0.0);
    float denom = DISK_PI * d2 + a;
    return a * cos_e * cos_r / denom;
}

// distance_attenuation (listing 4): 1 / (1 + k d^2).
float disk_distance_attenuation(float d2, float k) {
    return 1.0 / (1.0 + max(k, 0.0) * max(d2, 0.0));
}

// triangle_attenuation (listing 5): pow(e, t), written out at t = 0 and e = 0.
float disk_triangle_attenuation(float element_term, float t) {
    float e = clamp(element_term, 0.0, 1.0);
    float tt = max(t, 0.0);
    if (tt == 0.0) return 1.0;
    if (e == 0.0) return 0.0;
    return pow(e, tt);
}

// converge_blend (listing 3): min_scale min(o0, o1) + max_scale max(o0, o1).
float disk_converge_blend(float o0, float o1, float min_scale, float max_scale) {
    return min_scale * min(o0, o1) + max_scale * max(o0, o1);
}

#endif
