// Exact kernels of disk-based AO (renderer/ao/disk_geometry.hpp): the
// tangent-plane clipping in all 27 sign cases, the point-to-polygon form
// factor against closed forms and numerical integration, Bunnell's disk
// approximation, the attenuations and the convergence blend.
#include "renderer/ao/disk_geometry.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

using namespace iso;

namespace {

using V = glm::dvec3;

// A receiver frame away from the origin with a tilted normal, so that nothing
// depends on axis-aligned arithmetic.
struct Frame {
    V p{0.3, -1.2, 2.5};
    V n = glm::normalize(V(0.2, -0.5, 1.0));
    V t = glm::normalize(glm::cross(V(1, 0, 0), n));
    V b = glm::cross(n, t);
    // x, y along the tangent plane, z = height above it.
    V at(double x, double y, double z) const { return p + x * t + y * b + z * n; }
};

double height(const Frame& f, const V& v) { return glm::dot(f.n, v - f.p); }

// Vector area of a planar polygon (its length is the area; its direction the
// right-hand front normal).
V vector_area(const V* q, int count) {
    V a(0.0);
    for (int i = 0; i < count; ++i) a += 0.5 * glm::cross(q[i], q[(i + 1) % count]);
    return a;
}

double tri_area(const V& a, const V& b, const V& c) { return 0.5 * glm::length(glm::cross(b - a, c - a)); }

// Reference form factor by brute force: the triangle subdivided 4 ways,
// uniformly to depth `smooth` (centroid rule, O(h^2) where the integrand is
// smooth) and down to depth `edge` where the subtriangle straddles the
// tangent plane (the cut-off is a step; it costs O(h) only along the cut).
// Points below the plane contribute nothing; the emitter's cosine is signed
// so that a front face towards p counts positive, as in polygon_form_factor.
double integrate_form_factor(const V& p, const V& n, const V& a, const V& b, const V& c, const V& front, int depth,
                             int smooth, int edge) {
    const double ha = glm::dot(n, a - p), hb = glm::dot(n, b - p), hc = glm::dot(n, c - p);
    const bool straddles = !((ha > 0 && hb > 0 && hc > 0) || (ha <= 0 && hb <= 0 && hc <= 0));
    if (depth >= edge || (depth >= smooth && !straddles)) {
        const V x = (a + b + c) / 3.0;
        const V r = x - p;
        const double r2 = glm::dot(r, r);
        const double cos_r = glm::dot(n, r) / std::sqrt(r2);
        if (cos_r <= 0) return 0.0;
        const double cos_e = -glm::dot(front, r) / std::sqrt(r2);
        return cos_r * cos_e / (std::numbers::pi * r2) * tri_area(a, b, c);
    }
    const V ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
    return integrate_form_factor(p, n, a, ab, ca, front, depth + 1, smooth, edge) +
           integrate_form_factor(p, n, ab, b, bc, front, depth + 1, smooth, edge) +
           integrate_form_factor(p, n, ca, bc, c, front, depth + 1, smooth, edge) +
           integrate_form_factor(p, n, ab, bc, ca, front, depth + 1, smooth, edge);
}

double integrate_form_factor(const V& p, const V& n, const V& a, const V& b, const V& c) {
    const V front = glm::normalize(glm::cross(b - a, c - a));
    return integrate_form_factor(p, n, a, b, c, front, 0, 9, 15);
}

// The fraction of a triangle's area above the plane, from the vertex heights
// alone (similar triangles): one vertex a above, the others at heights
// hb, hc <= 0: (ha / (ha - hb)) (ha / (ha - hc)); one vertex c below, the
// others at or above: 1 - (hc / (hc - ha)) (hc / (hc - hb)).
double visible_fraction(const std::array<double, 3>& h) {
    int above = 0, below = 0;
    for (double x : h) above += x > 0, below += x < 0;
    if (above == 0) return 0.0;
    if (below == 0) return 1.0;
    if (above == 1) {
        const int a = h[0] > 0 ? 0 : h[1] > 0 ? 1 : 2;
        const double hb = h[(a + 1) % 3], hc = h[(a + 2) % 3];
        return (h[a] / (h[a] - hb)) * (h[a] / (h[a] - hc));
    }
    const int c = h[0] < 0 ? 0 : h[1] < 0 ? 1 : 2;
    const double ha = h[(c + 1) % 3], hb = h[(c + 2) % 3];
    return 1.0 - (h[c] / (h[c] - ha)) * (h[c] / (h[c] - hb));
}

// Barycentric coordinates of x in the plane of triangle (a, b, c).
glm::dvec3 barycentric(const V& x, const V& a, const V& b, const V& c) {
    const V n = glm::cross(b - a, c - a);
    const double d = glm::dot(n, n);
    const double wa = glm::dot(glm::cross(c - b, x - b), n) / d;
    const double wb = glm::dot(glm::cross(a - c, x - c), n) / d;
    return {wa, wb, 1.0 - wa - wb};
}

// The closed form for a differential area parallel to an a x b rectangle, at
// height c above one of its corners.
double rectangle_corner_form_factor(double a, double b, double c) {
    const double x = a / c, y = b / c;
    const double sx = std::sqrt(1 + x * x), sy = std::sqrt(1 + y * y);
    return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2 * std::numbers::pi);
}

