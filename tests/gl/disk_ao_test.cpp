// Disk AO on the GPU (docs/ao.md, "Disk AO on the GPU").
//
// Kernels: shaders/ao/disk_geometry.glsl run in a compute shader
// (shaders/ao/disk_geometry_check.comp) on a few hundred random and special
// inputs (all 27 sign cases of a triangle against the tangent plane, the
// epsilon snap, degenerate triangles, disks behind or below the receiver,
// the attenuations' edge cases) and compared with the C++ float templates of
// renderer/ao/disk_geometry.cpp.
#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <cstdint>
#include <random>
#include <sstream>
#include <vector>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "pass_harness.hpp"
#include "renderer/ao/disk_geometry.hpp"

using namespace iso;
using DiskAo = test::GlTest;

namespace {

using V = glm::vec3;

// One kernel test case: the 8 vec4s disk_geometry_check.comp reads.
struct KernelCase {
    V p{0.0f}, n{0, 0, 1}, v0{0.0f}, v1{0.0f}, v2{0.0f};
    float eps = 1e-6f;
    V c{0.0f}, m{0, 0, -1};
    float area = 1.0f, k = 0.0f, t = 1.0f, e = 1.0f, d2 = 0.0f;
    float o0 = 0.0f, o1 = 0.0f, min_scale = 0.7f, max_scale = 0.3f;
    std::string what;

