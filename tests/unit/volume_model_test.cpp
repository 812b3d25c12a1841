// Volume rendering's model on the CPU (renderer/volume): transfer functions
// (parsing, errors that name the point, interpolation in linear light,
// constant beyond the ends, steps), presets, clips, which chunks a transfer
// function leaves empty, and the reference march against closed forms:
// constant slabs whatever the step, the 0.5 crossing, surfaces between
// volume pieces, MIP/MinIP sampling with the ends included, clip planes.
#include <cmath>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "io/color.hpp"
#include "io/error.hpp"
#include "renderer/volume/preintegration.hpp"
#include "renderer/volume/reference.hpp"
#include "renderer/volume/transfer_function.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::error_of;

namespace {

// A dims^3 float volume of one value, spacing s, origin 0.
Volume constant_volume(int n, float value, double s = 1.0) {
    glm::dmat4 m(1.0);
    m[0][0] = m[1][1] = m[2][2] = s;
    Volume v = Volume::dense({n, n, n}, VoxelType::F32, m);
    for (auto& x : v.as<float>()) x = value;
    return v;
}

VolumeLook flat_look(const std::string& tf) {
    VolumeLook l;
    l.enabled = true;
    l.tf = TransferFunction::parse(tf);
    l.shading = false;
    return l;
}

} // namespace

TEST(TransferFunction, ParsesPrintsAndRoundTrips) {
    const auto tf = TransferFunction::parse("100:0:#000000, 300:0.25:#ff8000,300:0.5:#ffffff");
    ASSERT_EQ(tf.points().size(), 3u);
    EXPECT_EQ(tf.points()[1].value, 300);
    EXPECT_EQ(tf.points()[1].opacity, 0.25);
    EXPECT_EQ(tf.text(), "100:0:#000000,300:0.25:#ff8000,300:0.5:#ffffff");
    EXPECT_EQ(TransferFunction::parse(tf.text()), tf);
    const auto fine = TransferFunction::parse("0.1:0.3:#010203");
    EXPECT_EQ(TransferFunction::parse(fine.text()).points()[0].value, 0.1);
}

TEST(TransferFunction, ErrorsNameThePointAndTheReason) {
    EXPECT_NE(error_of([] { TransferFunction::parse("100:0"); }).find("is not value:opacity:#rrggbb"),
              std::string::npos);
    EXPECT_NE(error_of([] { TransferFunction::parse("200:0:#000000,100:1:#ffffff"); }).find("point 2"),
              std::string::npos);
    EXPECT_NE(error_of([] { TransferFunction::parse("1:1.5:#ffffff"); }).find("opacity per mm must be in 0..1"),
              std::string::npos);
    EXPECT_NE(error_of([] { TransferFunction::parse("1:1:#fffff"); }).find("point 1"), std::string::npos);
    EXPECT_NE(error_of([] { TransferFunction::parse("abc:1:#ffffff"); }).find("'abc' is not a finite number"),
              std::string::npos);
    EXPECT_NE(error_of([] { TransferFunction::parse("nan:1:#ffffff"); }).find("not a finite number"),
              std::string::npos);
    EXPECT_NE(error_of([] { TransferFunction::parse(""); }).find("transfer function"), std::string::npos);
    EXPECT_NE(error_of([] { transfer_function_from("bones"); }).find("bone, vessels, skin, soft tissue"),
              std::string::npos);
}

