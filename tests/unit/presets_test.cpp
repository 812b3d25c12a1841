// The one preset rule (renderer/core/presets.hpp) that the Surfaces and
// Volume panels share: which volumes CT's presets fit (by modality, or by
// HU-like values when the file names none; never MR), Otsu's thresholds
// against a brute force over the samples themselves, the iso presets each
// kind of volume gets, and the initial transfer function spanning a
// non-CT volume's own values (an MR of 0-563 got an axis of 0-3071).
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "renderer/core/presets.hpp"
#include "renderer/core/scene.hpp"

using namespace iso;

namespace {

// A 24^3 volume whose values run from `lo` to `hi` (a ramp along x, a few
// voxels at each end), tagged with `modality`.
std::unique_ptr<core::Scene> ramp(double lo, double hi, const std::string& modality) {
    Volume v = Volume::dense({24, 24, 24}, VoxelType::F32, glm::dmat4(1.0));
    auto s = v.as<float>();
    for (std::int64_t k = 0; k < 24; ++k)
        for (std::int64_t j = 0; j < 24; ++j)
            for (std::int64_t i = 0; i < 24; ++i) s[v.linear_index(i, j, k)] = float(lo + (hi - lo) * double(i) / 23.0);
    v.meta.modality = modality;
    auto scene = std::make_unique<core::Scene>();
    scene->set_volume(std::move(v), "ramp");
    return scene;
}

// Within-class variance of splitting `x` at `t` (below / at or above): what Otsu minimises.
double within(const std::vector<double>& x, double t) {
    double n[2] = {0, 0}, s[2] = {0, 0}, q[2] = {0, 0};
    for (double v : x) {
        const int c = v >= t;
        n[c] += 1;
        s[c] += v;
        q[c] += v * v;
    }
    double w = 0;
    for (int c = 0; c < 2; ++c)
        if (n[c] > 0) w += q[c] - s[c] * s[c] / n[c];
    return w;
}

} // namespace

TEST(Presets, CtPresetsFitCtByModalityOrHuLikeValuesButNeverMr) {
    EXPECT_TRUE(core::ct_in_hu(*ramp(-1024, 3071, "CT")));
    EXPECT_TRUE(core::ct_in_hu(*ramp(0, 4095, "CT"))) << "the modality says CT: its values are HU";
    EXPECT_TRUE(core::ct_in_hu(*ramp(-1024, 3071, ""))) << "a CT angiogram NIfTI: no modality, HU-like values";
    EXPECT_TRUE(core::ct_in_hu(*ramp(-1000, 1500, "")));
    EXPECT_FALSE(core::ct_in_hu(*ramp(-1024, 3071, "MR"))) << "an MR is no CT whatever its values";
    EXPECT_FALSE(core::ct_in_hu(*ramp(0, 563, ""))) << "no air at -1000: not HU";
    EXPECT_FALSE(core::ct_in_hu(*ramp(-3000, 3000, "")));
    EXPECT_FALSE(core::ct_in_hu(*ramp(-1024, 12000, "")));
    EXPECT_FALSE(core::ct_in_hu(core::Scene{}));
}

