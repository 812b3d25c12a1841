// Exact geometric kernels of disk-based AO (see disk_geometry.hpp). Each
// function maps one to one onto a GLSL function: glm::vec<3, T> -> vec3,
// std::atan2 -> atan(y, x), std::pow -> pow.
#include "renderer/ao/disk_geometry.hpp"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace iso {

namespace {

// Below this a squared length is treated as zero. Representable in float
// (min normal 1.2e-38) and far below any mm-scale geometry.
template <typename T> constexpr T tiny_squared() { return T(1e-30); }

} // namespace

template <typename T>
T snapped_plane_distance(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& v, T epsilon) {
    const T s = glm::dot(n, v - p);
    return std::abs(s) <= epsilon ? T(0) : s;
}

template <typename T>
ClippedQuad<T> clip_to_tangent_plane(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& v0,
                                     const glm::vec<3, T>& v1, const glm::vec<3, T>& v2, T epsilon) {
    const glm::vec<3, T> v[3] = {v0, v1, v2};
    const T s[3] = {snapped_plane_distance(p, n, v0, epsilon), snapped_plane_distance(p, n, v1, epsilon),
                    snapped_plane_distance(p, n, v2, epsilon)};

    ClippedQuad<T> out;
    // No vertex strictly above: the visible part has no area (8 of the 27
    // sign cases: each vertex on or below, including all three on the plane).
    if (!(s[0] > T(0) || s[1] > T(0) || s[2] > T(0))) {
        out.q[0] = out.q[1] = out.q[2] = out.q[3] = p;
        out.count = 0;
        out.visible = false;
        return out;
    }
    // The other 19 cases: one Sutherland-Hodgman step against s >= 0. At most
    // 4 points: two strict sign changes around a triangle need a vertex below,
    // which leaves at most two kept vertices.
    int k = 0;
    for (int i = 0; i < 3; ++i) {
        const int j = i == 2 ? 0 : i + 1;
        if (s[i] >= T(0)) out.q[k++] = v[i];
        if ((s[i] > T(0) && s[j] < T(0)) || (s[i] < T(0) && s[j] > T(0))) {
            // Opposite strict signs (|s| > epsilon each): s[i] - s[j] != 0 and
            // the parameter lies in (0, 1).
            const T t = s[i] / (s[i] - s[j]);
            out.q[k++] = v[i] + t * (v[j] - v[i]);
        }
    }
    out.count = k; // 3 or 4
    if (k == 3) out.q[3] = out.q[2];
    out.visible = true;
    return out;
}

template <typename T>
T polygon_form_factor(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>* q, int count) {
    T sum = T(0);
    for (int i = 0; i < count; ++i) {
        const int j = i + 1 == count ? 0 : i + 1;
        const glm::vec<3, T> ri = q[i] - p;
        const glm::vec<3, T> rj = q[j] - p;
        const T li2 = glm::dot(ri, ri);
        const T lj2 = glm::dot(rj, rj);
        // cross(r_j, r_i): its direction makes a polygon whose front faces p
        // positive (see the header).
        const glm::vec<3, T> c = glm::cross(rj, ri);
        const T c2 = glm::dot(c, c);
        // Degenerate edge: an endpoint at p, zero length, or p on the edge's
        // line (no plane through p and the edge). |c|^2 = |ri|^2 |rj|^2 sin^2.
        if (li2 <= tiny_squared<T>() || lj2 <= tiny_squared<T>() || c2 <= T(1e-24) * li2 * lj2) continue;
        const T cl = std::sqrt(c2);
        const T theta = std::atan2(cl, glm::dot(ri, rj)); // in [0, pi]
        sum += theta * glm::dot(n, c) / cl;
    }
    return sum / (T(2) * T(3.14159265358979323846));
}

template <typename T>
T clipped_triangle_form_factor(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& v0,
                               const glm::vec<3, T>& v1, const glm::vec<3, T>& v2, T epsilon) {
    const ClippedQuad<T> quad = clip_to_tangent_plane(p, n, v0, v1, v2, epsilon);
    if (!quad.visible) return T(0);
    return polygon_form_factor(p, n, quad.q, 4); // a repeated point is a zero-length edge: no term
}

template <typename T>
T disk_form_factor(const glm::vec<3, T>& p, const glm::vec<3, T>& n, const glm::vec<3, T>& c, const glm::vec<3, T>& m,
                   T area) {
    const glm::vec<3, T> d = c - p;
    const T d2 = std::max(glm::dot(d, d), tiny_squared<T>());
    const glm::vec<3, T> v = d * (T(1) / std::sqrt(d2)); // 0 when c == p (GLSL: inversesqrt)
    const T cos_r = std::max(glm::dot(n, v), T(0));
    const T cos_e = std::max(-glm::dot(m, v), T(0));
    const T a = std::max(area, T(0));
    const T denom = T(3.14159265358979323846) * d2 + a; // > 0: d2 >= tiny
    return a * cos_e * cos_r / denom;
}

template <typename T> T distance_attenuation(T d2, T k) {
    return T(1) / (T(1) + std::max(k, T(0)) * std::max(d2, T(0)));
}

template <typename T> T triangle_attenuation(T element_term, T t) {
    const T e = std::clamp(element_term, T(0), T(1));
    const T tt = std::max(t, T(0));
    if (tt == T(0)) return T(1);
    if (e == T(0)) return T(0);
    return std::pow(e, tt);
}

template <typename T> T converge_blend(T o0, T o1, T min_scale, T max_scale) {
    return min_scale * std::min(o0, o1) + max_scale * std::max(o0, o1);
}

#define ISO_DISK_GEOMETRY_INSTANTIATE(T)                                                                               \
    template T snapped_plane_distance<T>(const glm::vec<3, T>&, const glm::vec<3, T>&, const glm::vec<3, T>&, T);      \
    template ClippedQuad<T> clip_to_tangent_plane<T>(const glm::vec<3, T>&, const glm::vec<3, T>&,                     \
                                                     const glm::vec<3, T>&, const glm::vec<3, T>&,                     \
                                                     const glm::vec<3, T>&, T);                                        \
    template T polygon_form_factor<T>(const glm::vec<3, T>&, const glm::vec<3, T>&, const glm::vec<3, T>*, int);       \
    template T clipped_triangle_form_factor<T>(const glm::vec<3, T>&, const glm::vec<3, T>&, const glm::vec<3, T>&,    \
                                               const glm::vec<3, T>&, const glm::vec<3, T>&, T);                       \
    template T disk_form_factor<T>(const glm::vec<3, T>&, const glm::vec<3, T>&, const glm::vec<3, T>&,                \
                                   const glm::vec<3, T>&, T);                                                          \
    template T distance_attenuation<T>(T, T);                                                                          \
    template T triangle_attenuation<T>(T, T);                                                                          \
    template T converge_blend<T>(T, T, T, T);

ISO_DISK_GEOMETRY_INSTANTIATE(float)
ISO_DISK_GEOMETRY_INSTANTIATE(double)

#undef ISO_DISK_GEOMETRY_INSTANTIATE

} // namespace iso