// A regular `sides`-gon of circumradius r in the plane through c with unit
// normal m, wound so that its front faces along m.
std::vector<V> regular_polygon(const V& c, const V& m, double r, int sides) {
    const V u = glm::normalize(glm::cross(std::abs(m.x) < 0.9 ? V(1, 0, 0) : V(0, 1, 0), m));
    const V w = glm::cross(m, u);
    std::vector<V> q;
    for (int k = 0; k < sides; ++k) {
        const double phi = 2 * std::numbers::pi * k / sides;
        q.push_back(c + r * (std::cos(phi) * u + std::sin(phi) * w));
    }
    return q;
}

double polygon_ff(const V& p, const V& n, const std::vector<V>& q) {
    return polygon_form_factor(p, n, q.data(), int(q.size()));
}

} // namespace

// All 27 sign patterns of the three vertex heights, enumerated, on a tilted
// receiver frame: count and visibility from the pattern's counts of +, 0, -;
// every output point on or above the plane, inside the triangle, the kept
// vertices exact and the new ones on the plane; the area equal to the
// similar-triangle closed form; the winding kept; the form factor equal to a
// brute-force integral over the unclipped triangle.
TEST(DiskGeometry, ClipAllTwentySevenSignCases) {
    const Frame f;
    const double xs[3] = {0.3, 2.1, 0.7}, ys[3] = {-0.2, 0.4, 1.9}, mags[3] = {0.7, 1.3, 0.4};
    int cases = 0, visible_cases = 0, quads = 0;
    for (int code = 0; code < 27; ++code) {
        const int sign[3] = {code / 9 - 1, (code / 3) % 3 - 1, code % 3 - 1};
        std::array<double, 3> h{};
        V v[3];
        int above = 0, on = 0, below = 0;
        for (int i = 0; i < 3; ++i) {
            h[i] = sign[i] * mags[i];
            v[i] = f.at(xs[i], ys[i], h[i]);
            above += sign[i] > 0, on += sign[i] == 0, below += sign[i] < 0;
        }
        SCOPED_TRACE(testing::Message() << "signs " << sign[0] << " " << sign[1] << " " << sign[2]);
        ++cases;
        const ClippedQuad<double> r = clip_to_tangent_plane(f.p, f.n, v[0], v[1], v[2]);

        // The case table, from the counts alone.
        const int expected_count = above == 0 ? 0 : below == 0 ? 3 : above == 2 ? 4 : 3;
        ASSERT_EQ(r.count, expected_count);
        ASSERT_EQ(r.visible, above > 0);
        if (!r.visible) {
            for (const V& q : r.q) EXPECT_EQ(q, f.p); // all four equal
            EXPECT_EQ(clipped_triangle_form_factor(f.p, f.n, v[0], v[1], v[2]), 0.0);
            continue;
        }
        ++visible_cases;
        quads += r.count == 4;
        if (r.count == 3) {
            EXPECT_EQ(r.q[3], r.q[2]); // a triangle repeats its last point
        }

        // Kept vertices exactly, dropped ones absent, new points on the plane.
        for (int i = 0; i < 3; ++i) {
            bool found = false;
            for (int k = 0; k < r.count; ++k) found = found || r.q[k] == v[i];
            EXPECT_EQ(found, sign[i] >= 0) << "vertex " << i;
        }
        int new_points = 0;
        for (int k = 0; k < r.count; ++k) {
            const bool original = r.q[k] == v[0] || r.q[k] == v[1] || r.q[k] == v[2];
            const double hk = height(f, r.q[k]);
            EXPECT_GE(hk, -1e-12);
            if (!original) {
                ++new_points;
                EXPECT_NEAR(hk, 0.0, 1e-12) << "point " << k;
            }
            const glm::dvec3 w = barycentric(r.q[k], v[0], v[1], v[2]);
            for (int j = 0; j < 3; ++j) {
                EXPECT_GE(w[j], -1e-12);
                EXPECT_LE(w[j], 1 + 1e-12);
            }
        }
        // One new point per edge with strictly opposite signs: one for
        // (+, 0, -), two for (+, +, -) and (+, -, -).
        EXPECT_EQ(new_points, below == 0 ? 0 : above == 1 && below == 1 ? 1 : 2);

        // Area and winding.
        const V tri_front = glm::cross(v[1] - v[0], v[2] - v[0]);
        const V qa = vector_area(r.q, r.count);
        const double expected_area = visible_fraction(h) * tri_area(v[0], v[1], v[2]);
        EXPECT_NEAR(glm::length(qa), expected_area, 1e-12);
        EXPECT_GT(glm::dot(qa, tri_front), 0.0);
        EXPECT_GT(expected_area, 1e-3);

        // The form factor of the visible part against brute force over the
        // whole triangle with the below-plane part cut off point by point.
        const double ff = clipped_triangle_form_factor(f.p, f.n, v[0], v[1], v[2]);
        EXPECT_EQ(ff, polygon_form_factor(f.p, f.n, r.q, r.count));
        const double ref = integrate_form_factor(f.p, f.n, v[0], v[1], v[2]);
        EXPECT_NEAR(ff, ref, 1e-4 * std::abs(ref) + 1e-6);
    }
    EXPECT_EQ(cases, 27);
    EXPECT_EQ(visible_cases, 19); // 27 minus the 2^3 patterns with no vertex above
    EXPECT_EQ(quads, 3);          // two above, one below
}

