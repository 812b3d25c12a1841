// Progressive ray-traced AO of a view (renderer/ao/progressive.hpp): the
// standard-error stop rule, agreement with the point reference and the
// closed form, independence of the ray offset, cancellation and progress.
#include "renderer/ao/progressive.hpp"
#include "renderer/core/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tests/support/ao_metrics.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;

namespace {

// A floor (z <= 0) and a wall (x >= 10, 50 mm high), seen from 100 mm above.
struct WallScene {
    Mesh mesh;
    Camera cam;
    static constexpr int W = 48, H = 32;
    WallScene() {
        test::append_box(mesh, {-1000, -1000, -1}, {1000, 1000, 0});
        test::append_box(mesh, {10, -1000, -1}, {20, 1000, 50});
        cam.eye = {0, 0, 100};
        cam.target = {0, 0, 0};
        cam.up = {0, 1, 0};
        cam.fov_y_degrees = 30;
        cam.near_plane = 1;
        cam.far_plane = 1000;
    }
};

ProgressiveAoOptions fixed_rays(int n) {
    ProgressiveAoOptions o;
    o.radius_mm = 10;
    o.min_rays = o.max_rays = o.batch_rays = n;
    o.target_se = 1e-9;
    return o;
}

// Over the pixels where `a` is below `below` (all: 2).
double rmse(const Image& a, const Image& b, float below = 2) {
    double s = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.floats.size(); ++i)
        if (std::isfinite(a.floats[i]) && std::isfinite(b.floats[i]) && a.floats[i] < below) {
            s += (a.floats[i] - b.floats[i]) * (a.floats[i] - b.floats[i]);
            ++n;
        }
    return n ? std::sqrt(s / n) : 0.0;
}

} // namespace

TEST(ProgressiveAo, BinomialStandardError) {
    // p = (u + 1) / (n + 2): a pixel whose rays all agree is not exact.
    EXPECT_NEAR(ProgressiveAo::binomial_se(49, 98), 0.5 / std::sqrt(98.0), 1e-12);
    EXPECT_GT(ProgressiveAo::binomial_se(64, 64), 0.0);
    EXPECT_NEAR(ProgressiveAo::binomial_se(64, 64), std::sqrt(65.0 / 66 * (1.0 / 66) / 64), 1e-12);
    EXPECT_TRUE(std::isinf(ProgressiveAo::binomial_se(0, 0)));
}

// Each pixel stops at the first batch where sqrt(p (1 - p) / n) <= target
// for its true p (from 4096 rays): within one batch, every pixel's error is
// then at or below the target, and the image is done.
TEST(ProgressiveAo, StandardErrorRuleStopsAtThePredictedRayCount) {
    const WallScene s;
    const AoReference tracer({&s.mesh});
    ProgressiveAo truth(tracer, s.cam, s.W, s.H, fixed_rays(4096));
    truth.run();
    const Image p = truth.image();
    ProgressiveAoOptions o;
    o.radius_mm = 10;
    o.target_se = 0.02;
    o.batch_rays = 32;
    o.min_rays = 64;
    o.max_rays = 8192;
    ProgressiveAo ao(tracer, s.cam, s.W, s.H, o);
    int batches = 0;
    while (!ao.add_batch()) ++batches;
    const auto st = ao.stats();
    EXPECT_TRUE(st.done);
    EXPECT_EQ(st.pixels, s.W * s.H);
    EXPECT_EQ(st.capped, 0);
    EXPECT_LE(st.se_max, o.target_se);
    int predicted_max = 0, off_by_more = 0, occluded = 0;
    for (std::size_t i = 0; i < p.floats.size(); ++i) {
        const double q = (p.floats[i] * 4096.0 + 1) / 4098.0; // the rule's own estimate of p, from the truth
        int n = o.min_rays;
        while (std::sqrt(q * (1 - q) / n) > o.target_se) n += o.batch_rays;
        predicted_max = std::max(predicted_max, n);
        off_by_more += std::abs(ao.rays(i) - n) > o.batch_rays;
        occluded += p.floats[i] < 0.9f;
    }
    EXPECT_GT(occluded, 100) << "the wall's foot is in view";
    EXPECT_GT(predicted_max, 400) << "some pixels need many more rays than others";
    EXPECT_LE(off_by_more, int(p.floats.size() / 100)) << "pixels off the predicted count by more than one batch";
    EXPECT_NEAR(st.rays_max, predicted_max, o.batch_rays);
    EXPECT_EQ(st.rays_min, o.min_rays) << "open floor stops at the minimum";
    EXPECT_LT(double(st.rays) / st.pixels, 0.8 * predicted_max) << "adaptive: most pixels stop early";
}