    void pack(std::vector<glm::vec4>& out) const {
        out.insert(out.end(), {glm::vec4(p, eps), glm::vec4(n, area), glm::vec4(v0, k), glm::vec4(v1, t), glm::vec4(v2, e),
                               glm::vec4(c, d2), glm::vec4(m, o0), glm::vec4(o1, min_scale, max_scale, 0.0f)});
    }
};

std::vector<glm::vec4> run_kernels(const std::vector<KernelCase>& cases) {
    std::vector<glm::vec4> in;
    for (const auto& c : cases) c.pack(in);
    test::ComputePass pass({"ao/disk_geometry_check.comp"});
    pass.storage<glm::vec4>(0, in).storage<glm::vec4>(1, std::vector<glm::vec4>(in.size(), glm::vec4(-7.0f)));
    pass.set("case_count", int(cases.size()));
    pass.dispatch(GLuint(cases.size() + 63) / 64);
    return pass.read<glm::vec4>(1);
}

// The cases. Axis-aligned receivers make the signed distances exact in
// float, so the sign cases are decided the same way on both sides.
std::vector<KernelCase> kernel_cases() {
    std::vector<KernelCase> cases;
    // All 27 sign patterns (each vertex below, on, above the plane z = 0),
    // a triangle whose front faces up, then the same with the other winding.
    for (int winding = 0; winding < 2; ++winding)
        for (int code = 0; code < 27; ++code) {
            KernelCase k;
            const float z[3] = {float(code % 3 - 1), float(code / 3 % 3 - 1), float(code / 9 - 1)};
            const V a(1.0f, 0.2f, 0.5f * z[0]), b(-0.5f, 1.1f, 0.7f * z[1]), c(-0.4f, -1.3f, 1.3f * z[2]);
            k.v0 = a;
            k.v1 = winding ? c : b;
            k.v2 = winding ? b : c;
            k.what = "sign case " + std::to_string(code) + " winding " + std::to_string(winding);
            cases.push_back(k);
        }
    // The snap: a vertex within epsilon above or below the plane is on it.
    for (float h : {1e-7f, -1e-7f, 5e-7f, -5e-7f, 1e-12f}) {
        KernelCase k;
        k.v0 = V(1.0f, 0.0f, h);
        k.v1 = V(0.0f, 1.0f, 1.0f);
        k.v2 = V(-1.0f, -1.0f, -1.0f);
        k.what = "snap " + std::to_string(h);
        cases.push_back(k);
    }
    // A wide epsilon snaps a whole vertex.
    {
        KernelCase k;
        k.eps = 0.25f;
        k.v0 = V(1.0f, 0.0f, 0.2f);
        k.v1 = V(0.0f, 1.0f, 1.0f);
        k.v2 = V(-1.0f, -1.0f, -0.2f);
        k.what = "eps 0.25";
        cases.push_back(k);
    }
    // Degenerate triangles: collinear, repeated vertices, a vertex at p, an
    // edge through p, all three at p, a triangle in the plane.
    const std::vector<std::array<V, 3>> degenerate = {
        {V(0, 0, 1), V(1, 1, 2), V(2, 2, 3)},    {V(1, 0, 1), V(1, 0, 1), V(0, 1, 1)},  {V(1, 0, 1), V(1, 0, 1), V(1, 0, 1)},
        {V(0, 0, 0), V(1, 0, 1), V(0, 1, 1)},    {V(-1, 0, 0), V(1, 0, 0), V(0, 1, 1)}, {V(0, 0, 0), V(0, 0, 0), V(0, 0, 0)},
        {V(1, 0, 0), V(0, 1, 0), V(-1, -1, 0)},  {V(0, 0, 2), V(0, 0, 1), V(1, 1, 1)},
    };
    for (std::size_t i = 0; i < degenerate.size(); ++i) {
        KernelCase k;
        k.v0 = degenerate[i][0];
        k.v1 = degenerate[i][1];
        k.v2 = degenerate[i][2];
        k.what = "degenerate " + std::to_string(i);
        cases.push_back(k);
    }
    // Disk and attenuation edge cases.
    auto special = [&](const char* what, auto&& set) {
        KernelCase k;
        k.v0 = V(1, 0, 1);
        k.v1 = V(0, 1, 1);
        k.v2 = V(-1, -1, 1);
        k.what = what;
        set(k);
        cases.push_back(k);
    };
    special("disk at p", [](KernelCase& k) { k.c = k.p; });
    special("disk on the axis", [](KernelCase& k) { k.c = V(0, 0, 2); k.area = 3.0f; });
    special("disk back-facing", [](KernelCase& k) { k.c = V(0, 0, 2); k.m = V(0, 0, 1); });
    special("disk below", [](KernelCase& k) { k.c = V(0.5f, 0, -2); k.m = V(0, 0, 1); });
    special("disk zero area", [](KernelCase& k) { k.c = V(0, 1, 2); k.area = 0.0f; });
    special("disk negative area", [](KernelCase& k) { k.c = V(0, 1, 2); k.area = -1.0f; });
    special("e = 0, t = 1", [](KernelCase& k) { k.e = 0.0f; });
    special("e = 0, t = 0", [](KernelCase& k) { k.e = 0.0f; k.t = 0.0f; });
    special("e = 0.4, t = 2.5", [](KernelCase& k) { k.e = 0.4f; k.t = 2.5f; });
    special("e = 1.5 clamped", [](KernelCase& k) { k.e = 1.5f; k.t = 3.0f; });
    special("e = -1 clamped", [](KernelCase& k) { k.e = -1.0f; k.t = 3.0f; });
    special("t negative", [](KernelCase& k) { k.e = 0.5f; k.t = -2.0f; });
    special("k = 0.5, d2 = 3", [](KernelCase& k) { k.k = 0.5f; k.d2 = 3.0f; });
    special("k negative", [](KernelCase& k) { k.k = -1.0f; k.d2 = 3.0f; });
    special("blend", [](KernelCase& k) { k.o0 = 0.2f; k.o1 = 0.9f; });
    special("blend 0.5 / 0.5", [](KernelCase& k) { k.o0 = 0.9f; k.o1 = 0.1f; k.min_scale = 0.5f; k.max_scale = 0.5f; });

    // Random receivers (tilted, off the origin) and triangles around them.
    std::mt19937 rng(15);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.0f, 1.0f);
    auto unit = [&] {
        for (;;) {
            const V v(u(rng), u(rng), u(rng));
            const float l = glm::length(v);
            if (l > 0.1f && l <= 1.0f) return v / l;
        }
    };
    for (int i = 0; cases.size() < 400; ++i) {
        KernelCase k;
        k.p = V(u(rng), u(rng), u(rng)) * 20.0f;
        k.n = unit();
        const float scale = i % 3 == 0 ? 0.2f : (i % 3 == 1 ? 1.0f : 5.0f);
        k.v0 = k.p + V(u(rng), u(rng), u(rng)) * 2.0f * scale;
        k.v1 = k.p + V(u(rng), u(rng), u(rng)) * 2.0f * scale;
        k.v2 = k.p + V(u(rng), u(rng), u(rng)) * 2.0f * scale;
        // Keep the sign decisions unambiguous: a vertex whose height is near
        // the snap band could fall either side after one rounding (a fused
        // multiply-add on one side only), which would change the case, not
        // test the port.
        bool ambiguous = false;
        for (const V& v : {k.v0, k.v1, k.v2}) {
            const double s = glm::dot(glm::dvec3(k.n), glm::dvec3(v) - glm::dvec3(k.p));
            ambiguous |= std::abs(s) < 1e-3 * scale;
        }
        if (ambiguous) continue;
        k.c = k.p + V(u(rng), u(rng), u(rng)) * 3.0f * scale;
        k.m = unit();
        k.area = pos(rng) * scale * scale;
        k.k = pos(rng);
        k.d2 = pos(rng) * 10.0f;
        k.t = pos(rng) * 3.0f;
        k.e = pos(rng);
        k.o0 = pos(rng);
        k.o1 = pos(rng);
        k.what = "random " + std::to_string(i);
        cases.push_back(k);
    }
    return cases;
}

} // namespace