// Hand-checked outputs of named cases (vertex order and the intersection
// points written out).
TEST(DiskGeometry, ClipNamedCases) {
    const V p(0, 0, 0), n(0, 0, 1);
    // v0, v1 above, v2 below (the chapter's listing): v0, v1, v1->v2, v2->v0.
    {
        const V v0(0, 0, 1), v1(2, 0, 3), v2(0, 2, -1);
        const auto r = clip_to_tangent_plane(p, n, v0, v1, v2);
        ASSERT_EQ(r.count, 4);
        EXPECT_EQ(r.q[0], v0);
        EXPECT_EQ(r.q[1], v1);
        EXPECT_NEAR(glm::distance(r.q[2], V(2 - 1.5, 1.5, 0)), 0.0, 1e-15); // t = 3/4 along v1->v2
        EXPECT_NEAR(glm::distance(r.q[3], V(0, 1, 0)), 0.0, 1e-15);         // t = 1/2 along v2->v0
    }
    // One above, one on, one below: above, on, and the point on v2->v0.
    {
        const V v0(0, 0, 2), v1(1, 0, 0), v2(0, 1, -2);
        const auto r = clip_to_tangent_plane(p, n, v0, v1, v2);
        ASSERT_EQ(r.count, 3);
        EXPECT_EQ(r.q[0], v0);
        EXPECT_EQ(r.q[1], v1);
        EXPECT_NEAR(glm::distance(r.q[2], V(0, 0.5, 0)), 0.0, 1e-15);
        EXPECT_EQ(r.q[3], r.q[2]);
    }
    // Two on the plane, one below: invisible (a segment has no area).
    {
        const auto r = clip_to_tangent_plane(p, n, V(1, 0, 0), V(0, 1, 0), V(0, 0, -1));
        EXPECT_FALSE(r.visible);
        EXPECT_EQ(r.count, 0);
    }
    // All three on the plane: invisible.
    EXPECT_FALSE(clip_to_tangent_plane(p, n, V(1, 0, 0), V(0, 1, 0), V(1, 1, 0)).visible);
}