// At 4096 rays the view's estimate agrees with AoReference::at at the same
// point and normal, and with the closed form of the wall.
TEST(ProgressiveAo, AgreesWithThePointReferenceAndTheClosedForm) {
    const WallScene s;
    const AoReference tracer({&s.mesh});
    ProgressiveAo ao(tracer, s.cam, s.W, s.H, fixed_rays(4096));
    ao.run();
    const Image img = ao.image();
    int checked = 0;
    for (int y = 0; y < s.H; y += 5)
        for (int x = 0; x < s.W; x += 3) {
            const std::size_t i = std::size_t(y) * s.W + x;
            const auto surf = ao.surface(i);
            ASSERT_TRUE(surf);
            const auto [point, normal] = *surf;
            const double ref = tracer.at(point, normal, {.radius_mm = 10, .rays = 4096}, unsigned(i));
            EXPECT_NEAR(img.floats[i], ref, 0.025) << x << "," << y; // both within 0.0078 (1 SE)
            if (point.z > -0.01 && point.z < 0.01 && point.x < 10) { // the floor, 10 - x from the wall
                EXPECT_NEAR(normal.z, 1.0, 1e-9);
                EXPECT_NEAR(img.floats[i], wall_ao(10 - point.x, 10), 0.025) << "floor at x = " << point.x;
                ++checked;
            }
        }
    EXPECT_GT(checked, 20);
}

// The result does not depend on how far above the surface rays leave it:
// x10 and x0.1 the offset change the image by less than its noise (the
// RMSE between two seeds), over the occluded pixels (AO < 0.99: open
// surfaces have no noise). On the head CT's bone (iso 1150, the thin walls
// and creases of a marching-cubes mesh, where the offset matters most) and
// on the floor meeting a wall (exactly nothing changes there).
TEST(ProgressiveAo, RayOffsetChangesLessThanTheNoise) {
    core::Scene head;
    head.open(test::data("headsq.nhdr"));
    head.add_isosurfaces({1150});
    const Mesh& bone = head.mesh(head.surfaces().front());
    const WallScene wall;
    struct Case {
        const char* name;
        const Mesh* mesh;
        Camera cam;
    } cases[] = {{"bone 1150", &bone, head.camera(PatientView::Left, 1.0)}, {"wall", &wall.mesh, wall.cam}};
    for (const Case& c : cases) {
        const AoReference tracer({c.mesh});
        auto image = [&](double scale, unsigned seed) {
            ProgressiveAoOptions o = fixed_rays(256);
            o.offset_scale = scale;
            o.seed = seed;
            ProgressiveAo ao(tracer, c.cam, 64, 64, o);
            ao.run();
            return ao.image();
        };
        const Image base = image(1, 1);
        const double noise = rmse(base, image(1, 2), 0.99f);
        EXPECT_GT(noise, 0.005) << c.name;
        for (const double scale : {10.0, 0.1}) {
            const double d = rmse(base, image(scale, 1), 0.99f);
            std::printf("%s: offset x%g (%.2g mm) changes AO by RMSE %.5f; noise %.5f\n", c.name, scale,
                        scale * tracer.ray_offset(), d, noise);
            EXPECT_LT(d, noise) << c.name << ", offset x" << scale;
        }
    }
}

TEST(ProgressiveAo, CancelsAndReportsProgress) {
    const WallScene s;
    const AoReference tracer({&s.mesh});
    ProgressiveAoOptions o;
    o.radius_mm = 10;
    ProgressiveAo ao(tracer, s.cam, s.W, s.H, o);
    std::atomic<bool> cancel{true};
    EXPECT_FALSE(ao.add_batch(&cancel));
    EXPECT_EQ(ao.stats().rays, 0u) << "nothing traced once cancelled";
    int calls = 0;
    EXPECT_THROW(ao.run([&](double f, std::string_view stage) {
        EXPECT_GE(f, 0.0);
        EXPECT_LE(f, 1.0);
        EXPECT_EQ(stage, "ray-traced AO");
        return ++calls < 3;
    }),
                 Cancelled);
    EXPECT_EQ(calls, 3);
    EXPECT_EQ(ao.stats().batches, 3);
    // Background (a view of nothing) is NaN and done at once.
    Camera away = s.cam;
    away.target = {0, 0, 200}; // looking up, away from everything
    ProgressiveAo none(tracer, away, 8, 8, o);
    EXPECT_TRUE(none.done());
    for (float v : none.image().floats) EXPECT_TRUE(std::isnan(v));
}

// With a jittered primary ray per batch the estimate is AO over the pixel's
// footprint: on the open floor still exactly 1, next to the wall close to
// the centre's value.
TEST(ProgressiveAo, JitteredPrimaryRaysAverageThePixel) {
    const WallScene s;
    const AoReference tracer({&s.mesh});
    ProgressiveAoOptions o = fixed_rays(1024);
    ProgressiveAo centre(tracer, s.cam, s.W, s.H, o);
    centre.run();
    o.batch_rays = 32;
    o.jitter = true;
    ProgressiveAo jittered(tracer, s.cam, s.W, s.H, o);
    jittered.run();
    const Image a = centre.image(), b = jittered.image();
    EXPECT_EQ(b.floats[0], 1.0f);
    EXPECT_LT(rmse(a, b), 0.05);
}
