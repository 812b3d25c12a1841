// The renderer on a real GL context: depth and normal AOVs against an
// analytic sphere, id AOV, pass culling per requested output, patient views,
// extreme scales, degenerate and empty scenes.
#include "renderer/gpu/renderer.hpp"

#include <array>
#include <cmath>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/surface/extract.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using Render = test::GlTest;
using test::float_at;
using test::sphere_mesh;

namespace {} // namespace

TEST_F(Render, DepthAndNormalAovsMatchTheAnalyticSphere) {
    const glm::dvec3 c(10, -20, 30);
    const double r = 40.0;
    Renderer ren;
    ren.add(sphere_mesh(c, r, 1.0), {});
    Camera cam;
    cam.set_view(PatientView::Anterior, ren.bounds());
    RenderOptions opt;
    opt.width = opt.height = 128;
    opt.aov = Aov::Depth;
    const auto depth = ren.render(cam, opt);
    ASSERT_TRUE(depth.image.is_float);
    // Centre pixel: the sphere's nearest point, at distance |eye - c| - r along the axis.
    const double expected = glm::length(cam.eye - c) - r;
    EXPECT_NEAR(float_at(depth.image, 64, 64), expected, 0.25) << "mm";
    EXPECT_TRUE(std::isinf(float_at(depth.image, 0, 0))) << "background is infinitely far";
    // A pixel halfway to the silhouette: ray-sphere intersection along that pixel's ray.
    {
        const int px = 64 + 20, py = 64;
        const double aspect = 1.0, t = std::tan(glm::radians(cam.fov_y_degrees) * 0.5);
        const double ndc_x = (px + 0.5) / 64.0 - 1.0, ndc_y = 1.0 - (py + 0.5) / 64.0;
        const glm::dvec3 f = cam.forward(), right = glm::normalize(glm::cross(f, cam.up)), up = glm::cross(right, f);
        const glm::dvec3 dir = glm::normalize(f + right * (ndc_x * t * aspect) + up * (ndc_y * t));
        const glm::dvec3 oc = cam.eye - c;
        const double b = glm::dot(oc, dir), disc = b * b - (glm::dot(oc, oc) - r * r);
        ASSERT_GT(disc, 0);
        const double hit = -b - std::sqrt(disc);
        const double axial = hit * glm::dot(dir, f);
        EXPECT_NEAR(float_at(depth.image, px, py), axial, 0.3);
    }
    opt.aov = Aov::Normal;
    const auto normal = ren.render(cam, opt);
    // Facing the camera at the centre: the anterior direction (-y in LPS).
    EXPECT_NEAR(float_at(normal.image, 64, 64, 1), -1.0, 0.01);
    // Lighting is culled when only an AOV is asked for.
    for (const auto& p : normal.stats.passes) {
        if (p.name == "lighting") {
            EXPECT_FALSE(p.ran);
        }
        if (p.name == "gbuffer") {
            EXPECT_TRUE(p.ran);
        }
    }
}

TEST_F(Render, IdAovAndAnteriorOrientation) {
    Renderer ren;
    // Patient's left (+x) sphere and patient's right (-x) sphere.
    const auto left = ren.add(sphere_mesh({60, 0, 0}, 20, 2.0), {"left"});
    const auto right = ren.add(sphere_mesh({-60, 0, 0}, 20, 2.0), {"right"});
    Camera cam;
    cam.set_view(PatientView::Anterior, ren.bounds());
    RenderOptions opt{.width = 160, .height = 80, .aov = Aov::Id};
    auto pixel = [&](glm::dvec3 p) {
        const glm::dvec4 clip = cam.projection(2.0) * cam.view() * glm::dvec4(p, 1.0);
        return glm::ivec2(int((clip.x / clip.w + 1) * 0.5 * 160), int((1 - clip.y / clip.w) * 0.5 * 80));
    };
    const auto img = ren.render(cam, opt).image;
    // Anterior view: the patient's left (+x) appears on the image's right.
    const auto pl = pixel({60, 0, 0}), pr = pixel({-60, 0, 0});
    EXPECT_GT(pl.x, 80);
    EXPECT_LT(pr.x, 80);
    EXPECT_EQ(float_at(img, pl.x, pl.y), float(left));
    EXPECT_EQ(float_at(img, pr.x, pr.y), float(right));
    EXPECT_EQ(float_at(img, 80, 40), 0.0f);
    cam.set_view(PatientView::Posterior, ren.bounds());
    const auto back = ren.render(cam, opt).image;
    const auto bl = pixel({60, 0, 0});
    EXPECT_LT(bl.x, 80) << "from behind, the patient's left is on the image's left";
    EXPECT_EQ(float_at(back, bl.x, bl.y), float(left));
}

