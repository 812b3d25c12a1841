// The anterior view of the bundled head CT shows the face upright, read from
// the depth AOV rather than a screenshot: the nearest skin pixel (the nose)
// lies below the row of the eyes and above the row of the chin, and the
// patient's right eye is on the image's left (an anterior view shows the
// patient facing the viewer). The landmarks are the reader-placed ones of
// tests/unit/orientation_landmarks.hpp, projected with the camera the render
// used; the nose comes from the image alone.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "tests/support/orientation_landmarks.hpp"
#include "renderer/core/api.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
// core::render_input() renders in this process, on its own context: the
// fixture checks it for GL errors too.
using BundledHeadImage = test::GlTest;

namespace {

struct Pixel {
    double x, y; // image columns from the left, rows from the top
};

Pixel project(const core::RenderOutput& out, const glm::dvec3& p) {
    const int w = out.image.width, h = out.image.height;
    const glm::dvec4 c = out.camera.projection(double(w) / h) * out.camera.view() * glm::dvec4(p, 1.0);
    const glm::dvec2 ndc = glm::dvec2(c) / c.w;
    return {(ndc.x * 0.5 + 0.5) * w, (0.5 - ndc.y * 0.5) * h};
}

} // namespace

TEST_F(BundledHeadImage, AnteriorViewHasTheFaceUpright) {
    core::RenderRequest req;
    req.isos = {500.0};
    req.view = "anterior";
    req.width = 256;
    req.height = 256;
    req.aov = Aov::Depth;
    req.annotations = false;
    const auto out = core::render_input(test::data("headsq.nhdr"), req);
    const Image& d = out.image;
    ASSERT_TRUE(d.is_float);
    ASSERT_EQ(d.channels, 1);

    // The nose: the centroid of the pixels within 1 mm of the nearest one in
    // the depth AOV (linear eye depth; the background is +inf).
    float nearest = std::numeric_limits<float>::infinity();
    std::size_t covered = 0;
    for (const float z : d.floats)
        if (std::isfinite(z)) ++covered, nearest = std::min(nearest, z);
    Pixel nose{0, 0};
    int n = 0;
    for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x)
            if (d.floats[std::size_t(y) * d.width + x] <= nearest + 1.0f) nose.x += x + 0.5, nose.y += y + 0.5, ++n;
    nose.x /= n;
    nose.y /= n;
    ASSERT_GT(covered, std::size_t(d.width * d.height / 10)) << "the head covers too little of the image";

    const test::HeadLandmarks lm = test::head_landmarks(core::open_volume(test::data("headsq.nhdr")).index_to_lps);
    const Pixel le = project(out, lm.left_eye), re = project(out, lm.right_eye), chin = project(out, lm.chin);
    SCOPED_TRACE("nose (" + std::to_string(nose.x) + ", " + std::to_string(nose.y) + "), eyes rows " +
                 std::to_string(re.y) + " / " + std::to_string(le.y) + ", chin row " + std::to_string(chin.y));
    std::printf("nose pixel (%.0f, %.0f); eye rows %.1f / %.1f; chin row %.1f\n", nose.x, nose.y, re.y, le.y, chin.y);
    // Landmarks fall on the head (the projection is the render's own).
    for (const Pixel& p : {le, re, chin}) {
        ASSERT_TRUE(p.x >= 0 && p.x < d.width && p.y >= 0 && p.y < d.height);
        EXPECT_TRUE(std::isfinite(d.floats[std::size_t(p.y) * d.width + std::size_t(p.x)]));
    }
    // Upright: eyes above the nose, the nose above the chin (rows grow downwards).
    EXPECT_LT(0.5 * (le.y + re.y), nose.y - 2.0);
    EXPECT_LT(nose.y, chin.y - 10.0);
    // The nose is between the eyes; the patient's right eye is on the image's left.
    EXPECT_GT(nose.x, re.x);
    EXPECT_LT(nose.x, le.x);
    // The nose is nearer than the eyes and the chin in the depth AOV too.
    const auto depth_at = [&](const Pixel& p) { return d.floats[std::size_t(p.y) * d.width + std::size_t(p.x)]; };
    EXPECT_LT(nearest, depth_at(le) - 5.0f);
    EXPECT_LT(nearest, depth_at(re) - 5.0f);
    EXPECT_LT(nearest, depth_at(chin) - 5.0f);
}