TEST(TransferFunction, InterpolatesInLinearLightAndIsConstantBeyondTheEnds) {
    const auto tf = TransferFunction::parse("0:0:#000000,100:0.5:#ffffff");
    const glm::dvec4 mid = tf.at(50);
    EXPECT_DOUBLE_EQ(mid.a, 0.25);
    EXPECT_NEAR(mid.r, 0.5, 1e-7); // linear light: half of white, not sRGB 0.5 (0.214 linear)
    EXPECT_EQ(tf.at(-1e9), tf.at(0));
    EXPECT_EQ(tf.at(1e9), tf.at(100));
    EXPECT_DOUBLE_EQ(tf.at(1e9).a, 0.5);
    // A step: below the shared value the first point's side, at and above it the second's.
    const auto step = TransferFunction::parse("0:0:#000000,10:0:#000000,10:1:#ffffff,20:1:#ffffff");
    EXPECT_EQ(step.at(9.999).a, 0.0);
    EXPECT_EQ(step.at(10).a, 1.0);
    EXPECT_EQ(step.max_opacity(0, 9.5), 0.0);
    EXPECT_EQ(step.max_opacity(0, 10), 1.0);
    // The largest opacity over a range includes points inside it.
    const auto peak = TransferFunction::parse("0:0:#000000,50:0.8:#ffffff,100:0:#000000");
    EXPECT_DOUBLE_EQ(peak.max_opacity(10, 90), 0.8);
    EXPECT_DOUBLE_EQ(peak.max_opacity(0, 25), 0.4);
    EXPECT_DOUBLE_EQ(peak.max_opacity(100, 200), 0.0);
}

TEST(TransferFunction, PresetsParseAndModesName) {
    for (const auto& name : transfer_function_presets()) EXPECT_FALSE(transfer_function_from(name).empty()) << name;
    EXPECT_EQ(transfer_function_presets().size(), 4u);
    for (auto m : {VolumeMode::Composite, VolumeMode::Mip, VolumeMode::Minip})
        EXPECT_EQ(volume_mode_from_name(volume_mode_name(m)), m);
    EXPECT_NE(error_of([] { volume_mode_from_name("max"); }).find("composite, mip or minip"), std::string::npos);
}

TEST(Clip, ParsesKeepsAndPrints) {
    Clip c;
    c.add("box=-10,-20,-30,10,20,30");
    c.add("plane=0,0,5,0,0,-2"); // keeps z <= 5
    EXPECT_TRUE(c.keeps({0, 0, 0}));
    EXPECT_FALSE(c.keeps({0, 0, 6}));
    EXPECT_FALSE(c.keeps({11, 0, 0}));
    EXPECT_EQ(c.half_spaces().size(), 7u);
    Clip again;
    for (std::size_t a = 0, b; a < c.text().size(); a = b + 2) {
        b = c.text().find("; ", a);
        if (b == std::string::npos) b = c.text().size();
        again.add(c.text().substr(a, b - a));
    }
    EXPECT_EQ(again, c);
    EXPECT_NE(error_of([&] { c.add("box=0,0,0,1,1,1"); }).find("only one clip box"), std::string::npos);
    EXPECT_NE(error_of([] { Clip().add("box=1,0,0,0,1,1"); }).find("minimum must be below"), std::string::npos);
    EXPECT_NE(error_of([] { Clip().add("plane=0,0,0,0,0,0"); }).find("no length"), std::string::npos);
    EXPECT_NE(error_of([] { Clip().add("sphere=1"); }).find("neither box="), std::string::npos);
}

TEST(VolumeModel, OccupiedChunksFollowTheTransferFunction) {
    VolumeLook l = flat_look("100:0:#000000,200:1:#ffffff");
    // A chunk reaching within a texel of the tables (100 / 4095) of the
    // ramp's start counts: the march reads the tables interpolated.
    const std::vector<double> mins = {0, 50, 50, 150, 250}, maxs = {50, 99.9, 100, 180, 300};
    EXPECT_EQ(occupied_chunks(l, mins, maxs), (std::vector<unsigned char>{0, 0, 1, 1, 1}));
    l.mode = VolumeMode::Mip; // every sample counts for the extreme
    EXPECT_EQ(occupied_chunks(l, mins, maxs), (std::vector<unsigned char>{1, 1, 1, 1, 1}));
}

