// Exact closest points (renderer/surface/closest.hpp): triangle pairs in the
// configurations that decide the minimum (face to corner, skew edges,
// parallel faces, crossing, degenerate triangles), the BVH's branch and bound
// against a brute-force double-precision minimum over every triangle pair
// on small random meshes and on touching and nested surfaces, and a closed
// form: two spheres whose poles face each other are d - r1 - r2 apart.
#include "renderer/surface/closest.hpp"

#include <cmath>
#include <random>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "io/error.hpp"
#include "tests/support/meshes.hpp"

using namespace iso;

namespace {

TriangleCorners tri(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) { return {a, b, c}; }

// Random triangles in a box: small, some degenerate (a repeated corner, or
// three collinear corners), as a soup.
Mesh random_soup(std::mt19937& rng, int n, glm::dvec3 origin, double size) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Mesh m;
    for (int i = 0; i < n; ++i) {
        const glm::dvec3 c = origin + size * glm::dvec3(u(rng), u(rng), u(rng));
        const auto jitter = [&] { return glm::dvec3(u(rng), u(rng), u(rng)) - 0.5; };
        glm::dvec3 p[3] = {c + jitter(), c + jitter(), c + jitter()};
        if (i % 11 == 3) p[2] = p[1];                       // a repeated corner
        if (i % 13 == 5) p[2] = p[0] + 0.5 * (p[1] - p[0]); // collinear (up to float rounding)
        const auto base = std::uint32_t(m.positions.size());
        for (const auto& q : p) m.positions.emplace_back(glm::vec3(q));
        m.triangles.push_back({base, base + 1, base + 2});
    }
    return m;
}

Mesh transformed(Mesh m, const glm::dmat4& x) {
    for (auto& p : m.positions) p = glm::vec3(x * glm::dvec4(glm::dvec3(p), 1.0));
    return m;
}

void expect_same_minimum(const Mesh& a, const Mesh& b) {
    const TriangleBvh ba(a), bb(b);
    const SurfaceDistance fast = surface_distance(ba, bb);
    const SurfaceDistance slow = surface_distance_brute_force(a, b);
    EXPECT_EQ(fast.pair.distance_mm, slow.pair.distance_mm) << "the same pair's distance, bit for bit";
    EXPECT_NEAR(glm::length(fast.pair.a - fast.pair.b), fast.pair.distance_mm, 1e-12);
    EXPECT_EQ(fast.touching, slow.touching);
    EXPECT_LE(fast.triangle_pairs, slow.triangle_pairs);
    // The points lie on the triangles named.
    const auto on = [](const TriangleBvh& t, std::uint32_t k, const glm::dvec3& p) {
        return point_triangle_distance(p, t.corners(k)).distance_mm;
    };
    EXPECT_LT(on(ba, fast.triangle_a, fast.pair.a), 1e-9);
    EXPECT_LT(on(bb, fast.triangle_b, fast.pair.b), 1e-9);
}

} // namespace

TEST(TriangleDistance, TheConfigurationsThatDecideTheMinimum) {
    const auto base = tri({0, 0, 0}, {10, 0, 0}, {0, 10, 0});
    // A corner above the face: the face's point below it.
    auto c = triangle_distance(base, tri({2, 2, 3}, {2, 2, 9}, {5, 5, 9}));
    EXPECT_DOUBLE_EQ(c.distance_mm, 3.0);
    EXPECT_EQ(c.a, glm::dvec3(2, 2, 0));
    EXPECT_EQ(c.b, glm::dvec3(2, 2, 3));
    // Skew edges: the closest points lie inside both edges, at no corner.
    c = triangle_distance(tri({0, 0, 0}, {10, 0, 0}, {5, -10, 0}), tri({5, -5, 4}, {5, 5, 4}, {5, 0, 20}));
    EXPECT_NEAR(c.distance_mm, 4.0, 1e-12);
    EXPECT_NEAR(glm::length(c.a - glm::dvec3(5, 0, 0)), 0.0, 1e-12);
    // Parallel faces 2 mm apart, overlapping: 2 mm.
    c = triangle_distance(base, tri({1, 1, 2}, {4, 1, 2}, {1, 4, 2}));
    EXPECT_DOUBLE_EQ(c.distance_mm, 2.0);
    // Crossing triangles: 0, at a point of both.
    c = triangle_distance(base, tri({2, 2, -3}, {2, 2, 3}, {2, 8, 3}));
    EXPECT_EQ(c.distance_mm, 0.0);
    EXPECT_NEAR(c.a.z, 0.0, 1e-12);
    // A degenerate triangle (a segment) across the face: 0; above it: its height.
    c = triangle_distance(base, tri({1, 1, -1}, {1, 1, 1}, {1, 1, 0.5}));
    EXPECT_EQ(c.distance_mm, 0.0);
    c = triangle_distance(tri({1, 1, 5}, {3, 1, 5}, {2, 1, 5}), base);
    EXPECT_DOUBLE_EQ(c.distance_mm, 5.0);
    // A point: its own triangle of one point.
    c = triangle_distance(tri({20, 0, 0}, {20, 0, 0}, {20, 0, 0}), base);
    EXPECT_DOUBLE_EQ(c.distance_mm, 10.0);
    EXPECT_EQ(c.b, glm::dvec3(10, 0, 0));
}

