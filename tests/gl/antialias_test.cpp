// Anti-aliasing on a real GL context against exact coverage: a triangle's
// edge across the image (a half-plane within the view), white on black,
// flat shaded, so a pixel's exact value is the sRGB encoding of the area of
// the pixel on the triangle's side (computed by clipping the pixel square).
// DSRAA's sub-samples, the accumulation of jittered frames (Halton and a
// stratified 8 x 8 grid), N x N supersampling and the export's convergence
// rule (core::render_converged) are each measured against it.
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "io/color.hpp"
#include "renderer/core/api.hpp"
#include "renderer/gpu/renderer.hpp"

using namespace iso;
using AntiAlias = test::GlTest;

namespace {

constexpr int kW = 96, kH = 64;
// The triangle: its edge A-B crosses the view at a slant; C lies far beyond the view.
const glm::dvec3 kA(-300, 0, -70), kB(300, 0, 40), kC(0, 0, 2000);

Mesh edge_triangle() {
    Mesh m;
    m.positions = {glm::vec3(kA), glm::vec3(kB), glm::vec3(kC)};
    m.normals = {glm::vec3(0, -1, 0), glm::vec3(0, -1, 0), glm::vec3(0, -1, 0)};
    m.triangles = {{0u, 1u, 2u}};
    return m;
}

FrameLook flat_look(int samples) {
    FrameLook l;
    l.flat_shading = true;
    l.background = glm::vec3(0.0f);
    l.aa.samples = samples;
    return l;
}

// The edge in image pixels (x right, y down from the top-left corner), and
// which side of it the triangle is on.
struct Edge {
    glm::dvec2 a, b;
    double side = 1;
};
Edge image_edge(const Camera& cam) {
    const glm::dmat4 vp = cam.projection(double(kW) / kH) * cam.view();
    const auto pixel = [&](glm::dvec3 p) {
        const glm::dvec4 c = vp * glm::dvec4(p, 1.0);
        return glm::dvec2((c.x / c.w + 1) * 0.5 * kW, (1 - c.y / c.w) * 0.5 * kH);
    };
    Edge e{pixel(kA), pixel(kB)};
    const glm::dvec2 c = pixel(kC), d = e.b - e.a;
    e.side = (d.x * (c.y - e.a.y) - d.y * (c.x - e.a.x)) > 0 ? 1 : -1;
    return e;
}

// The area of pixel (x, y) on the triangle's side of the edge: the pixel
// square clipped by the half-plane (Sutherland-Hodgman), by the shoelace formula.
double coverage(const Edge& e, int x, int y) {
    const glm::dvec2 d = e.b - e.a;
    const auto f = [&](glm::dvec2 p) { return e.side * (d.x * (p.y - e.a.y) - d.y * (p.x - e.a.x)); };
    const glm::dvec2 sq[4] = {{x, y}, {x + 1, y}, {x + 1, y + 1}, {x, y + 1}};
    std::vector<glm::dvec2> poly;
    for (int i = 0; i < 4; ++i) {
        const glm::dvec2 p = sq[i], q = sq[(i + 1) % 4];
        const double fp = f(p), fq = f(q);
        if (fp >= 0) poly.push_back(p);
        if ((fp >= 0) != (fq >= 0)) poly.push_back(p + (q - p) * (fp / (fp - fq)));
    }
    double area = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const glm::dvec2 p = poly[i], q = poly[(i + 1) % poly.size()];
        area += p.x * q.y - q.x * p.y;
    }
    return std::abs(area) * 0.5;
}

// RMS and largest difference, in sRGB units, between the image's red
// channel and the exact coverage: over the pixels the edge crosses, and
// over the others (where every method must be exact).
struct EdgeError {
    double edge_rms = 0, edge_max = 0, interior_max = 0;
};
EdgeError against_exact(const Image& img, const Camera& cam) {
    const Edge e = image_edge(cam);
    EdgeError r;
    double sum = 0;
    int n = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const double c = coverage(e, x, y);
            const double want = srgb_from_linear(float(c));
            const double got = img.bytes[(std::size_t(y) * kW + x) * 4] / 255.0;
            const double d = std::abs(got - want);
            if (c > 0 && c < 1) {
                sum += d * d;
                ++n;
                r.edge_max = std::max(r.edge_max, d);
            } else {
                r.interior_max = std::max(r.interior_max, d);
            }
        }
    r.edge_rms = n ? std::sqrt(sum / n) : 0;
    return r;
}

RenderResult draw(Renderer& ren, const Camera& cam, const FrameLook& look, bool accumulate = false,
                  std::optional<glm::vec2> jitter = {}, bool restart = false) {
    RenderOptions opt;
    opt.restart_accumulation = restart;
    opt.width = kW;
    opt.height = kH;
    opt.look = look;
    opt.accumulate = accumulate;
    opt.jitter = jitter;
    return ren.render(cam, opt);
}

} // namespace