TEST(Presets, OtsuThresholdsAreTheBruteForceOverTheSamples) {
    // Two classes: two Gaussians, 1:3, at 100 and 600.
    std::mt19937 rng(7);
    std::normal_distribution<double> a(100, 40), b(600, 60);
    std::vector<double> x;
    for (int i = 0; i < 4000; ++i) x.push_back(a(rng));
    for (int i = 0; i < 12000; ++i) x.push_back(b(rng));
    const double lo = *std::min_element(x.begin(), x.end()), hi = *std::max_element(x.begin(), x.end());
    const int bins = 256;
    std::vector<double> counts(bins, 0.0);
    for (double v : x) counts[std::size_t(std::min(bins - 1, int((v - lo) / (hi - lo) * bins)))] += 1;
    const auto t = core::otsu_thresholds(counts, lo, hi, 2);
    ASSERT_EQ(t.size(), 1u);
    // The brute force over the bin edges, on the samples themselves.
    double best = std::numeric_limits<double>::infinity(), best_t = 0;
    for (int e = 1; e < bins; ++e) {
        const double edge = lo + (hi - lo) * e / bins;
        if (const double w = within(x, edge); w < best) best = w, best_t = edge;
    }
    EXPECT_NEAR(t[0], best_t, 2 * (hi - lo) / bins) << "within two bins of the samples' optimum";
    EXPECT_GT(t[0], 100 + 40) << "between the modes (Otsu leans towards the smaller class)";
    EXPECT_LT(t[0], 600 - 60);
    // Three classes: the thresholds fall between the three modes.
    std::normal_distribution<double> c(1200, 50);
    for (int i = 0; i < 3000; ++i) x.push_back(c(rng));
    const double hi3 = *std::max_element(x.begin(), x.end());
    std::vector<double> counts3(bins, 0.0);
    for (double v : x) counts3[std::size_t(std::min(bins - 1, int((v - lo) / (hi3 - lo) * bins)))] += 1;
    const auto t3 = core::otsu_thresholds(counts3, lo, hi3, 3);
    ASSERT_EQ(t3.size(), 2u);
    EXPECT_GT(t3[0], 200);
    EXPECT_LT(t3[0], 500);
    EXPECT_GT(t3[1], 750);
    EXPECT_LT(t3[1], 1050);
    EXPECT_TRUE(core::otsu_thresholds({}, 0, 1, 2).empty());
    EXPECT_TRUE(core::otsu_thresholds(std::vector<double>(8, 0.0), 0, 1, 2).empty()) << "no samples";
}

TEST(Presets, IsoPresetsForCtAndForOtherVolumes) {
    // CT: bone first and chosen, the others in range enabled; none named after a dataset.
    const auto ct = core::iso_presets(*ramp(-1024, 3071, ""));
    ASSERT_EQ(ct.size(), 4u);
    EXPECT_EQ(ct[0].name, "bone");
    for (const auto& p : ct) {
        EXPECT_TRUE(p.hu);
        EXPECT_TRUE(p.enabled) << p.name;
    }
    // Not CT (an MR of 0 to 563): its own thresholds first, enabled and
    // within its values; the CT presets listed but disabled, saying why.
    const auto mr = core::iso_presets(*ramp(0, 563, "MR"));
    ASSERT_EQ(mr.size(), 6u);
    for (int i = 0; i < 2; ++i) {
        EXPECT_FALSE(mr[std::size_t(i)].hu);
        EXPECT_TRUE(mr[std::size_t(i)].enabled);
        EXPECT_GT(mr[std::size_t(i)].value, 0.0);
        EXPECT_LT(mr[std::size_t(i)].value, 563.0);
    }
    EXPECT_LT(mr[0].value, mr[1].value) << "foreground, then the bright structures above it";
    for (std::size_t i = 2; i < mr.size(); ++i) {
        EXPECT_TRUE(mr[i].hu);
        EXPECT_FALSE(mr[i].enabled);
        EXPECT_NE(mr[i].why_not.find("Hounsfield"), std::string::npos);
    }
    for (const auto& p : mr) EXPECT_EQ(p.name.find("headsq"), std::string::npos);
    EXPECT_TRUE(core::iso_presets(core::Scene{}).empty());
}

TEST(Presets, TheInitialTransferFunctionSpansAVolumesOwnValues) {
    const TransferFunction mr = core::initial_transfer_function(*ramp(0, 563, "MR"));
    ASSERT_FALSE(mr.points().empty());
    EXPECT_DOUBLE_EQ(mr.points().front().value, 0.0);
    EXPECT_DOUBLE_EQ(mr.points().back().value, 563.0);
    EXPECT_EQ(core::initial_transfer_function(*ramp(-1024, 3071, "")), transfer_function_from("bone"));
}
