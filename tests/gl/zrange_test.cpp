// shaders/ao/zrange.comp read back exactly (pass_harness.hpp): the nearest
// and farthest linear depth of a hand-made 5x3 reversed-Z depth image with
// background texels, against values derived by hand from the camera's
// projection (renderer/frame/camera.cpp), bit for bit.
//
// Planes n = 1, f = 17. The projection (glm::perspectiveRH_ZO with far and
// near swapped) gives a point at linear depth z the depth
//     d = n (f - z) / (z (f - n)),   so   z = n f / (d (f - n) + n) = 17 / (16 d + 1),
// which is Camera::linear_depth and the shader's formula. With d = (2^k - 1) / 16
// the denominator is 2^k and every step is exact in float: 16 d + 1 is exact,
// and dividing 17 by a power of two is exact whether the GPU divides
// correctly rounded or multiplies by a reciprocal (1/2^k is exact too):
//     d = 1/16 -> z = 8.5     (0x41080000)     d = 3/16  -> z = 4.25   (0x40880000)
//     d = 7/16 -> z = 2.125   (0x40080000)     d = 15/16 -> z = 1.0625 (0x3F880000)
// Other texels (d = 1/4 -> 3.4, 5/16 -> 17/6) lie strictly between and round
// however they round; d = 0 is background and must be skipped.
#include <bit>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "pass_harness.hpp"
#include "renderer/passes/std140.hpp"
#include "renderer/frame/camera.hpp"

using namespace iso;
using ZRange = test::GlTest;

namespace {

constexpr float kNear = 1.0f, kFar = 17.0f;

// The 5x3 depth image, row y = 0 first. Column 4 holds the global extremes
// (d = 1/16, the farthest, and 15/16, the nearest); columns 0..3 alone range
// from 7/16 (2.125) to 3/16 (4.25).
const std::vector<float> kDepth = {
    0.0f,      7 / 16.0f, 0.25f,     0.0f,      1 / 16.0f, //
    3 / 16.0f, 0.0f,      5 / 16.0f, 0.25f,     0.0f,      //
    0.0f,      0.25f,     0.0f,      7 / 16.0f, 15 / 16.0f,
};

struct Range {
    std::uint32_t min_bits = 0, max_bits = 0;
};

std::uint32_t bits(float x) { return std::bit_cast<std::uint32_t>(x); }

// One dispatch over the whole texture (so texels beyond `size` are visited
// and must be skipped), the buffer initialised as the z-range pass does.
Range run_zrange(const gl::Texture& depth, glm::ivec2 size) {
    test::ComputePass pass({"ao/zrange.comp"});
    pass.texture(0, depth).storage<std::uint32_t>(0, {0x7F800000u, 0u}).params(passes::ZRangeParams{size, kNear, kFar});
    pass.dispatch(GLuint(depth.width() + 15) / 16, GLuint(depth.height() + 15) / 16);
    const auto out = pass.read<std::uint32_t>(0);
    EXPECT_EQ(out.size(), 2u);
    return out.size() == 2 ? Range{out[0], out[1]} : Range{};
}

} // namespace

TEST_F(ZRange, HandDerivedDepthsMatchTheCameraProjection) {
    // The (d, z) pairs above, through the camera's own matrices, in double:
    // every value is a short dyadic fraction, so the equalities are exact.
    Camera cam;
    cam.near_plane = kNear;
    cam.far_plane = kFar;
    const glm::dmat4 proj = cam.projection(5.0 / 3.0);
    const std::pair<double, double> pairs[] = {
        {1 / 16.0, 8.5}, {3 / 16.0, 4.25}, {7 / 16.0, 2.125}, {15 / 16.0, 1.0625}};
    for (const auto& [d, z] : pairs) {
        const glm::dvec4 clip = proj * glm::dvec4(0.3, -0.2, -z, 1.0); // eye space looks down -z
        EXPECT_EQ(clip.z / clip.w, d) << "z " << z;
        EXPECT_EQ(cam.linear_depth(d), z) << "d " << d;
    }
    EXPECT_EQ(cam.linear_depth(1.0), 1.0) << "d = 1 is the near plane";
}

TEST_F(ZRange, MinAndMaxLinearDepthAreExact) {
    const auto depth = test::texture_2d(GL_DEPTH_COMPONENT32F, 5, 3, GL_DEPTH_COMPONENT, GL_FLOAT, kDepth);
    // The texture holds the depths unchanged (32-bit float storage).
    const auto stored = test::read_texture<float>(depth, GL_DEPTH_COMPONENT, GL_FLOAT);
    ASSERT_EQ(stored.size(), kDepth.size());
    for (std::size_t i = 0; i < kDepth.size(); ++i) ASSERT_EQ(bits(stored[i]), bits(kDepth[i])) << "texel " << i;

    const Range all = run_zrange(depth, {5, 3});
    EXPECT_EQ(all.min_bits, 0x3F880000u) << std::bit_cast<float>(all.min_bits) << " (expected 1.0625)";
    EXPECT_EQ(all.max_bits, 0x41080000u) << std::bit_cast<float>(all.max_bits) << " (expected 8.5)";
    EXPECT_EQ(bits(1.0625f), 0x3F880000u);
    EXPECT_EQ(bits(8.5f), 0x41080000u);

    // `size` 4x3 leaves out column 4 and its extremes.
    const Range inner = run_zrange(depth, {4, 3});
    EXPECT_EQ(inner.min_bits, 0x40080000u) << std::bit_cast<float>(inner.min_bits) << " (expected 2.125)";
    EXPECT_EQ(inner.max_bits, 0x40880000u) << std::bit_cast<float>(inner.max_bits) << " (expected 4.25)";
    EXPECT_EQ(bits(2.125f), 0x40080000u);
    EXPECT_EQ(bits(4.25f), 0x40880000u);

    // Only background (texel 0,0): the buffer keeps its initial +inf and 0.
    const Range none = run_zrange(depth, {1, 1});
    EXPECT_EQ(none.min_bits, 0x7F800000u);
    EXPECT_EQ(none.max_bits, 0u);
}

TEST_F(ZRange, WorkgroupsMergeThroughTheGlobalAtomics) {
    // The same texels spread over two 16x16 workgroups: columns 0..3 at
    // x = 0..3 (first workgroup), column 4 at x = 20 (second), background
    // elsewhere. The global min/max must merge both groups' results.
    const int w = 32, h = 3;
    std::vector<float> texels(std::size_t(w * h), 0.0f);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < 4; ++x) texels[std::size_t(y * w + x)] = kDepth[std::size_t(y * 5 + x)];
        texels[std::size_t(y * w + 20)] = kDepth[std::size_t(y * 5 + 4)];
    }
    const auto depth = test::texture_2d(GL_DEPTH_COMPONENT32F, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, texels);
    const Range both = run_zrange(depth, {w, h});
    EXPECT_EQ(both.min_bits, 0x3F880000u) << std::bit_cast<float>(both.min_bits);
    EXPECT_EQ(both.max_bits, 0x41080000u) << std::bit_cast<float>(both.max_bits);
    // The first workgroup alone (size 16 wide): the second group's extremes are out.
    const Range first = run_zrange(depth, {16, h});
    EXPECT_EQ(first.min_bits, 0x40080000u) << std::bit_cast<float>(first.min_bits);
    EXPECT_EQ(first.max_bits, 0x40880000u) << std::bit_cast<float>(first.max_bits);
}