// A vertex 1e-12 from the plane is on it: no sliver edge, no sliver triangle.
TEST(DiskGeometry, EpsilonSnapRemovesSlivers) {
    const V p(0, 0, 0), n(0, 0, 1);
    const V v0(0.5, 0.5, 1e-12), v1(1.5, 0.5, 1), v2(0.5, 1.5, -1);
    // Without the snap: a quad whose last edge is 1e-12 long.
    const auto raw = clip_to_tangent_plane(p, n, v0, v1, v2, 0.0);
    ASSERT_EQ(raw.count, 4);
    EXPECT_LT(glm::distance(raw.q[3], raw.q[0]), 1e-11);
    // With the chapter's epsilon: the triangle v0, v1, (v1->v2 on the plane).
    const auto snapped = clip_to_tangent_plane(p, n, v0, v1, v2);
    ASSERT_EQ(snapped.count, 3);
    EXPECT_EQ(snapped.q[0], v0);
    EXPECT_EQ(snapped.q[1], v1);
    EXPECT_NEAR(glm::distance(snapped.q[2], V(1.0, 1.0, 0)), 0.0, 1e-15);
    EXPECT_EQ(snapped_plane_distance(p, n, v0, DiskAoSettings{}.clip_epsilon), 0.0);
    EXPECT_NEAR(clipped_triangle_form_factor(p, n, v0, v1, v2), polygon_form_factor(p, n, raw.q, 4), 1e-12);

    // One vertex 1e-12 above, the others below: a sliver triangle of area
    // ~1e-12 without the snap, invisible with it. Same from 1e-12 below.
    const V w1(1.5, 0.5, -1), w2(0.5, 1.5, -1);
    EXPECT_TRUE(clip_to_tangent_plane(p, n, v0, w1, w2, 0.0).visible);
    EXPECT_FALSE(clip_to_tangent_plane(p, n, v0, w1, w2).visible);
    EXPECT_EQ(clipped_triangle_form_factor(p, n, v0, w1, w2), 0.0);
    const V u0(0.5, 0.5, -1e-12), u1(1.5, 0.5, 1), u2(0.5, 1.5, 1);
    const auto r = clip_to_tangent_plane(p, n, u0, u1, u2);
    EXPECT_EQ(r.count, 3); // u0 is on the plane: the whole triangle, no cut
    EXPECT_EQ(r.q[0], u0);
}

// Zero-area and repeated-vertex triangles: finite, no area, no form factor.
TEST(DiskGeometry, DegenerateTriangles) {
    const Frame f;
    const V a = f.at(0.5, 0.2, 0.8), b = f.at(1.5, 0.9, -0.6);
    const V mid = 0.5 * (a + b);
    const std::array<std::array<V, 3>, 5> tris = {{
        {a, b, mid},                                                     // collinear, crossing the plane
        {a, mid, f.at(0.75, 0.395, 0.45)},                               // a sliver (2 % as wide as long), above
        {a, a, b},                                                       // repeated vertex
        {a, a, a},                                                       // a point
        {f.at(0.5, 0.2, 0.8), f.at(0.7, 0.2, 0.8), f.at(0.9, 0.2, 0.8)}, // collinear, above
    }};
    for (const auto& t : tris) {
        const auto r = clip_to_tangent_plane(f.p, f.n, t[0], t[1], t[2]);
        for (const V& q : r.q) EXPECT_TRUE(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z));
        EXPECT_NEAR(glm::length(vector_area(r.q, 4)),
                    tri_area(t[0], t[1], t[2]) * visible_fraction({height(f, t[0]), height(f, t[1]), height(f, t[2])}),
                    1e-6);
        const double ff = clipped_triangle_form_factor(f.p, f.n, t[0], t[1], t[2]);
        EXPECT_TRUE(std::isfinite(ff));
        // Zero area in exact arithmetic (all but the sliver):
        // no form factor, up to rounding.
        if (&t != &tris[1]) {
            EXPECT_NEAR(ff, 0.0, 1e-14);
        } else {
            EXPECT_GT(std::abs(ff), 1e-5);
        }
    }
    // Points at the receiver: every edge is degenerate.
    const V at_p[4] = {f.p, f.p, f.p, f.p};
    EXPECT_EQ(polygon_form_factor(f.p, f.n, at_p, 4), 0.0);
    // A vertex at p: finite (the one-sided limit, see the header), |F| <= 1.
    const double fv = polygon_form_factor(f.p, f.n, std::array<V, 3>{f.p, f.at(1, 0, 0.5), f.at(0, 1, 0.5)}.data(), 3);
    EXPECT_TRUE(std::isfinite(fv));
    EXPECT_LE(std::abs(fv), 1.0);
    // An edge whose line passes through p (p between its endpoints).
    const double fe =
        polygon_form_factor(f.p, f.n, std::array<V, 3>{f.at(-1, 0, 0), f.at(1, 0, 0), f.at(0, 1, 1)}.data(), 3);
    EXPECT_TRUE(std::isfinite(fe));
    // The zero normal and a zero-area disk.
    EXPECT_EQ(disk_form_factor(f.p, V(0.0), f.at(0, 0, 1), -f.n, 1.0), 0.0);
    EXPECT_EQ(disk_form_factor(f.p, f.n, f.p, -f.n, 1.0), 0.0); // the disk at p
    EXPECT_EQ(disk_form_factor(f.p, f.n, f.at(0, 0, 1), -f.n, 0.0), 0.0);
}

