// Disk AO on the GPU (docs/ao.md, "Disk AO on the GPU").
//
// The whole method: the element terms and gathered pixels read back and
// compared with the CPU evaluation (disk_element_terms, disk_occlusion) at
// the same points; the AO against the Embree reference on the bunny and the
// bundled CT skin; culling with AO off; the hierarchy and the element terms
// kept when only the camera moves.
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
#include "renderer/ao/disk_hierarchy.hpp"
#include "renderer/core/api.hpp"
#include "renderer/gpu/renderer.hpp"
#include "tests/support/ao_metrics.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/scenes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using DiskAo = test::GlTest;
using test::looking;

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
        out.insert(out.end(),
                   {glm::vec4(p, eps), glm::vec4(n, area), glm::vec4(v0, k), glm::vec4(v1, t), glm::vec4(v2, e),
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
        {V(0, 0, 1), V(1, 1, 2), V(2, 2, 3)},   {V(1, 0, 1), V(1, 0, 1), V(0, 1, 1)},
        {V(1, 0, 1), V(1, 0, 1), V(1, 0, 1)},   {V(0, 0, 0), V(1, 0, 1), V(0, 1, 1)},
        {V(-1, 0, 0), V(1, 0, 0), V(0, 1, 1)},  {V(0, 0, 0), V(0, 0, 0), V(0, 0, 0)},
        {V(1, 0, 0), V(0, 1, 0), V(-1, -1, 0)}, {V(0, 0, 2), V(0, 0, 1), V(1, 1, 1)},
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
    special("disk on the axis", [](KernelCase& k) {
        k.c = V(0, 0, 2);
        k.area = 3.0f;
    });
    special("disk back-facing", [](KernelCase& k) {
        k.c = V(0, 0, 2);
        k.m = V(0, 0, 1);
    });
    special("disk below", [](KernelCase& k) {
        k.c = V(0.5f, 0, -2);
        k.m = V(0, 0, 1);
    });
    special("disk zero area", [](KernelCase& k) {
        k.c = V(0, 1, 2);
        k.area = 0.0f;
    });
    special("disk negative area", [](KernelCase& k) {
        k.c = V(0, 1, 2);
        k.area = -1.0f;
    });
    special("e = 0, t = 1", [](KernelCase& k) { k.e = 0.0f; });
    special("e = 0, t = 0", [](KernelCase& k) {
        k.e = 0.0f;
        k.t = 0.0f;
    });
    special("e = 0.4, t = 2.5", [](KernelCase& k) {
        k.e = 0.4f;
        k.t = 2.5f;
    });
    special("e = 1.5 clamped", [](KernelCase& k) {
        k.e = 1.5f;
        k.t = 3.0f;
    });
    special("e = -1 clamped", [](KernelCase& k) {
        k.e = -1.0f;
        k.t = 3.0f;
    });
    special("t negative", [](KernelCase& k) {
        k.e = 0.5f;
        k.t = -2.0f;
    });
    special("k = 0.5, d2 = 3", [](KernelCase& k) {
        k.k = 0.5f;
        k.d2 = 3.0f;
    });
    special("k negative", [](KernelCase& k) {
        k.k = -1.0f;
        k.d2 = 3.0f;
    });
    special("blend", [](KernelCase& k) {
        k.o0 = 0.2f;
        k.o1 = 0.9f;
    });
    special("blend 0.5 / 0.5", [](KernelCase& k) {
        k.o0 = 0.9f;
        k.o1 = 0.1f;
        k.min_scale = 0.5f;
        k.max_scale = 0.5f;
    });

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
            const float scale =
                std::max({glm::length(k.p), glm::length(k.v0), glm::length(k.v1), glm::length(k.v2), 1.0f});
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
            EXPECT_TRUE(near(pairs[j].first, pairs[j].second))
                << "term " << j << ": GPU " << pairs[j].first << ", CPU " << pairs[j].second;
            if (j < 3 || j == 9) worst_ff = std::max(worst_ff, double(std::abs(pairs[j].first - pairs[j].second)));
        }
        // Exact decisions: the snapped heights are 0 on both sides or on neither.
        const float gpu_s[3] = {o[5].z, o[5].w, o[6].x};
        const V verts[3] = {k.v0, k.v1, k.v2};
        for (int j = 0; j < 3; ++j)
            EXPECT_EQ(gpu_s[j] == 0.0f, snapped_plane_distance<float>(k.p, k.n, verts[j], k.eps) == 0.0f);
    }
    // Every kind of outcome was exercised.
    EXPECT_GT(quads, 20);
    EXPECT_GT(triangles, 20);
    EXPECT_GT(invisible, 20);
    std::cout << "[disk kernels] " << cases.size() << " cases (" << quads << " quads, " << triangles << " triangles, "
              << invisible << " invisible): worst |GPU - CPU| form factor " << worst_ff << ", point " << worst_point
              << " (relative)\n";
}