TEST_F(Render, ExtremeScalesAndNearFarRatio) {
    // A 0.1 mm sphere seen from 2 m: near/far planes must still resolve it.
    Renderer tiny;
    tiny.add(sphere_mesh({0, 0, 0}, 0.05, 0.004), {});
    Camera cam;
    cam.set_view(PatientView::Anterior, tiny.bounds());
    cam.eye = glm::dvec3(0, -2000, 0);
    cam.near_plane = 1.0;
    cam.far_plane = 4000.0;
    cam.fov_y_degrees = 0.005; // a telephoto view of it
    RenderOptions opt{.width = 64, .height = 64, .aov = Aov::Depth};
    const auto d = tiny.render(cam, opt).image;
    EXPECT_NEAR(float_at(d, 32, 32), 2000.0 - 0.05, 0.02) << "reversed-Z float depth keeps sub-0.1 mm precision at 2 m";
    // Whole body at 2 m scale and micro-CT at 0.01 mm.
    for (double scale : {1000.0, 0.01}) {
        Renderer ren;
        ren.add(sphere_mesh({scale, 0, 0}, scale, scale / 10), {});
        Camera c2;
        c2.set_view(PatientView::Left, ren.bounds());
        const auto img = ren.render(c2, {.width = 64, .height = 64, .aov = Aov::Depth}).image;
        EXPECT_NEAR(float_at(img, 32, 32), glm::length(c2.eye - glm::dvec3(scale, 0, 0)) - scale, 0.02 * scale);
    }
}

TEST_F(Render, DegenerateAndEmptyScenes) {
    Renderer empty;
    Camera cam;
    cam.set_view(PatientView::Anterior, empty.bounds());
    RenderOptions opt{.width = 32, .height = 16};
    const auto img = empty.render(cam, opt).image;
    ASSERT_FALSE(img.is_float);
    ASSERT_EQ(img.channels, 4);
    ASSERT_EQ(img.bytes.size(), 32u * 16u * 4u);
    // Nothing is drawn: every pixel is the background, which the lighting
    // pass writes sRGB-encoded (IEC 61966-2-1) and not tone mapped, as
    // RGBA8 (round to nearest). The default (0.08, 0.09, 0.11) linear is
    // 255 * sRGB = 79.89, 84.62, 93.22: far from a rounding tie.
    const auto srgb8 = [](double linear) {
        const double s = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
        return int(std::lround(255 * s));
    };
    const std::array<int, 4> background{srgb8(opt.look.background.r), srgb8(opt.look.background.g),
                                        srgb8(opt.look.background.b), opt.look.transparent_background ? 0 : 255};
    ASSERT_EQ(background, (std::array<int, 4>{80, 85, 93, 255}));
    std::size_t other = 0;
    for (std::size_t p = 0; p < img.bytes.size() / 4; ++p) {
        const std::array<int, 4> px{img.bytes[p * 4], img.bytes[p * 4 + 1], img.bytes[p * 4 + 2], img.bytes[p * 4 + 3]};
        if (px == background) continue;
        if (++other <= 3) ADD_FAILURE() << "pixel " << p % 32 << "," << p / 32 << " is not the background";
    }
    EXPECT_EQ(other, 0u) << "of " << img.bytes.size() / 4 << " pixels";
    Renderer degenerate;
    Mesh m;
    m.positions = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 0, 0}};
    m.triangles = {{0, 1, 2}, {2, 3, 4}, {0, 0, 0}};
    degenerate.add(m, {});
    cam.set_view(PatientView::Anterior, degenerate.bounds());
    const auto d = degenerate.render(cam, {.width = 32, .height = 32, .aov = Aov::Normal}).image;
    for (float x : d.floats) EXPECT_TRUE(std::isfinite(x));
    EXPECT_THROW(degenerate.render(cam, {.width = 0, .height = 10}), Error);
}

TEST_F(Render, SteadyFramesMakeNoNewGlObjects) {
    // The viewer's case: the same view redrawn (still frames accumulating AO,
    // annotations on, presented into a window's framebuffer, then read back).
    // After the first frame of each kind, nothing is created: the pool's and
    // the GL objects' counts stay put.
    Renderer ren;
    ren.add(sphere_mesh({0, 0, 0}, 20, 2.0), {});
    Bounds b = ren.bounds();
    Camera cam;
    cam.set_view(PatientView::Left, b);
    cam.fit(b, 1.0);
    Annotations ann;
    ann.labels.push_back({{0, 0, 20}, "top"});
    auto window = gl::Texture::create_2d(GL_RGBA8, 96, 96);
    auto window_fb = gl::Framebuffer::create();
    window_fb.attach(GL_COLOR_ATTACHMENT0, window);
    RenderOptions o;
    o.width = o.height = 96;
    o.look.ao = AoMethod::Cone;
    o.annotations = &ann;
    o.present = true;
    o.target_framebuffer = window_fb.id();
    for (const bool present : {true, false}) {
        o.present = present;
        ren.render(cam, o);
        const auto created = ren.pool().stats().created;
        const auto objects = ren.gl_objects_created();
        for (int f = 0; f < 4; ++f) {
            const auto r = ren.render(cam, o);
            EXPECT_EQ(r.stats.physical_resources, 0u) << "frame " << f;
            EXPECT_GT(r.stats.reused_resources, 0u);
        }
        EXPECT_EQ(ren.pool().stats().created, created) << (present ? "presented" : "read back");
        EXPECT_EQ(ren.gl_objects_created(), objects) << (present ? "presented" : "read back");
        EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    }
    // A new size makes new resources once; the old ones are evicted by age.
    o.width = 64;
    ren.render(cam, o);
    const auto created = ren.pool().stats().created;
    for (int f = 0; f < 5; ++f) ren.render(cam, o);
    EXPECT_EQ(ren.pool().stats().created, created);
    EXPECT_GT(ren.pool().stats().destroyed, 0u) << "the 96x96 textures were evicted";
}
