// Picking on a real GL context (docs/picking.md): the lists the frame's own
// geometry passes build for the pick region, read back exactly, against a
// CPU ray cast of the same meshes (double precision, every hit along the
// pixel's ray): count, order, object and triangle; a rectangle lists every
// triangle inside it; an empty region, a background pixel, a region across
// the image border; a pick with AO and transparency on lists the same.
#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "renderer/gpu/renderer.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/scenes.hpp"

using namespace iso;
using namespace iso::test;
using Pick = test::GlTest;

namespace {

struct CpuHit {
    double t;
    std::uint32_t object, triangle;
    double edge; // smallest barycentric: near 0, the ray grazes an edge
};

// Every crossing of the ray with the meshes (object ids 1-based, in order),
// sorted as the pick sorts: nearest first, ties by object then triangle.
std::vector<CpuHit> ray_cast(const std::vector<const Mesh*>& meshes, const Ray& ray, double near_t) {
    std::vector<CpuHit> hits;
    for (std::size_t o = 0; o < meshes.size(); ++o)
        for (std::size_t k = 0; k < meshes[o]->triangles.size(); ++k) {
            const auto& tri = meshes[o]->triangles[k];
            const glm::dvec3 a(meshes[o]->positions[tri[0]]), b(meshes[o]->positions[tri[1]]),
                c(meshes[o]->positions[tri[2]]);
            const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(ray.dir, e2);
            const double det = glm::dot(e1, p);
            if (std::abs(det) < 1e-300) continue;
            const glm::dvec3 s = ray.origin - a;
            const double u = glm::dot(s, p) / det;
            const glm::dvec3 q = glm::cross(s, e1);
            const double v = glm::dot(ray.dir, q) / det, t = glm::dot(e2, q) / det;
            if (u < 0 || v < 0 || u + v > 1 || t < near_t) continue;
            hits.push_back({t, std::uint32_t(o + 1), std::uint32_t(k), std::min({u, v, 1 - u - v})});
        }
    std::sort(hits.begin(), hits.end(), [](const CpuHit& x, const CpuHit& y) {
        return std::tie(x.t, x.object, x.triangle) < std::tie(y.t, y.object, y.triangle);
    });
    return hits;
}

struct Scene {
    std::vector<Mesh> meshes;
    std::vector<float> opacity;
};

RenderResult pick(const Scene& s, const Camera& cam, int size, PickRegion region, bool ao = false) {
    Renderer ren;
    for (std::size_t i = 0; i < s.meshes.size(); ++i) {
        SceneObject o;
        o.opacity = s.opacity[i];
        ren.add(s.meshes[i], o);
    }
    RenderOptions o;
    o.width = o.height = size;
    o.pick = region;
    o.look.ao = ao ? AoMethod::Cone : AoMethod::Off;
    return ren.render(cam, o);
}

Scene nested_shells() {
    Scene s;
    for (double r : {8.0, 14.0, 20.0}) {
        s.meshes.push_back(sphere_mesh(glm::dvec3(0), r, 0.9));
        s.opacity.push_back(0.3f);
    }
    return s;
}

} // namespace

TEST_F(Pick, ListsOverNestedShellsEqualTheCpuRayCast) {
    const Scene s = nested_shells();
    const Camera cam = anterior(box(20));
    const int size = 64;
    const PickRegion region{27, 30, 6, 5};
    const auto r = pick(s, cam, size, region);
    ASSERT_EQ(r.pick.region.width, 6);
    ASSERT_EQ(r.pick.pixels.size(), 30u);
    EXPECT_LE(r.pick.offered, r.pick.capacity);
    std::vector<const Mesh*> meshes;
    for (const auto& m : s.meshes) meshes.push_back(&m);
    int compared = 0;
    for (int y = 0; y < region.height; ++y)
        for (int x = 0; x < region.width; ++x) {
            const Ray ray = cam.pixel_ray(region.x + x + 0.5, region.y + y + 0.5, size, size);
            const auto cpu = ray_cast(meshes, ray, 0.0);
            const auto& gpu = r.pick.pixels[std::size_t(y * region.width + x)];
            // A ray within the rasterizer's snapping (1/256 px on llvmpipe, a
            // few thousandths of these 1.4-pixel triangles) of an edge may go to
            // either neighbour.
            if (std::any_of(cpu.begin(), cpu.end(), [](const CpuHit& h) { return h.edge < 0.01; })) continue;
            ++compared;
            SCOPED_TRACE("pixel " + std::to_string(region.x + x) + "," + std::to_string(region.y + y));
            ASSERT_EQ(gpu.size(), cpu.size());
            EXPECT_EQ(gpu.size(), 6u) << "three closed shells: six crossings";
            double t = 1.0;
            for (std::size_t i = 0; i < cpu.size(); ++i) {
                EXPECT_EQ(gpu[i].object, cpu[i].object) << i;
                EXPECT_EQ(gpu[i].primitive, cpu[i].triangle) << i;
                EXPECT_FLOAT_EQ(gpu[i].alpha, 0.3f);
                EXPECT_NEAR(gpu[i].transmittance, t, 1e-6) << "front to back";
                t *= 0.7;
                if (i > 0) {
                    EXPECT_LE(gpu[i].depth, gpu[i - 1].depth) << "reversed Z: nearest first";
                }
            }
        }
    EXPECT_GE(compared, 20);
}