namespace {

RenderOptions disk_options(int size, double radius) {
    RenderOptions o;
    o.width = o.height = size;
    o.aov = Aov::Ao;
    o.look.ao = AoMethod::Disk;
    o.look.cone.radius_mm = radius;
    return o;
}

bool ran(const graph::FrameStats& s, const std::string& name) {
    for (const auto& p : s.passes)
        if (p.name == name) return p.ran;
    return false;
}
bool declared(const graph::FrameStats& s, const std::string& name) {
    for (const auto& p : s.passes)
        if (p.name == name) return true;
    return false;
}

} // namespace

// GPU = CPU: the bunny (a real scanned mesh: 1 000 triangles with shared
// vertices, concave folds) over a floor box (two surfaces: concatenate),
// R = 0.05 (a tenth of the bunny), 96x96, with the defaults (no element
// passes, epsilon 16) and with the chapter's two element passes at epsilon
// 8. Element terms and every 7th foreground pixel are read back and
// compared with disk_element_terms / disk_occlusion_sided at the very
// points, normals, sides (from the GPU's geometric normal) and terms the
// GPU used. Both sides run the same float traversal (disk_occlusion_t<float>
// and its GLSL mirror); they differ by rounding (fused multiply-adds,
// llvmpipe's atan and sqrt): measured p99 <= 1.9e-6 and max <= 2.9e-6.
// Bounds: 99 % within 1e-5; every value within 0.02, because a node whose
// d^2 lies within rounding of traversal_epsilon x area (or of R) may be
// opened on one side and not the other, which moves that one value by up to
// about a hundredth.
TEST_F(DiskAo, ElementTermsAndGatherMatchTheCpuHierarchy) {
    const Mesh bunny = core::open_mesh(test::data("bunny.vtp"));
    Bounds bb;
    for (const auto& p : bunny.positions) bb.add(glm::dvec3(p));
    const glm::vec3 lo(bb.min), hi(bb.max);
    const float pad = 0.3f * (hi.x - lo.x);
    // Floor under the bunny: the bunny's up is +y in its file.
    const Mesh floor = test::flat_box_mesh({lo.x - pad, lo.y - 0.02f, lo.z - pad}, {hi.x + pad, lo.y, hi.z + pad});
    Renderer ren;
    ren.add(bunny, {});
    ren.add(floor, {});
    const glm::dvec3 c = bb.center();
    const double size = 2.0 * bb.radius();
    Camera cam = looking(c + size * glm::dvec3(0.3, 0.5, 1.1), c, {0, 1, 0});
    cam.fit_planes(ren.bounds());
    const double radius = 0.05;
    const DiskHierarchy hb = build_disk_hierarchy(bunny), hf = build_disk_hierarchy(floor);
    const DiskHierarchy h = concatenate({&hb, &hf});
    auto summarize = [](std::vector<double> err, const std::string& what) {
        std::sort(err.begin(), err.end());
        const double p99 = err[std::min(err.size() - 1, std::size_t(0.99 * double(err.size())))];
        std::cout << "[disk GPU vs CPU] " << what << ": " << err.size() << " values, p99 " << p99 << ", max "
                  << err.back() << "\n";
        EXPECT_LE(p99, 1e-5) << what;
        EXPECT_LE(err.back(), 0.02) << what;
    };
    // The defaults (no element passes, epsilon 16), then the chapter's two
    // element passes (t = 1, 0.7 / 0.3) at epsilon 8.
    for (const int passes : {0, 2}) {
        SCOPED_TRACE("passes " + std::to_string(passes));
        RenderOptions o = disk_options(96, radius);
        if (passes) {
            o.look.disk.passes = passes;
            o.look.disk.traversal_epsilon = 8;
        }
        RenderHooks hooks;
        hooks.read_disk = true;
        const RenderResult r = ren.render(cam, o, hooks);
        ASSERT_EQ(r.disk_elements, passes > 0);
        ASSERT_EQ(r.disk_nodes, h.nodes.size());
        ASSERT_EQ(r.disk_terms.size(), h.nodes.size());
        const std::vector<float> cpu_terms = disk_element_terms(h, o.look.disk, radius);
        ASSERT_EQ(cpu_terms.size(), h.nodes.size());
        std::vector<double> term_err;
        double open = 0;
        for (std::size_t i = 0; i < h.nodes.size(); ++i) {
            ASSERT_TRUE(std::isfinite(r.disk_terms[i])) << i;
            term_err.push_back(std::abs(double(r.disk_terms[i]) - double(cpu_terms[i])));
            open += cpu_terms[i];
        }
        summarize(term_err, "element terms, passes " + std::to_string(passes));
        if (passes) {
            EXPECT_LT(open / double(h.nodes.size()), 0.99) << "the terms resolve some occlusion";
        }

        // Gathered pixels: every 7th foreground pixel, at the GPU's own
        // receiver, its side (from the GPU's geometric normal) and terms.
        ASSERT_EQ(r.disk_receivers.size(), std::size_t(2 * 96 * 96));
        std::vector<double> px_err;
        std::size_t dark = 0;
        for (std::size_t i = 0; i < 96 * 96; i += 7) {
            const glm::vec4 pa = r.disk_receivers[2 * i], nb = r.disk_receivers[2 * i + 1];
            if (!std::isfinite(pa.w)) continue;
            ASSERT_TRUE(nb.w == 1.0f || nb.w == -1.0f) << nb.w;
            const glm::dvec3 n = glm::dvec3(glm::vec3(nb));
            const double cpu = 1.0 - disk_occlusion_sided(h, glm::dvec3(glm::vec3(pa)), n, double(nb.w) * n,
                                                          r.disk_terms, o.look.disk, radius);
            px_err.push_back(std::abs(double(pa.w) - cpu));
            dark += cpu < 0.8;
            // The AO image holds the same value (its rows top-down).
            const std::size_t x = i % 96, y = i / 96;
            EXPECT_EQ(r.image.floats[(95 - y) * 96 + x], pa.w) << "pixel " << x << "," << y;
        }
        ASSERT_GT(px_err.size(), 300u);
        EXPECT_GT(dark, 10u) << "the sample holds occluded pixels";
        summarize(px_err, "gathered pixels, passes " + std::to_string(passes));
    }
}

