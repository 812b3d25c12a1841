// CPU side of cone-traced AO: cone directions, Poisson-disk columns, jitter
// sets, settings validation.
#include "renderer/ao/cone_pattern.hpp"

#include <cmath>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "io/error.hpp"

using namespace iso;

TEST(ConePattern, DirectionsAreUnitCosineWeightedAndCoverTheHemisphere) {
    for (int n : {1, 3, 6, 8, 16, 64}) {
        const auto d = cone_directions(n);
        ASSERT_EQ(int(d.size()), n);
        double mean_z = 0, mean_x = 0, mean_y = 0;
        for (const auto& c : d) {
            EXPECT_NEAR(glm::length(glm::vec3(c)), 1.0, 1e-5);
            EXPECT_GE(c.z, 0.0f);
            mean_x += c.x / n;
            mean_y += c.y / n;
            mean_z += c.z / n;
        }
        // Solid angles add up to the hemisphere: n * 2 pi (1 - cos a) = 2 pi.
        const double cos_a = std::sqrt(1.0 - double(d[0].w) * d[0].w);
        EXPECT_NEAR(n * (1.0 - cos_a), 1.0, 1e-5) << n;
        if (n >= 6) {
            // Cosine-weighted: E[z] = 2/3 for Malley directions; the sunflower is balanced around the normal.
            EXPECT_NEAR(mean_z, 2.0 / 3.0, 0.04) << n;
            EXPECT_NEAR(mean_x, 0.0, 0.08) << n;
            EXPECT_NEAR(mean_y, 0.0, 0.08) << n;
        }
    }
}

TEST(ConePattern, PoissonDiskPointsAreInsideAndApart) {
    for (int n : {1, 4, 8, 16, 32, 64}) {
        const auto p = poisson_disk(n, 7);
        ASSERT_EQ(int(p.size()), n);
        double min_d = 1e9;
        for (int i = 0; i < n; ++i) {
            EXPECT_LE(glm::length(p[i]), 1.0f);
            for (int j = 0; j < i; ++j) min_d = std::min(min_d, double(glm::length(p[i] - p[j])));
        }
        // The densest packing is ~2/sqrt(n) apart; dart throwing (and the concentric map) keep a third of it.
        if (n > 1) {
            EXPECT_GT(min_d, 0.66 / std::sqrt(double(n))) << n;
        }
        EXPECT_EQ(poisson_disk(n, 7), p) << "deterministic in the seed";
    }
}

TEST(ConePattern, PoissonDiskDensityIsUniformUpToTheRim) {
    // Over many sets, the fraction of points beyond radius sqrt(1/2) (half the area) is one half.
    int outer = 0, total = 0;
    for (std::uint32_t seed = 0; seed < 200; ++seed)
        for (const auto& p : poisson_disk(16, seed)) {
            outer += glm::dot(p, p) > 0.5f;
            ++total;
        }
    EXPECT_NEAR(double(outer) / total, 0.5, 0.03);
}

TEST(ConePattern, EachFrameGetsNewJitterSets) {
    ConeAoSettings s;
    const auto a = cone_pattern(s, 0), b = cone_pattern(s, 1);
    const std::size_t expected = std::size_t(s.cones + s.jitter_sets + s.jitter_sets * s.samples);
    ASSERT_EQ(a.size(), expected);
    ASSERT_EQ(b.size(), expected);
    for (int c = 0; c < s.cones; ++c) EXPECT_EQ(a[std::size_t(c)], b[std::size_t(c)]) << "cones stay";
    int differ = 0;
    for (std::size_t i = std::size_t(s.cones); i < a.size(); ++i) differ += a[i] != b[i];
    EXPECT_GT(differ, int(a.size() - std::size_t(s.cones)) * 9 / 10);
    for (int j = 0; j < s.jitter_sets; ++j) {
        const auto& set = a[std::size_t(s.cones + j)];
        EXPECT_NEAR(set.x * set.x + set.y * set.y, 1.0f, 1e-5f) << "a rotation";
        EXPECT_LE(std::abs(set.z), 0.5f);
    }
}

TEST(ConePattern, ValidationNamesTheSetting) {
    ConeAoSettings s;
    EXPECT_NO_THROW(validate(s));
    s.cones = 0;
    try {
        validate(s);
        FAIL();
    } catch (const Error& e) {
        // The core names the setting; the CLI turns it into --ao-cones (Cli tests).
        EXPECT_EQ(e.where(), "cone AO setting cones") << e.what();
    }
    s = {};
    s.radius_mm = std::nan("");
    EXPECT_THROW(validate(s), Error);
    s = {};
    s.layers = 9;
    EXPECT_THROW(validate(s), Error);
}