// A disk of radius R on the axis at height h: F = R^2 / (h^2 + R^2). A
// regular 256-gon lies between its inscribed disk (radius R cos(pi/256)) and
// its circumscribed one, and F grows with the region, so its form factor is
// bracketed exactly by the closed form at the two radii.
TEST(DiskGeometry, PolygonFormFactorOfDiskOnAxis) {
    const V p(0.4, -0.3, 1.0), n = glm::normalize(V(1, 2, 2));
    for (double h : {0.05, 0.3, 1.0, 4.0, 50.0}) {
        for (double R : {0.1, 1.0, 7.0}) {
            const int sides = 256;
            const auto q = regular_polygon(p + h * n, -n, R, sides); // front faces p
            const double F = polygon_ff(p, n, q);
            const double rin = R * std::cos(std::numbers::pi / sides);
            const double lo = rin * rin / (h * h + rin * rin), hi = R * R / (h * h + R * R);
            EXPECT_GE(F, lo - 1e-13) << h << " " << R;
            EXPECT_LE(F, hi + 1e-13) << h << " " << R;
            // The other winding (back towards p): the same magnitude, negative.
            const std::vector<V> back(q.rbegin(), q.rend());
            EXPECT_NEAR(polygon_ff(p, n, back), -F, 1e-13);
        }
    }
}

// A square of side 2a centred on the axis at height h: four a x a corner
// rectangles, F = (4/pi) X/sqrt(1+X^2) atan(X/sqrt(1+X^2)), X = a/h; and an
// a x b rectangle seen from above one corner (the corner formula itself).
TEST(DiskGeometry, PolygonFormFactorOfRectangles) {
    const Frame f;
    for (double a : {0.1, 0.5, 1.0, 3.0}) {
        for (double h : {0.2, 1.0, 2.5}) {
            const V q[4] = {f.at(-a, -a, h), f.at(-a, a, h), f.at(a, a, h), f.at(a, -a, h)}; // normal -n: faces p
            const double X = a / h, s = std::sqrt(1 + X * X);
            const double closed = 4 / std::numbers::pi * X / s * std::atan(X / s);
            EXPECT_NEAR(polygon_form_factor(f.p, f.n, q, 4), closed, 1e-14) << a << " " << h;
            EXPECT_NEAR(closed, 4 * rectangle_corner_form_factor(a, a, h), 1e-15);
        }
    }
    for (auto [a, b, c] : {std::array<double, 3>{1.0, 2.5, 0.7}, {0.3, 0.1, 2.0}, {4.0, 0.5, 0.5}}) {
        const V q[4] = {f.at(0, 0, c), f.at(0, b, c), f.at(a, b, c), f.at(a, 0, c)};
        EXPECT_NEAR(polygon_form_factor(f.p, f.n, q, 4), rectangle_corner_form_factor(a, b, c), 1e-14);
    }
    // A huge square just above p fills the hemisphere: F -> 1.
    const V big[4] = {f.at(-1e4, -1e4, 1e-3), f.at(-1e4, 1e4, 1e-3), f.at(1e4, 1e4, 1e-3), f.at(1e4, -1e4, 1e-3)};
    EXPECT_NEAR(polygon_form_factor(f.p, f.n, big, 4), 1.0, 1e-6);
}