// Against the Embree reference (512 rays, 256x256), as cone AO is checked in
// ao_test.cpp: the bunny at R = 0.05 and the bundled CT skin at R = 10 mm.
// Default settings (no element passes, epsilon 16, sided gather). Bounds:
// measured RMSE 0.018 (skin; the 512-ray reference's own noise RMS is
// ~0.007 of it) and 0.005 (bunny), bias -0.001 / +0.001, plus a margin
// (docs/ao.md, "Disk AO on the GPU"); no AO at all is at least 1.5x worse.
TEST_F(DiskAo, CtSkinAndBunnyAgainstTheEmbreeReference) {
    struct Case {
        std::string input, view;
        std::vector<double> isos;
        double radius, max_rmse, max_bias;
    };
    const Case cases[] = {{test::data("headsq.nhdr"), "left", {500}, 10.0, 0.03, 0.01},
                          {test::data("bunny.vtp"), "anterior", {}, 0.05, 0.015, 0.01}};
    for (const auto& k : cases) {
        core::RenderRequest rq;
        rq.isos = k.isos;
        rq.view = k.view;
        rq.width = rq.height = 256;
        rq.aov = Aov::Ao;
        rq.look.ao = AoMethod::Raytraced;
        rq.look.cone.radius_mm = k.radius;
        rq.look.ao_rays = 512;
        const auto ref = core::render_input(k.input, rq);
        rq.look.ao = AoMethod::Disk;
        rq.time_passes = true;
        const auto disk = core::render_input(k.input, rq);
        const auto e = ao_error(disk.image, ref.image, rq.look.ao_rays);
        double gather_ms = 0, element_ms = 0;
        for (const auto& p : disk.stats.passes) {
            if (p.name == "disk_gather") gather_ms = p.ms;
            if (p.name == "disk_elements") element_ms = p.ms;
        }
        std::cout << "[disk vs Embree] " << k.input << ": RMSE " << e.rmse << " bias " << e.bias << " p95 " << e.p95
                  << " (elements " << element_ms << " ms, gather " << gather_ms << " ms)\n";
        EXPECT_GT(e.pixels, 5000u);
        EXPECT_LE(e.rmse, k.max_rmse) << k.input << ": bias " << e.bias << " MAE " << e.mae << " p95 " << e.p95;
        EXPECT_LE(std::abs(e.bias), k.max_bias) << k.input;
        Image ones = ref.image;
        for (auto& v : ones.floats)
            if (std::isfinite(v)) v = 1;
        EXPECT_GT(ao_error(ones, ref.image).rmse, 1.5 * e.rmse) << k.input;
        EXPECT_NE(disk.meta.text.at("isoscope:ao").find("disk"), std::string::npos);
        EXPECT_NE(disk.meta.text.at("isoscope:ao_parameters").find("passes 0; traversal_epsilon 16"),
                  std::string::npos);
    }
}