TEST_F(AntiAlias, DsraaSubSamplesApproachExactCoverageOfAnEdge) {
    Renderer ren;
    ren.add(edge_triangle(), {"edge", glm::vec3(1.0f)});
    const Camera cam;
    const EdgeError one = against_exact(draw(ren, cam, flat_look(1)).image, cam);
    const RenderResult r4 = draw(ren, cam, flat_look(4));
    EXPECT_EQ(r4.aa_samples, 4);
    const EdgeError four = against_exact(r4.image, cam);
    const RenderResult r8 = draw(ren, cam, flat_look(8));
    const EdgeError eight = against_exact(r8.image, cam);
    std::printf("edge RMSE (sRGB): 1 sample %.3f, DSRAA 4 %.3f, DSRAA %d %.3f\n", one.edge_rms, four.edge_rms,
                r8.aa_samples, eight.edge_rms);
    EXPECT_GT(one.edge_rms, 0.3) << "one sample per pixel is a staircase";
    EXPECT_LT(four.edge_rms, 0.13) << "MSAA 4x's figure: the reconstruction loses nothing on a two-colour edge";
    // 8 sub-samples where the GL allows them (llvmpipe stops at 4: the frame then says so).
    EXPECT_GE(r8.aa_samples, 4);
    if (r8.aa_samples == 8) {
        EXPECT_LT(eight.edge_rms, four.edge_rms);
    }
    // Away from the edge every pixel is exact: the reconstruction never blurs.
    for (const EdgeError& e : {one, four, eight}) EXPECT_LE(e.interior_max, 0.5 / 255.0);
    // The pass runs only with sub-samples.
    const auto ran = [](const RenderResult& r) {
        for (const auto& p : r.stats.passes)
            if (p.name == "dsraa") return p.ran;
        return false;
    };
    EXPECT_TRUE(ran(r4));
    EXPECT_FALSE(ran(draw(ren, cam, flat_look(1))));
}

TEST_F(AntiAlias, JitteredFramesConvergeToTheSupersampledImage) {
    Renderer ren;
    ren.add(edge_triangle(), {"edge", glm::vec3(1.0f)});
    const Camera cam;
    // N x N supersampling: the image drawn 8 times larger, averaged in linear light.
    const int N = 8;
    RenderOptions big;
    big.width = kW * N;
    big.height = kH * N;
    big.look = flat_look(1);
    const Image large = ren.render(cam, big).image;
    Image super = large;
    super.width = kW;
    super.height = kH;
    super.bytes.assign(std::size_t(kW) * kH * 4, 255);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            double sum = 0;
            for (int j = 0; j < N; ++j)
                for (int i = 0; i < N; ++i)
                    sum += linear_from_srgb(large.bytes[(std::size_t(y * N + j) * big.width + x * N + i) * 4] / 255.0f);
            super.bytes[(std::size_t(y) * kW + x) * 4] =
                std::uint8_t(std::lround(255.0 * srgb_from_linear(float(sum / (N * N)))));
        }
    const EdgeError ss = against_exact(super, cam);
    EXPECT_LT(ss.edge_rms, 0.03);
    // Halton-jittered frames, one sample each: the error falls as frames accumulate.
    std::vector<double> errors;
    RenderResult r;
    for (int n = 1; n <= 64; ++n) {
        r = draw(ren, cam, flat_look(1), true);
        ASSERT_EQ(r.aa_frames, n) << "the average restarted";
        if (n == 4 || n == 16 || n == 64) errors.push_back(against_exact(r.image, cam).edge_rms);
    }
    std::printf("accumulated edge RMSE: 4 frames %.4f, 16 %.4f, 64 %.4f; 8x8 supersampled %.4f\n", errors[0], errors[1],
                errors[2], ss.edge_rms);
    EXPECT_LT(errors[1], errors[0]);
    EXPECT_LT(errors[2], errors[1]);
    EXPECT_LT(errors[2], 0.03);
    EXPECT_LE(against_exact(r.image, cam).interior_max, 0.5 / 255.0);
    // A stratified 8 x 8 grid of offsets (what exact-coverage references use).
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i)
            r = draw(ren, cam, flat_look(1), true, glm::vec2((i + 0.5f) / 8 - 0.5f, (j + 0.5f) / 8 - 0.5f),
                     i == 0 && j == 0);
    EXPECT_EQ(r.aa_frames, 64) << "a new jitter is not a new view";
    const EdgeError grid = against_exact(r.image, cam);
    EXPECT_LT(grid.edge_rms, 0.02);
    // Anything but the jitter starts the average again.
    RenderOptions moved;
    moved.width = kW;
    moved.height = kH;
    moved.look = flat_look(1);
    moved.look.background = glm::vec3(0.01f);
    moved.accumulate = true;
    EXPECT_EQ(ren.render(cam, moved).aa_frames, 1);
}

TEST_F(AntiAlias, ExportsStopWhenTheImageStopsChanging) {
    core::Scene scene;
    core::SurfaceInfo info;
    info.name = "edge";
    info.color = glm::vec3(1.0f);
    scene.add_mesh(edge_triangle(), info);
    core::RenderRequest req;
    req.width = kW;
    req.height = kH;
    req.camera = Camera();
    req.annotations = false;
    req.look = flat_look(4);
    req.look.aa.tolerance = 0.05;
    core::RenderOutput out = core::render_image(scene, req);
    std::printf("export: %d frames, last change %.4f, edge RMSE %.4f\n", out.aa_frames, out.aa_change,
                against_exact(out.image, out.camera).edge_rms);
    EXPECT_GE(out.aa_frames, 4);
    EXPECT_LT(out.aa_frames, req.look.aa.frames) << "a tolerance of 0.05 is reached before 64 frames";
    EXPECT_LE(out.aa_change, 0.05);
    EXPECT_NE(out.meta.text["isoscope:antialiasing"].find("DSRAA 4"), std::string::npos);
    const EdgeError converged = against_exact(out.image, out.camera);
    EXPECT_LT(converged.edge_rms, 0.05);
    // A tolerance of 0 runs every frame; a single frame is one frame.
    req.look.aa.tolerance = 0;
    req.look.aa.frames = 16;
    EXPECT_EQ(core::render_image(scene, req).aa_frames, 16);
    req.look.aa.frames = 1;
    EXPECT_EQ(core::render_image(scene, req).aa_frames, 1);
}