// Wholly below the tangent plane: the unclipped contour sum is not 0 (it
// counts the part below negatively), the clipped form factor is.
TEST(DiskGeometry, PolygonBehindTheReceiverGivesZero) {
    const Frame f;
    const V v0 = f.at(-1, -1, -0.5), v1 = f.at(2, -1, -0.8), v2 = f.at(0, 2, -0.3);
    const V tri[3] = {v0, v1, v2};
    EXPECT_GT(std::abs(polygon_form_factor(f.p, f.n, tri, 3)), 0.05);
    EXPECT_EQ(clipped_triangle_form_factor(f.p, f.n, v0, v1, v2), 0.0);
    EXPECT_EQ(clipped_triangle_form_factor(f.p, f.n, v0, v2, v1), 0.0);
}

// Tilted triangles crossing the tangent plane: clip + contour form factor
// equals brute-force integration over the triangle with the part below the
// plane cut off point by point.
TEST(DiskGeometry, ClippedFormFactorMatchesNumericalIntegration) {
    const Frame f;
    const std::array<std::array<V, 3>, 4> tris = {{
        {f.at(0.5, -1.0, -0.7), f.at(1.8, 0.2, 1.2), f.at(-0.4, 1.5, 0.9)},
        {f.at(-2.0, 0.5, 2.0), f.at(2.0, 0.3, 2.0), f.at(0.1, 1.0, -1.5)},  // one below
        {f.at(-0.3, 0.4, 0.6), f.at(0.6, 0.5, -0.2), f.at(0.1, 1.2, -0.9)}, // one above
        {f.at(0.2, -0.6, 0.3), f.at(0.9, 0.7, -0.4), f.at(-0.8, 0.4, 0.05)},
    }};
    for (const auto& t : tris) {
        for (int wind = 0; wind < 2; ++wind) {
            const V a = t[0], b = wind ? t[2] : t[1], c = wind ? t[1] : t[2];
            const double ff = clipped_triangle_form_factor(f.p, f.n, a, b, c);
            const double ref = integrate_form_factor(f.p, f.n, a, b, c);
            EXPECT_GT(std::abs(ref), 0.01);
            EXPECT_NEAR(ff, ref, 1e-4 * std::abs(ref) + 1e-6);
        }
    }
}