TEST(VolumeModel, ConstantSlabMatchesTheClosedFormWhateverTheStep) {
    const Volume v = constant_volume(11, 100.0f, 1.0); // the box [0, 10] mm per axis
    const VolumeSampler s(v);
    for (double a : {0.02, 0.3, 0.9, 1.0})
        for (double step : {0.1, 0.5, 3.0, 50.0}) {
            char tf[64];
            std::snprintf(tf, sizeof tf, "0:%g:#ff8000", a);
            const VolumeLook look = flat_look(tf);
            // Along z through the box: 10 mm of path.
            const RayResult r = march_ray(s, look, {}, {5, 5, -20}, {0, 0, 1}, 0, 1e9, {}, step);
            const double T = std::pow(1.0 - a, 10.0);
            EXPECT_NEAR(r.transmittance, T, 1e-12) << a << " " << step;
            const glm::dvec3 c = look.tf.at(100);
            EXPECT_NEAR(r.color.r, c.r * (1.0 - T), 1e-12);
            EXPECT_NEAR(r.color.g, c.g * (1.0 - T), 1e-12);
            // The 0.5 crossing: (1 - a)^x = 0.5 after the entry at z = 0.
            if (a < 1.0 && T < 0.5) {
                ASSERT_TRUE(r.t_half);
                EXPECT_NEAR(*r.t_half - 20.0, std::log(0.5) / std::log(1.0 - a), 1e-9) << a << " " << step;
            }
        }
}

TEST(VolumeModel, SurfacesComeBetweenThePiecesInDepthOrder) {
    const Volume v = constant_volume(11, 100.0f);
    const VolumeSampler s(v);
    const VolumeLook look = flat_look("0:0.2:#ffffff");
    const glm::dvec3 red(1, 0, 0), blue(0, 0, 1);
    // A translucent plane halfway (t = 25: z = 5) and an opaque one at z = 8.
    const std::vector<RayLayer> layers = {{28, blue, 1.0}, {25, red, 0.5}};
    const RayResult r = march_ray(s, look, {}, {5, 5, -20}, {0, 0, 1}, 0, 1e9, layers, 0.5);
    const double T5 = std::pow(0.8, 5.0), T3 = std::pow(0.8, 3.0);
    const double white = 1 - T5 + T5 * 0.5 * (1 - T3), red_part = T5 * 0.5, blue_part = T5 * 0.5 * T3;
    EXPECT_NEAR(r.color.r, white + red_part, 1e-12);
    EXPECT_NEAR(r.color.g, white, 1e-12);
    EXPECT_NEAR(r.color.b, white + blue_part, 1e-12);
    EXPECT_NEAR(r.transmittance, 0.0, 1e-15); // the opaque plane ends the ray
}

TEST(VolumeModel, ClipPlanesAndNearFarCutTheRay) {
    const Volume v = constant_volume(11, 100.0f);
    const VolumeSampler s(v);
    const VolumeLook look = flat_look("0:0.1:#ffffff");
    Clip clip;
    clip.add("plane=0,0,4,0,0,-1"); // keeps z <= 4
    const RayResult r = march_ray(s, look, clip, {5, 5, -20}, {0, 0, 1}, 0, 1e9, {}, 0.5);
    EXPECT_NEAR(r.transmittance, std::pow(0.9, 4.0), 1e-12);
    // Far at t = 22 (z = 2): 2 mm.
    const RayResult f = march_ray(s, look, {}, {5, 5, -20}, {0, 0, 1}, 0, 22, {}, 0.5);
    EXPECT_NEAR(f.transmittance, std::pow(0.9, 2.0), 1e-12);
    // A ray beside the box, and one kept by no half-space.
    EXPECT_EQ(march_ray(s, look, {}, {15, 5, -20}, {0, 0, 1}, 0, 1e9, {}, 0.5).transmittance, 1.0);
    clip.add("plane=0,0,6,0,0,1"); // and z >= 6: nothing left
    EXPECT_EQ(march_ray(s, look, clip, {5, 5, -20}, {0, 0, 1}, 0, 1e9, {}, 0.5).samples, 0u);
}

