// The Volume type itself: geometry checks, value ranges, affine helpers.
#include "io/volume.hpp"

#include <cmath>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "io/error.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;

TEST(Volume, DenseAllocatesZeroFilled) {
    auto v = Volume::dense({3, 4, 5}, VoxelType::I16, make_affine({0.5, 0.5, 2.0}, {10, 20, 30}));
    ASSERT_EQ(v.bytes().size(), 3u * 4u * 5u * 2u);
    for (auto x : v.as<std::int16_t>()) EXPECT_EQ(x, 0);
    EXPECT_EQ(v.linear_index(1, 2, 3), 1u + 3u * (2u + 4u * 3u));
    const auto w = v.index_to_world({2, 0, 1});
    EXPECT_DOUBLE_EQ(w.x, 11.0);
    EXPECT_DOUBLE_EQ(w.y, 20.0);
    EXPECT_DOUBLE_EQ(w.z, 32.0);
    EXPECT_DOUBLE_EQ(v.spacing().z, 2.0);
}

TEST(Volume, RangeSkipsNonFiniteAndCountsThem) {
    auto v = Volume::dense({2, 2, 1}, VoxelType::F32, glm::dmat4(1.0));
    auto s = v.as<float>();
    s[0] = -3.5f;
    s[1] = std::numeric_limits<float>::quiet_NaN();
    s[2] = std::numeric_limits<float>::infinity();
    s[3] = 7.0f;
    const auto r = v.value_range();
    EXPECT_EQ(r.min, -3.5);
    EXPECT_EQ(r.max, 7.0);
    EXPECT_EQ(r.nan_count, 1u);
    EXPECT_EQ(r.inf_count, 1u);
    warn_non_finite(v);
    ASSERT_EQ(v.meta.warnings.size(), 1u);
    EXPECT_NE(v.meta.warnings[0].find("1 NaN and 1 infinite"), std::string::npos);
}

TEST(Volume, SizeChecksNameTheFileAndReason) {
    try {
        checked_byte_size("big.nrrd", {1LL << 40, 1LL << 40, 1LL << 40}, VoxelType::F64);
        FAIL() << "overflow not detected";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), "big.nrrd");
        EXPECT_NE(e.reason().find("overflow"), std::string::npos) << e.what();
    }
    EXPECT_THROW(checked_byte_size("neg.nrrd", {4, -1, 4}, VoxelType::U8), Error);
    EXPECT_THROW(checked_byte_size("zero.nrrd", {4, 0, 4}, VoxelType::U8), Error);
    // Larger than the machine: 2^20 cubed bytes = 1 EiB.
    EXPECT_THROW(checked_byte_size("huge.nrrd", {1 << 20, 1 << 20, 1 << 20}, VoxelType::U8), Error);
}

TEST(Volume, AffineChecks) {
    EXPECT_NO_THROW(check_affine("ok", make_affine({1, 2, 3}, {0, 0, 0})));
    EXPECT_THROW(check_affine("zero", make_affine({1, 0, 3}, {0, 0, 0})), Error);
    glm::dmat3 skew(1.0);
    skew[1] = glm::normalize(glm::dvec3(0.2, 1.0, 0.0)); // j axis leans 11 degrees towards i
    EXPECT_THROW(check_affine("skew", make_affine({1, 1, 1}, {0, 0, 0}, skew)), Error);
    EXPECT_NO_THROW(check_affine("skew", make_affine({1, 1, 1}, {0, 0, 0}, skew), /*allow_shear=*/true));
    auto nan = make_affine({1, 1, 1}, {0, 0, 0});
    nan[3][0] = std::nan("");
    EXPECT_THROW(check_affine("nan", nan), Error);
    // A mirrored (negative determinant) but orthogonal frame is valid.
    EXPECT_NO_THROW(check_affine("mirror", make_affine({-1, 1, 1}, {0, 0, 0})));
}

TEST(Volume, RasToLpsNegatesXY) {
    const auto m = ras_to_lps(make_affine({1, 1, 1}, {5, 6, 7}));
    EXPECT_EQ(m[3][0], -5.0);
    EXPECT_EQ(m[3][1], -6.0);
    EXPECT_EQ(m[3][2], 7.0);
    EXPECT_EQ(m[0][0], -1.0);
    EXPECT_EQ(m[1][1], -1.0);
    EXPECT_EQ(m[2][2], 1.0);
}