// Additivity: a quad is the sum of its two triangles; a triangle crossing the
// plane, split in two along a median, clips to the sum of its halves'.
// Reciprocity: A1 F12 = A2 F21, with the parallel-plates closed form.
TEST(DiskGeometry, AdditivityAndReciprocity) {
    const Frame f;
    const V q[4] = {f.at(-0.5, -0.7, 1.1), f.at(-0.8, 0.9, 1.4), f.at(1.2, 1.1, 0.9), f.at(1.0, -0.6, 0.7)};
    const V t1[3] = {q[0], q[1], q[2]}, t2[3] = {q[0], q[2], q[3]};
    const double whole = polygon_form_factor(f.p, f.n, q, 4);
    EXPECT_GT(std::abs(whole), 0.05);
    EXPECT_NEAR(whole, polygon_form_factor(f.p, f.n, t1, 3) + polygon_form_factor(f.p, f.n, t2, 3), 1e-14);

    const V a = f.at(0.5, -1.0, -0.7), b = f.at(1.8, 0.2, 1.2), c = f.at(-0.4, 1.5, 0.9);
    const V m = 0.5 * (b + c);
    EXPECT_NEAR(clipped_triangle_form_factor(f.p, f.n, a, b, c),
                clipped_triangle_form_factor(f.p, f.n, a, b, m) + clipped_triangle_form_factor(f.p, f.n, a, m, c),
                1e-14);

    // Reciprocity, integrating the receiver's point form factor over its own
    // area (midpoint rule, 200 x 200).
    const auto integrate_over_square = [](const V& o, const V& e1, const V& e2, const V& normal, const V* target) {
        const int m = 200;
        double sum = 0;
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j) {
                const V x = o + ((i + 0.5) / m) * e1 + ((j + 0.5) / m) * e2;
                sum += polygon_form_factor(x, normal, target, 4);
            }
        return sum * glm::length(glm::cross(e1, e2)) / (m * m);
    };
    // Two unit squares facing each other at distance 1: F = 0.19982 (closed
    // form for directly opposed rectangles, X = Y = 1).
    {
        const V lower[4] = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0)}; // front +z
        const V upper[4] = {V(0, 0, 1), V(0, 1, 1), V(1, 1, 1), V(1, 0, 1)}; // front -z
        const double X = 1, Y = 1;
        const double closed =
            2 / (std::numbers::pi * X * Y) *
            (0.5 * std::log((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)) +
             X * std::sqrt(1 + Y * Y) * std::atan(X / std::sqrt(1 + Y * Y)) +
             Y * std::sqrt(1 + X * X) * std::atan(Y / std::sqrt(1 + X * X)) - X * std::atan(X) - Y * std::atan(Y));
        const double f12 = integrate_over_square(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, 1), upper);
        const double f21 = integrate_over_square(V(0, 0, 1), V(1, 0, 0), V(0, 1, 0), V(0, 0, -1), lower);
        EXPECT_NEAR(closed, 0.19982, 1e-5);
        EXPECT_NEAR(f12, closed, 1e-5);
        EXPECT_NEAR(f21, closed, 1e-5);
    }
    // Perpendicular, not touching: a floor square and a wall square.
    {
        const V floor_sq[4] = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0)};             // front +z, area 1
        const V wall[4] = {V(1.2, 0, 0.2), V(1.2, 0, 1.7), V(1.2, 1, 1.7), V(1.2, 1, 0.2)}; // front -x, area 1.5
        const double a1f12 = integrate_over_square(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, 1), wall);
        const double a2f21 = integrate_over_square(V(1.2, 0, 0.2), V(0, 1, 0), V(0, 0, 1.5), V(-1, 0, 0), floor_sq);
        EXPECT_GT(a1f12, 0.05);
        EXPECT_NEAR(a1f12, a2f21, 1e-5 * a1f12);
    }
}

// Bunnell's disk: exact on the axis; off the axis it tends to the exact form
// factor of the disk (a 256-gon with the same area) as d/R grows, with a
// relative error O((R/d)^2); back-facing or below the plane gives 0.
TEST(DiskGeometry, DiskFormFactor) {
    const Frame f;
    for (double h : {0.1, 1.0, 10.0})
        for (double R : {0.5, 2.0}) {
            const double F = disk_form_factor(f.p, f.n, f.at(0, 0, h), -f.n, std::numbers::pi * R * R);
            EXPECT_NEAR(F, R * R / (h * h + R * R), 1e-15);
        }

    const V dir = glm::normalize(f.at(0.6, -0.3, 1.0) - f.p); // off the normal
    const V m = glm::normalize(-dir + 0.5 * f.t - 0.2 * f.b); // tilted emitter
    const double R = 1.0;
    double last = 1e9;
    for (double d : {3.0, 10.0, 30.0, 100.0, 300.0}) {
        const V c = f.p + d * dir;
        const auto q = regular_polygon(c, m, R, 256);
        const double area = glm::length(vector_area(q.data(), int(q.size())));
        const double exact = polygon_ff(f.p, f.n, q);
        const double approx = disk_form_factor(f.p, f.n, c, m, area);
        const double err = std::abs(approx / exact - 1);
        EXPECT_LT(err, 1.5 * (R / d) * (R / d)) << d; // measured 0.88 (R/d)^2
        EXPECT_LT(err, last) << d;
        last = err;
    }
    EXPECT_LT(last, 1e-4);

    EXPECT_EQ(disk_form_factor(f.p, f.n, f.at(0, 0, 1), f.n, 1.0), 0.0);           // its back faces p
    EXPECT_EQ(disk_form_factor(f.p, f.n, f.at(0, 0, -1), f.n, 1.0), 0.0);          // below the plane
    EXPECT_NEAR(disk_form_factor(f.p, f.n, f.at(1, 0, 0), -f.t, 1.0), 0.0, 1e-15); // in the plane (cos_r = 0)
}