// Tolerances: both sides evaluate the same float operations in the same
// order, but the GPU may fuse multiply-adds and llvmpipe's atan, sqrt and
// pow are approximations of a few ulp. Points (coordinates up to ~30 mm) are
// held to 4e-6 relative to their size + 1e-6; form factors (|F| <= 1) and
// the other terms to 2e-6 absolute + 1e-5 relative; clip counts exactly.
TEST_F(DiskAo, GlslKernelsMatchTheCppFloatTemplates) {
    const auto cases = kernel_cases();
    ASSERT_GE(cases.size(), 300u);
    const auto out = run_kernels(cases);
    ASSERT_EQ(out.size(), cases.size() * 8);
    auto near = [](float gpu, float cpu) { return std::abs(gpu - cpu) <= 2e-6f + 1e-5f * std::abs(cpu); };
    double worst_ff = 0, worst_point = 0;
    int quads = 0, triangles = 0, invisible = 0;
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const KernelCase& k = cases[i];
        const glm::vec4* o = &out[8 * i];
        SCOPED_TRACE(k.what);
        const ClippedQuad<float> cq = clip_to_tangent_plane<float>(k.p, k.n, k.v0, k.v1, k.v2, k.eps);
        ASSERT_EQ(int(o[0].w), cq.count);
        (cq.count == 4 ? quads : cq.count == 3 ? triangles : invisible)++;
        for (int j = 0; j < 4; ++j) {
            const float scale = std::max({glm::length(k.p), glm::length(k.v0), glm::length(k.v1), glm::length(k.v2), 1.0f});
            const float err = glm::length(glm::vec3(o[j]) - cq.q[j]);
            worst_point = std::max(worst_point, double(err / scale));
            EXPECT_LE(err, 1e-6f + 4e-6f * scale) << "point " << j;
        }
        const float ff_quad = polygon_form_factor<float>(k.p, k.n, cq.q, 4);
        const float ff_clip = clipped_triangle_form_factor<float>(k.p, k.n, k.v0, k.v1, k.v2, k.eps);
        const float ff_disk = disk_form_factor<float>(k.p, k.n, k.c, k.m, k.area);
        const V tri[4] = {k.v0, k.v1, k.v2, k.v2};
        const float ff_tri = polygon_form_factor<float>(k.p, k.n, tri, 3);
        const std::pair<float, float> pairs[] = {
            {o[4].x, ff_quad},
            {o[4].y, ff_clip},
            {o[4].z, ff_disk},
            {o[4].w, distance_attenuation<float>(k.d2, k.k)},
            {o[5].x, triangle_attenuation<float>(k.e, k.t)},
            {o[5].y, converge_blend<float>(k.o0, k.o1, k.min_scale, k.max_scale)},
            {o[5].z, snapped_plane_distance<float>(k.p, k.n, k.v0, k.eps)},
            {o[5].w, snapped_plane_distance<float>(k.p, k.n, k.v1, k.eps)},
            {o[6].x, snapped_plane_distance<float>(k.p, k.n, k.v2, k.eps)},
            {o[6].y, ff_tri},
        };
        for (std::size_t j = 0; j < std::size(pairs); ++j) {
            EXPECT_TRUE(std::isfinite(pairs[j].first)) << "term " << j;
            EXPECT_TRUE(near(pairs[j].first, pairs[j].second)) << "term " << j << ": GPU " << pairs[j].first << ", CPU " << pairs[j].second;
            if (j < 3 || j == 9) worst_ff = std::max(worst_ff, double(std::abs(pairs[j].first - pairs[j].second)));
        }
        // Exact decisions: the snapped heights are 0 on both sides or on neither.
        const float gpu_s[3] = {o[5].z, o[5].w, o[6].x};
        const V verts[3] = {k.v0, k.v1, k.v2};
        for (int j = 0; j < 3; ++j) EXPECT_EQ(gpu_s[j] == 0.0f, snapped_plane_distance<float>(k.p, k.n, verts[j], k.eps) == 0.0f);
    }
    // Every kind of outcome was exercised.
    EXPECT_GT(quads, 20);
    EXPECT_GT(triangles, 20);
    EXPECT_GT(invisible, 20);
    std::cout << "[disk kernels] " << cases.size() << " cases (" << quads << " quads, " << triangles << " triangles, " << invisible
              << " invisible): worst |GPU - CPU| form factor " << worst_ff << ", point " << worst_point << " (relative)\n";
}