TEST(SurfaceDistance, TheHierarchyFindsTheBruteForceMinimumOnRandomSoups) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 40; ++trial) {
        SCOPED_TRACE("trial " + std::to_string(trial));
        const int na = 1 + trial * 7 % 90, nb = 1 + trial * 13 % 70;
        // Apart, interleaved, and one inside the other's box.
        const double shift = trial % 3 == 0 ? 12.0 : trial % 3 == 1 ? 3.0 : 0.0;
        const Mesh a = random_soup(rng, na, {0, 0, 0}, 8.0);
        const Mesh b = random_soup(rng, nb, {shift, 0.5 * shift, 0}, 6.0);
        expect_same_minimum(a, b);
    }
}

TEST(SurfaceDistance, NestedAndTouchingSurfacesAndTwoSpheres) {
    // A ball inside a larger one, off centre, rotated: the gap is found between faces.
    const Mesh outer = test::sphere_mesh({0, 0, 0}, 9.0, 1.0);
    const Mesh inner = transformed(test::sphere_mesh({0, 0, 0}, 4.0, 1.0),
                                   glm::rotate(glm::translate(glm::dmat4(1.0), {2.1, -1.3, 0.7}), 0.4, {1, 2, 3}));
    expect_same_minimum(outer, inner);
    // Crossing spheres: 0.
    const Mesh crossing = test::uv_sphere({6, 0, 0}, 5.0, 12, 24);
    expect_same_minimum(test::uv_sphere({0, 0, 0}, 5.0, 12, 24), crossing);
    EXPECT_TRUE(surface_distance(TriangleBvh(outer), TriangleBvh(crossing)).touching);
    // Two UV spheres whose poles face each other on the z axis: the polytopes
    // lie inside their spheres and the poles are on them, so the distance is
    // exactly d - r1 - r2 (10 mm), between the poles.
    const Mesh s1 = test::uv_sphere({0, 0, 0}, 10.0, 40, 80), s2 = test::uv_sphere({0, 0, 35}, 15.0, 40, 80);
    const SurfaceDistance d = surface_distance(TriangleBvh(s1), TriangleBvh(s2));
    EXPECT_NEAR(d.pair.distance_mm, 10.0, 1e-12);
    EXPECT_NEAR(glm::length(d.pair.a - glm::dvec3(0, 0, 10)), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(d.pair.b - glm::dvec3(0, 0, 20)), 0.0, 1e-9);
    EXPECT_LT(d.triangle_pairs, 0.01 * double(s1.triangles.size()) * double(s2.triangles.size()))
        << "the boxes prune almost every pair";
    // Along an oblique axis the closest points are inside faces: between the
    // true spheres' gap and that plus both spheres' sagitta (the chord
    // error of a 40 x 80 tessellation: r (1 - cos(pi / 40)) at most).
    const glm::dvec3 dir = glm::normalize(glm::dvec3(1, 2, 2));
    const Mesh s3 = test::uv_sphere(40.0 * dir, 15.0, 40, 80);
    const double gap = 40.0 - 25.0, sag = 25.0 * (1 - std::cos(3.14159265358979 / 40));
    const SurfaceDistance o = surface_distance(TriangleBvh(s1), TriangleBvh(s3));
    EXPECT_GE(o.pair.distance_mm, gap - 1e-9);
    EXPECT_LE(o.pair.distance_mm, gap + sag);
}

TEST(SurfaceDistance, NearestPointAndOneComponentsTriangles) {
    const Mesh s = test::uv_sphere({0, 0, 0}, 10.0, 20, 40);
    const TriangleBvh bvh(s);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-20, 20);
    for (int i = 0; i < 50; ++i) {
        const glm::dvec3 p(u(rng), u(rng), u(rng));
        const NearestPoint n = nearest_point(bvh, p);
        double best = 1e300;
        for (std::uint32_t t = 0; t < s.triangles.size(); ++t)
            best = std::min(best, point_triangle_distance(p, bvh.corners(t)).distance_mm);
        EXPECT_EQ(n.distance_mm, best);
        EXPECT_NEAR(glm::length(n.point - p), n.distance_mm, 1e-12);
    }
    // A hierarchy over some triangles only measures those.
    const TriangleBvh north(s, {0, 1, 2});
    EXPECT_EQ(north.size(), 3u);
    EXPECT_NEAR(nearest_point(north, {0, 0, 30}).distance_mm, 20.0, 1e-9);
}

TEST(SurfaceDistance, BadSurfacesAreRefusedWithTheReason) {
    Mesh empty;
    EXPECT_THROW(TriangleBvh{empty}, Error);
    Mesh nan = test::uv_sphere({0, 0, 0}, 1.0, 4, 8);
    nan.positions[3].x = std::nanf("");
    try {
        TriangleBvh b(nan);
        FAIL() << "a NaN vertex was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();
    }
    const Mesh s = test::uv_sphere({0, 0, 0}, 1.0, 4, 8);
    EXPECT_THROW(TriangleBvh(s, {0, 999}), Error);
    EXPECT_THROW(nearest_point(TriangleBvh(s), {std::nan(""), 0, 0}), Error);
}