TEST(DiskGeometry, Attenuations) {
    EXPECT_EQ(distance_attenuation(0.0, 0.5), 1.0);
    EXPECT_DOUBLE_EQ(distance_attenuation(4.0, 0.5), 1.0 / 3.0);
    EXPECT_EQ(distance_attenuation(123.0), 1.0);     // default k = 0
    EXPECT_EQ(distance_attenuation(4.0, -1.0), 1.0); // k < 0 taken as 0

    EXPECT_DOUBLE_EQ(triangle_attenuation(0.25, 0.5), 0.5);
    EXPECT_DOUBLE_EQ(triangle_attenuation(0.25, 2.0), 0.0625);
    EXPECT_EQ(triangle_attenuation(0.6), 0.6); // default t = 1: Bunnell's modulation
    EXPECT_EQ(triangle_attenuation(0.0, 0.0), 1.0);
    EXPECT_EQ(triangle_attenuation(0.0, 2.0), 0.0);
    EXPECT_EQ(triangle_attenuation(1.5, 2.0), 1.0); // clamped to [0, 1]
    EXPECT_EQ(triangle_attenuation(-0.5, 2.0), 0.0);

    EXPECT_EQ(DiskAoSettings{}.clip_epsilon, 1e-6);
    // The chapter's 8, doubled by measurement against Embree (docs/ao.md, "Disk AO: hierarchy and CPU evaluation").
    EXPECT_EQ(DiskAoSettings{}.traversal_epsilon, 16.0);
    EXPECT_EQ(DiskAoSettings{}.min_scale + DiskAoSettings{}.max_scale, 1.0);
}

// Two elements that fill each other's hemisphere (F = 1): Bunnell's iteration
// acc' = 1 - F acc alternates 1, 0, 1, 0 and never converges. The blend of
// the last two passes is the same whichever pass came last:
// 0.7 * 0 + 0.3 * 1 = 0.3.
TEST(DiskGeometry, ConvergeBlendOnTwoCycle) {
    for (int passes : {2, 3, 4, 7}) {
        double prev = 1.0, acc = 1.0;
        for (int k = 0; k < passes; ++k) {
            prev = acc;
            acc = 1.0 - 1.0 * prev;
        }
        EXPECT_NE(acc, prev);
        EXPECT_DOUBLE_EQ(converge_blend(prev, acc), 0.3) << passes;
    }
    EXPECT_DOUBLE_EQ(converge_blend(0.2, 0.9), 0.7 * 0.2 + 0.3 * 0.9);
    EXPECT_EQ(converge_blend(0.2, 0.9), converge_blend(0.9, 0.2));
    EXPECT_EQ(converge_blend(0.45, 0.45), 0.45);               // a converged value is kept
    EXPECT_DOUBLE_EQ(converge_blend(0.2, 0.9, 1.0, 0.0), 0.2); // pure minimum
}

// The float instantiation (what the GLSL port computes) agrees with double.
TEST(DiskGeometry, FloatMatchesDouble) {
    const Frame f;
    const V v0 = f.at(0.5, -1.0, -0.7), v1 = f.at(1.8, 0.2, 1.2), v2 = f.at(-0.4, 1.5, 0.9);
    const glm::vec3 pf(f.p), nf(f.n);
    const auto rf = clip_to_tangent_plane(pf, nf, glm::vec3(v0), glm::vec3(v1), glm::vec3(v2));
    const auto rd = clip_to_tangent_plane(f.p, f.n, v0, v1, v2);
    ASSERT_EQ(rf.count, rd.count);
    for (int k = 0; k < 4; ++k) EXPECT_LT(glm::distance(V(rf.q[k]), rd.q[k]), 1e-5);
    EXPECT_NEAR(clipped_triangle_form_factor(pf, nf, glm::vec3(v0), glm::vec3(v1), glm::vec3(v2)),
                clipped_triangle_form_factor(f.p, f.n, v0, v1, v2), 1e-5);
    EXPECT_NEAR(disk_form_factor(pf, nf, glm::vec3(f.at(0, 0, 1)), glm::vec3(-f.n), 3.14159265f), 0.5, 1e-6);
    EXPECT_FLOAT_EQ(converge_blend(0.0f, 1.0f), 0.3f);
}