// AO off: the disk passes are declared and culled. On: built once; a moved
// camera reuses the hierarchy and the element terms (only the gather runs);
// new settings rerun the element passes only; a new surface rebuilds.
TEST_F(DiskAo, PassesAreCulledWhenOffAndTheHierarchyIsKeptAcrossViews) {
    Renderer ren;
    ren.add(test::flat_box_mesh({-20, -20, -20}, {20, 20, 20}), {});
    ren.add(test::flat_box_mesh({-40, -40, -25}, {40, 40, -20}), {});
    const Camera cam = looking({30, -300, 40}, {0, 0, 0}, {0, 0, 1});
    RenderOptions o;
    o.width = o.height = 48;
    o.look.ao = AoMethod::Off;
    o.look.cone.radius_mm = 10;
    o.look.disk.passes = 2; // the element passes run (the default has none)
    const auto off = ren.render(cam, o);
    for (const char* pass : {"disk_build", "disk_elements", "disk_gather", "cone_ao"})
        EXPECT_FALSE(ran(off.stats, pass)) << pass << " with AO off";
    EXPECT_FALSE(off.disk_built);
    o.look.ao = AoMethod::Disk;
    const auto a = ren.render(cam, o);
    EXPECT_TRUE(a.disk_built);
    EXPECT_TRUE(a.disk_elements);
    EXPECT_TRUE(ran(a.stats, "disk_gather"));
    EXPECT_FALSE(ran(a.stats, "voxelize")) << "disk AO does not run the cone chain";
    EXPECT_FALSE(ran(a.stats, "cone_ao"));
    Camera moved = cam;
    moved.orbit(20, 5);
    const auto b = ren.render(moved, o);
    EXPECT_FALSE(b.disk_built) << "only the camera moved";
    EXPECT_FALSE(b.disk_elements) << "the terms do not depend on the camera";
    EXPECT_FALSE(declared(b.stats, "disk_build"));
    EXPECT_TRUE(ran(b.stats, "disk_gather"));
    o.look.disk.passes = 3;
    const auto c = ren.render(moved, o);
    EXPECT_FALSE(c.disk_built);
    EXPECT_TRUE(c.disk_elements) << "new settings";
    o.look.cone.radius_mm = 12;
    EXPECT_TRUE(ren.render(moved, o).disk_elements) << "new radius";
    ren.add(test::flat_box_mesh({-5, -5, 25}, {5, 5, 35}), {});
    const auto d = ren.render(moved, o);
    EXPECT_TRUE(d.disk_built) << "a new surface";
    EXPECT_TRUE(d.disk_elements);
    ren.object(3).visible = false;
    EXPECT_TRUE(ren.render(moved, o).disk_built) << "the visible set changed";
    o.look.disk.passes = 0;
    const auto none = ren.render(moved, o);
    EXPECT_FALSE(none.disk_elements) << "no element passes";
    EXPECT_FALSE(declared(none.stats, "disk_elements"));
    EXPECT_TRUE(ran(none.stats, "disk_gather"));
    // The colour image with disk AO differs from the one without.
    const auto lit = ren.render(moved, o);
    o.look.ao = AoMethod::Off;
    const auto unlit = ren.render(moved, o);
    EXPECT_NE(lit.image.bytes, unlit.image.bytes);
}