TEST(VolumeModel, MipSamplesEveryVoxelOfAnAxisAlignedColumn) {
    glm::dmat4 m(1.0);
    Volume v = Volume::dense({3, 3, 9}, VoxelType::I16, m);
    auto data = v.as<std::int16_t>();
    for (std::size_t i = 0; i < data.size(); ++i) data[i] = std::int16_t((i * 37) % 101);
    const VolumeSampler s(v);
    VolumeLook look = flat_look("0:1:#000000,100:1:#ffffff");
    for (auto mode : {VolumeMode::Mip, VolumeMode::Minip}) {
        look.mode = mode;
        const RayResult r = march_ray(s, look, {}, {1, 1, -5}, {0, 0, 1}, 0, 1e9, {}, 1.0);
        double want = mode == VolumeMode::Mip ? -1e9 : 1e9;
        for (int k = 0; k < 9; ++k)
            want = mode == VolumeMode::Mip ? std::max(want, v.value(1, 1, k)) : std::min(want, v.value(1, 1, k));
        ASSERT_TRUE(r.extreme);
        EXPECT_EQ(*r.extreme, want);
        EXPECT_EQ(r.samples, 9u);
        EXPECT_NEAR(r.color.r, look.tf.at(want).r, 1e-12); // opacity 1: the extreme's colour
    }
}

TEST(VolumeModel, NanSamplesCountAsBelowEveryValue) {
    Volume v = constant_volume(4, 50.0f);
    v.as<float>()[0] = std::nanf("");
    const VolumeSampler s(v);
    EXPECT_LT(s.at_index({0, 0, 0}), 50.0);
    EXPECT_TRUE(std::isfinite(s.at_index({0.5, 0, 0})));
}

// Pre-integration (renderer/volume/preintegration.hpp): the tables against
// closed forms for a value varying linearly along a segment.
namespace {

// The optical depth of h mm whose value runs linearly from v0 to v1
// through a ramp of opacity 0 at value 0 to a1 at value 100 (constant
// beyond): h / (v1 - v0) times the integral of -ln(1 - a(v)) dv, in closed
// form, G(a) = (1 - a) ln(1 - a) + a per unit of opacity.
double ramp_depth(double v0, double v1, double a1, double h) {
    auto G = [](double a) { return (1.0 - a) * std::log1p(-a) + a; };
    auto P = [&](double v) { // integral from 0 to v
        if (v <= 0) return 0.0;
        const double x = std::min(v, 100.0);
        double p = 100.0 / a1 * G(a1 * x / 100.0);
        if (v > 100) p += (v - 100.0) * -std::log1p(-a1);
        return p;
    };
    return h * (P(v1) - P(v0)) / (v1 - v0);
}

} // namespace

TEST(Preintegration, ALinearValueThroughARampMatchesTheClosedForm) {
    for (double a1 : {0.05, 0.5, 0.95}) {
        char text[64];
        std::snprintf(text, sizeof text, "0:0:#ff8000,100:%g:#ff8000", a1);
        const TransferTables t(TransferFunction::parse(text));
        const glm::dvec3 c = TransferFunction::parse(text).at(50);
        // Within the ramp, across its start, across its end, both ways, and beyond it.
        const double cases[][2] = {{20, 80}, {-50, 30}, {70, 180}, {180, 70}, {-40, 160}, {120, 170}};
        for (const auto& v : cases)
            for (double h : {0.1, 1.0, 4.0}) {
                const SegmentLight s = t.segment(v[0], v[1], h);
                const double T = std::exp(-ramp_depth(v[0], v[1], a1, h));
                EXPECT_NEAR(s.transmittance, T, 1e-6 * std::max(T, 1e-3)) << a1 << " " << v[0] << ".." << v[1];
                // One colour: what is not transmitted is emitted in it.
                EXPECT_NEAR(s.color.r, c.r * (1.0 - T), 1e-6) << a1 << " " << v[0] << ".." << v[1];
                EXPECT_NEAR(s.color.b, c.b * (1.0 - T), 1e-6) << a1 << " " << v[0] << ".." << v[1];
            }
    }
}

TEST(Preintegration, AConstantValueIsTheSampledModel) {
    const TransferFunction tf = TransferFunction::parse("0:0:#2040ff,100:0.6:#ff8000,200:0.2:#ffffff");
    const TransferTables t(tf);
    for (double v : {-10.0, 37.0, 100.0, 150.5, 400.0})
        for (double h : {0.3, 2.0}) {
            const SegmentLight s = t.segment(v, v, h);
            const glm::dvec4 c = tf.at(v);
            const double T = std::pow(1.0 - c.a, h);
            // To the tables' resolution: at a point (100, 200) the texels
            // on either side of its kink are interpolated.
            EXPECT_NEAR(s.transmittance, T, 2e-4) << v;
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.color[k], c[k] * (1.0 - T), 5e-4) << v;
        }
}