TEST_F(Pick, ListsEndAtTheFirstOpaqueLayerAndTranslucentOnesAreOnlyInFront) {
    // A translucent plate in front of two opaque plates.
    Scene s;
    s.meshes = {plate(-5, 10), plate(0, 10), plate(5, 10)};
    s.opacity = {0.4f, 1.0f, 1.0f};
    const auto r = pick(s, anterior(box(10)), 32, {16, 16, 1, 1});
    ASSERT_EQ(r.pick.pixels.size(), 1u);
    const auto& l = r.pick.pixels[0];
    ASSERT_EQ(l.size(), 2u) << "the hidden opaque layer is not: the list ends at the first opaque one";
    EXPECT_EQ(l[0].object, 1u);
    EXPECT_FLOAT_EQ(l[0].alpha, 0.4f);
    EXPECT_EQ(l[1].object, 2u);
    EXPECT_FLOAT_EQ(l[1].transmittance, 0.6f);
    // Drawn far to near (each one passing the depth test in turn), the same list.
    Scene reversed{{s.meshes[2], s.meshes[1], s.meshes[0]}, {1.0f, 1.0f, 0.4f}};
    const auto rev = pick(reversed, anterior(box(10)), 32, {16, 16, 1, 1});
    ASSERT_EQ(rev.pick.pixels[0].size(), 2u);
    EXPECT_EQ(rev.pick.pixels[0][0].object, 3u);
    EXPECT_EQ(rev.pick.pixels[0][1].object, 2u);
    // A translucent plate behind the opaque one is not (the list pass tests against the opaque depth).
    s.opacity = {1.0f, 1.0f, 0.4f};
    const auto behind = pick(s, anterior(box(10)), 32, {16, 16, 1, 1});
    ASSERT_EQ(behind.pick.pixels[0].size(), 1u);
    EXPECT_EQ(behind.pick.pixels[0][0].object, 1u);
}

TEST_F(Pick, ARectangleListsEveryTriangleInside) {
    // A 6 x 6 grid of quads on a plate, all inside the rectangle.
    Mesh grid;
    const int n = 6;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) grid.positions.push_back(glm::vec3(-6.0f + 2.0f * i, 0.0f, -6.0f + 2.0f * j));
    grid.normals.assign(grid.positions.size(), glm::vec3(0, -1, 0));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = std::uint32_t(j * (n + 1) + i);
            grid.triangles.push_back({a, a + 1, a + std::uint32_t(n) + 2});
            grid.triangles.push_back({a, a + std::uint32_t(n) + 2, a + std::uint32_t(n) + 1});
        }
    Scene s{{grid}, {1.0f}};
    const auto r = pick(s, anterior(box(10)), 64, {0, 0, 64, 64});
    std::set<std::uint32_t> seen;
    std::size_t background = 0;
    for (const auto& px : r.pick.pixels) {
        background += px.empty();
        for (const auto& f : px) seen.insert(f.primitive);
    }
    EXPECT_EQ(seen.size(), grid.triangles.size());
    EXPECT_GT(background, 0u) << "the plate does not fill the image";
}

TEST_F(Pick, EmptyRegionBackgroundAndTheImageBorder) {
    Scene s{{plate(0, 5)}, {1.0f}};
    const Camera cam = anterior(box(10));
    // Empty: nothing is listed and no pick pass runs.
    auto r = pick(s, cam, 32, {10, 10, 0, 3});
    EXPECT_TRUE(r.pick.pixels.empty());
    for (const auto& p : r.stats.passes) EXPECT_TRUE(p.name.find("pick") == std::string::npos) << p.name;
    // Background pixel: an empty list.
    r = pick(s, cam, 32, {0, 0, 1, 1});
    ASSERT_EQ(r.pick.pixels.size(), 1u);
    EXPECT_TRUE(r.pick.pixels[0].empty());
    // Across the border: clipped to the image.
    r = pick(s, cam, 32, {30, -2, 5, 4});
    EXPECT_EQ(r.pick.region.x, 30);
    EXPECT_EQ(r.pick.region.y, 0);
    EXPECT_EQ(r.pick.region.width, 2);
    EXPECT_EQ(r.pick.region.height, 2);
    EXPECT_EQ(r.pick.pixels.size(), 4u);
    // The plate's centre, through the pixel at the image's centre.
    r = pick(s, cam, 32, {16, 16, 1, 1});
    ASSERT_EQ(r.pick.pixels[0].size(), 1u);
}

TEST_F(Pick, WithAoAndTransparencyOnTheListsAreTheSame) {
    Scene s = nested_shells();
    s.meshes.push_back(sphere_mesh(glm::dvec3(0), 4.0, 0.5));
    s.opacity.push_back(1.0f); // an opaque core
    const Camera cam = anterior(box(20));
    const PickRegion region{29, 31, 3, 3};
    const auto plain = pick(s, cam, 64, region), lit = pick(s, cam, 64, region, true);
    bool traced = false;
    for (const auto& p : lit.stats.passes) traced |= p.name == "oit_ao";
    EXPECT_TRUE(traced) << "AO ran, translucent AO included";
    ASSERT_EQ(plain.pick.pixels.size(), lit.pick.pixels.size());
    for (std::size_t i = 0; i < plain.pick.pixels.size(); ++i) {
        ASSERT_EQ(plain.pick.pixels[i].size(), lit.pick.pixels[i].size());
        EXPECT_GE(plain.pick.pixels[i].size(), 4u) << "three shells' front halves and the core";
        for (std::size_t k = 0; k < plain.pick.pixels[i].size(); ++k) {
            EXPECT_EQ(plain.pick.pixels[i][k].object, lit.pick.pixels[i][k].object);
            EXPECT_EQ(plain.pick.pixels[i][k].primitive, lit.pick.pixels[i][k].primitive);
        }
    }
}