TEST_F(DiskAo, GatherReportsProgressInBandsAndCanBeCancelled) {
    // The bunny at R = 0.05, 96 x 200 (four bands of 64 rows, the last 8):
    // with a progress callback the gather runs band by band and reports
    // after each; the image is the same bit for bit as without one; a
    // callback that says stop after the first band makes the core throw
    // iso::Cancelled naming disk AO.
    core::RenderRequest rq;
    rq.isos = {};
    rq.view = "anterior";
    rq.width = 96;
    rq.height = 200;
    rq.aov = Aov::Ao;
    rq.look.ao = AoMethod::Disk;
    rq.look.cone.radius_mm = 0.05;
    const std::string input = test::data("bunny.vtp");
    const auto plain = core::render_input(input, rq);
    std::vector<double> disk_fractions;
    rq.progress = [&](double f, std::string_view stage) {
        if (stage == "disk AO") disk_fractions.push_back(f);
        return true;
    };
    const auto banded = core::render_input(input, rq);
    ASSERT_EQ(disk_fractions.size(), 4u);
    EXPECT_DOUBLE_EQ(disk_fractions[0], 64.0 / 200.0);
    EXPECT_DOUBLE_EQ(disk_fractions.back(), 1.0);
    ASSERT_EQ(plain.image.floats.size(), banded.image.floats.size());
    std::size_t surface = 0;
    for (std::size_t i = 0; i < plain.image.floats.size(); ++i) {
        const float a = plain.image.floats[i], b = banded.image.floats[i];
        if (std::isnan(a)) {
            EXPECT_TRUE(std::isnan(b)) << i;
            continue;
        }
        ++surface;
        ASSERT_EQ(a, b) << "pixel " << i;
    }
    EXPECT_GT(surface, 1000u); // measured 1555 bunny pixels
    int calls = 0;
    rq.progress = [&](double, std::string_view stage) { return stage != "disk AO" || ++calls < 1; };
    try {
        core::render_input(input, rq);
        FAIL() << "a cancelled gather must not return an image";
    } catch (const Cancelled& e) {
        EXPECT_NE(std::string(e.what()).find("disk AO"), std::string::npos) << e.what();
    }
    EXPECT_EQ(calls, 1);
}
