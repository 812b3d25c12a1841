// Labels in exported images are legible: the bundled head with its skin
// translucent and its bone opaque, the face's markups (landmarks, two lines,
// an angle) plus a point inside the skull, rendered through the core API,
// written as PNG and read back. For every label box the overlay reports,
// the WCAG 2.x contrast ratio between the text's pixels (where the label's
// glyph coverage is full) and the halo ring around them (full halo, no
// coverage), each the median relative luminance of those pixels as read
// from the written file, is at least 4.5:1 (AA for normal text); the text
// is at its own colour, also where the labelled point is hidden; and no
// two labels overlap. At 1200 x 980 and at 2x scale.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "io/image.hpp"
#include "io/markups.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/contrast.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using LabelContrast = test::GlTest;

namespace {

bool overlap(const LabelBox& a, const LabelBox& b) {
    return a.lo.x < b.hi.x && b.lo.x < a.hi.x && a.lo.y < b.hi.y && b.lo.y < a.hi.y;
}

// The head, skin (iso 500) at 35 % opacity over opaque bone (iso 1150), the face's markups and a point inside the
// skull, rendered and written to `png`; returns what render_image reported, the image read back from the file.
std::pair<core::RenderOutput, Image> render_head(int w, int h, float scale, const std::string& png) {
    core::Scene scene;
    scene.open(test::data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    scene.info(ids[0]).opacity = 0.35f;
    core::RenderRequest req;
    req.width = w;
    req.height = h;
    req.scale = scale;
    req.markups = load_markups(test::data("markups/headsq-face.mrk.json")).markups;
    Markup inside;
    inside.type = MarkupType::Fiducial;
    MarkupControlPoint c;
    c.position = scene.bounds().center();
    c.label = "centre \xC2\xB1 2 \xC2\xB5m, \xC3\xA9t\xC3\xA9";
    inside.points.push_back(c);
    req.markups.push_back(inside);
    core::RenderOutput out = core::render_image(scene, req);
    save_image(out.image, png, out.meta);
    return {std::move(out), load_image(png)};
}

void expect_legible(const core::RenderOutput& out, const Image& img) {
    ASSERT_EQ(img.width, out.image.width);
    // Letters (4), scale bar, 3 landmarks, 2 lines, the angle, the point inside, the legend's 2 rows.
    ASSERT_EQ(out.labels.size(), 4u + 1u + 3u + 2u + 1u + 1u + 2u);
    double worst = 1e9;
    for (std::size_t i = 0; i < out.labels.size(); ++i) {
        const LabelBox& l = out.labels[i];
        const test::Measured m = test::measure_label(img, l);
        std::printf("%-34s %4d,%4d %s text L %.3f ring L %.3f (%zu, %zu px) contrast %.2f:1\n", l.text.c_str(), l.lo.x,
                    l.lo.y, l.moved ? "moved" : "     ", m.text_l, m.ring_l, m.text, m.ring, m.ratio);
        EXPECT_GE(m.text, 6u) << l.text << ": bold stems have pixels at full coverage";
        EXPECT_GE(m.ring, 20u) << l.text;
        EXPECT_GE(m.ratio, 4.5) << l.text << " (WCAG AA)";
        worst = std::min(worst, m.ratio);
        // Full contrast: the text at its own colour (also where its point is hidden), 2 levels for rounding.
        const glm::ivec3 want = glm::ivec3(glm::round(l.color * 255.0f));
        EXPECT_NEAR(m.text_colour.r, want.r, 2) << l.text;
        EXPECT_NEAR(m.text_colour.g, want.g, 2) << l.text;
        EXPECT_NEAR(m.text_colour.b, want.b, 2) << l.text;
        for (std::size_t k = 0; k < i; ++k)
            EXPECT_FALSE(overlap(l, out.labels[k])) << "'" << l.text << "' and '" << out.labels[k].text << "'";
    }
    std::printf("lowest contrast %.2f:1\n", worst);
}

} // namespace

TEST_F(LabelContrast, ExportAt1200x980) {
    test::TempDir dir;
    const auto [out, img] = render_head(1200, 980, 1.0f, dir / "head.png");
    expect_legible(out, img);
}

TEST_F(LabelContrast, ExportAtScaleTwo) {
    test::TempDir dir;
    const auto [out, img] = render_head(800, 640, 2.0f, dir / "head2.png");
    expect_legible(out, img);
    // The text is twice the size: the scale bar's label box against the one at scale 1.
    const auto one = render_head(400, 320, 1.0f, dir / "head1.png");
    const auto& a = out.labels[4];
    const auto& b = one.first.labels[4];
    ASSERT_TRUE(a.fixed && b.fixed);
    EXPECT_NEAR(double(a.hi.y - a.lo.y) / double(b.hi.y - b.lo.y), 2.0, 0.15);
}