TEST(Preintegration, AThinPeakBetweenTwoSamplesIsNotMissed) {
    // Opacity only over values 499..501: a segment from 0 to 1000 passes it
    // in 2/1000 of its length; sampling at its ends sees nothing.
    const TransferFunction tf = TransferFunction::parse("499:0:#ffffff,500:0.9:#ffffff,501:0:#ffffff");
    const TransferTables t(tf);
    const double h = 500.0; // mm: 1 mm of the segment inside the peak
    // The peak's integral: two ramps of 1 value each, 0 -> 0.9 -> 0.
    const double a = 0.9, ramp = ((1.0 - a) * std::log1p(-a) + a) / a; // per value, each side
    const double T = std::exp(-h / 1000.0 * 2.0 * ramp);
    EXPECT_NEAR(t.segment(0, 1000, h).transmittance, T, 1e-4);
    EXPECT_NEAR(t.segment(1000, 0, h).transmittance, T, 1e-4);
    EXPECT_EQ(tf.at(0).a + tf.at(1000).a, 0.0); // what the sampled march sees
}

TEST(Preintegration, VaryingColourIsWithinItsStatedBoundOfTheExactIntegral) {
    // Colour red -> white over an opacity ramp: the exact front-to-back
    // integral for a linear value (many sub-steps) against the two halves.
    const TransferFunction tf = TransferFunction::parse("0:0:#ff0000,100:0.8:#ffffff");
    const TransferTables t(tf);
    double worst = 0;
    for (double h : {0.5, 1.5, 4.0})
        for (const auto& v : {glm::dvec2(0, 100), glm::dvec2(100, 0), glm::dvec2(30, 90), glm::dvec2(-20, 140)}) {
            glm::dvec3 exact(0.0);
            double T = 1;
            const int n = 20000;
            for (int i = 0; i < n; ++i) {
                const glm::dvec4 c = tf.at(v[0] + (v[1] - v[0]) * (i + 0.5) / n);
                const double keep = std::pow(1.0 - c.a, h / n);
                exact += T * (1.0 - keep) * glm::dvec3(c);
                T *= keep;
            }
            const SegmentLight s = t.segment(v[0], v[1], h);
            EXPECT_NEAR(s.transmittance, T, 1e-5) << h << " " << v[0];
            double e = 0;
            for (int k = 0; k < 3; ++k) e = std::max(e, std::abs(s.color[k] - exact[k]));
            // Second order in a half's optical depth times its change of
            // colour (red to white here): 0.0025 at depths under 0.4,
            // 0.016 under 1.2 (a step of 1.5 mm), 0.061 at 2.4-3.1.
            const double depth = -std::log(T);
            EXPECT_LE(e, depth < 0.5 ? 0.003 : depth < 1.2 ? 0.02 : 0.07) << h << " " << v[0] << ".." << v[1];
            worst = std::max(worst, e);
        }
    std::printf("varying colour: largest error %.4f (linear light)\n", worst);
}

TEST(Preintegration, TheGpuTablesHoldTheIntegralsInFloat) {
    const TransferTables t(transfer_function_from("vessels"));
    ASSERT_EQ(t.integrals().size(), std::size_t(TransferTables::kTexels));
    const double w = t.width();
    for (int i : {0, 1, 100, 2000, 4095}) {
        const glm::dvec4 d = t.integral(t.lo() + i * w);
        const glm::vec4 f = t.integrals()[std::size_t(i)];
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(f[k], d[k], 1e-6 * std::max(1.0, std::abs(d[k]))) << i;
    }
    // Classification texels are the function at their values.
    EXPECT_NEAR(t.classification()[0].a, 0.0, 1e-7);
    EXPECT_NEAR(t.classify(170.0).a, 0.5, 1e-3);
    EXPECT_LT(t.clear_below(), 140.0);
    EXPECT_GT(t.clear_below(), 139.0);
    EXPECT_TRUE(std::isinf(t.clear_above())); // opaque up to the last point
}
