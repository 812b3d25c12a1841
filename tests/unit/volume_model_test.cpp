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
    const std::vector<double> mins = {0, 50, 150, 250}, maxs = {50, 100, 180, 300};
    EXPECT_EQ(occupied_chunks(l, mins, maxs), (std::vector<unsigned char>{0, 0, 1, 1}));
    l.mode = VolumeMode::Mip; // every sample counts for the extreme
    EXPECT_EQ(occupied_chunks(l, mins, maxs), (std::vector<unsigned char>{1, 1, 1, 1}));
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
