// The overlay's markups on the CPU: the measurement text a Line or an Angle
// shows (the file's value, else computed from the points), the colours,
// which control points are drawn, what each vertex carries for the depth
// comparison, labels that are not ASCII, and the scale.
#include "renderer/frame/annotations.hpp"

#include <cmath>

#include <glm/glm.hpp>

#include "tests/support/test_util.hpp"

using namespace iso;

namespace {

MarkupControlPoint point(glm::dvec3 p, const std::string& label = "") {
    MarkupControlPoint c;
    c.position = p;
    c.label = label;
    return c;
}

Markup markup(MarkupType t, std::vector<glm::dvec3> ps) {
    Markup m;
    m.type = t;
    for (const auto& p : ps) m.points.push_back(point(p));
    return m;
}

// A camera looking at the origin from the front (anterior), 30 degrees vertical field.
Camera front_camera() {
    Camera c;
    c.eye = {0, -300, 0};
    c.target = {0, 0, 0};
    c.up = {0, 0, 1};
    c.near_plane = 100;
    c.far_plane = 500;
    return c;
}

Annotations markups_only(std::vector<Markup> ms) {
    Annotations a;
    a.scale_bar = a.orientation = false;
    a.markups = std::move(ms);
    return a;
}

} // namespace

TEST(Overlay, LineLengthIsTheFilesValueElseComputed) {
    Markup line = markup(MarkupType::Line, {{0, 0, 0}, {30, 40, 0}});
    EXPECT_EQ(markup_measurement_text(line), "50.0 mm") << "computed from the points";
    line.measurements.push_back({"length", 42.3, "mm"});
    EXPECT_EQ(markup_measurement_text(line), "42.3 mm") << "the file's value";
    line.measurements[0].units = "cm"; // not what is drawn: computed instead
    EXPECT_EQ(markup_measurement_text(line), "50.0 mm");
    line.measurements[0] = {"length", std::nullopt, "mm"}; // Slicer had none
    EXPECT_EQ(markup_measurement_text(line), "50.0 mm");
    line.points[1].status = PositionStatus::Undefined;
    EXPECT_EQ(markup_measurement_text(line), "") << "no value, nothing computed";
    line.measurements[0].value = 12.26;
    EXPECT_EQ(markup_measurement_text(line), "12.3 mm") << "the file's value still is one";
    // Slicer's own file: 80.4578... mm stored.
    const auto f = load_markups(test::data("markups/slicer-line-ras.mrk.json"));
    ASSERT_EQ(f.markups.size(), 1u);
    EXPECT_EQ(markup_measurement_text(f.markups[0]), "80.5 mm");
}

TEST(Overlay, AngleValueInDegreesWithTheDegreeSign) {
    const double a = glm::radians(87.5);
    Markup angle = markup(MarkupType::Angle, {{10, 0, 0}, {0, 0, 0}, {10 * std::cos(a), 0, 10 * std::sin(a)}});
    EXPECT_EQ(markup_measurement_text(angle), "87.5\xC2\xB0");
    angle.measurements.push_back({"angle", 91.04, "deg"});
    EXPECT_EQ(markup_measurement_text(angle), "91.0\xC2\xB0");
    Markup flat = markup(MarkupType::Angle, {{10, 0, 0}, {0, 0, 0}, {0, 0, 0}}); // a zero-length arm
    EXPECT_EQ(markup_measurement_text(flat), "");
    EXPECT_EQ(markup_measurement_text(markup(MarkupType::Fiducial, {{0, 0, 0}})), "");
}

TEST(Overlay, ColoursFollowSlicersSelection) {
    Markup m = markup(MarkupType::Fiducial, {{0, 0, 0}, {1, 0, 0}});
    m.points[1].selected = false;
    const glm::vec3 fallback = markup_color(m, 0);
    EXPECT_EQ(markup_color(m, 1), fallback) << "no colours in the file: the type's default";
    EXPECT_NE(markup_color(markup(MarkupType::Line, {}), -1), fallback) << "each type its own default";
    m.selected_color = glm::dvec3(0.1, 0.2, 0.3);
    m.color = glm::dvec3(0.4, 0.5, 0.6);
    EXPECT_EQ(markup_color(m, 0), glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_EQ(markup_color(m, 1), glm::vec3(0.4f, 0.5f, 0.6f));
    EXPECT_EQ(markup_color(m, -1), glm::vec3(0.1f, 0.2f, 0.3f)) << "lines: selected when a point is";
}

TEST(Overlay, OnlyDefinedVisiblePointsAreDrawnAndCarryTheirDepth) {
    const Camera cam = front_camera();
    Markup m = markup(MarkupType::Fiducial, {{0, 0, 0}, {10, 0, 0}, {-10, 0, 0}, {0, -250, 0}});
    m.points[1].status = PositionStatus::Undefined;
    m.points[2].visible = false;
    // m.points[3] is nearer than the near plane (50 mm from the eye): not drawn.
    const auto v = build_overlay(markups_only({m}), cam, 200, 100, 1.0f);
    ASSERT_FALSE(v.empty());
    for (const auto& x : v) {
        // One glyph: every vertex anchored at the origin's pixel (the image centre), 300 mm deep.
        EXPECT_NEAR(x.anchor.x, 100.0f, 1e-3f);
        EXPECT_NEAR(x.anchor.y, 50.0f, 1e-3f);
        EXPECT_NEAR(x.inv_depth, 1.0f / 300.0f, 1e-8f);
        EXPECT_LT(glm::length(x.pixel - glm::vec2(100, 50)), 10.0f);
    }
    // Nothing defined: nothing drawn, and no annotation either.
    m.points.resize(2);
    m.points[0].status = PositionStatus::Preview;
    EXPECT_TRUE(build_overlay(markups_only({m}), cam, 200, 100, 1.0f).empty());
}

TEST(Overlay, LineVerticesCarryTheirEndsDepthAndDashDistance) {
    const Camera cam = front_camera();
    // From 300 mm deep to 400 mm deep, across the image.
    const auto v =
        build_overlay(markups_only({markup(MarkupType::Line, {{-20, 0, 0}, {20, 100, 0}})}), cam, 200, 200, 1.0f);
    float max_along = 0;
    std::size_t line_vertices = 0;
    for (const auto& x : v) {
        if (x.anchor.x >= 0) continue; // glyphs and the label
        ++line_vertices;
        EXPECT_TRUE(std::abs(x.inv_depth - 1.0f / 300.0f) < 1e-7f || std::abs(x.inv_depth - 1.0f / 400.0f) < 1e-7f)
            << x.inv_depth;
        max_along = std::max(max_along, x.along);
    }
    EXPECT_EQ(line_vertices, 12u) << "outline and colour, two triangles each";
    // The ends' pixels: x = 100 + 100 * (x_mm / (depth tan 15deg)).
    const double t = std::tan(glm::radians(15.0));
    const double a = 100 - 100 * 20 / (300 * t), b = 100 + 100 * 20 / (400 * t);
    EXPECT_NEAR(max_along, b - a, 1e-3);
}

TEST(Overlay, LabelsThatAreNotAsciiAndTheScale) {
    const Camera cam = front_camera();
    Markup m = markup(MarkupType::Fiducial, {{0, 0, 0}});
    m.points[0].label = "Nasion \xC3\xBC \xE2\x86\x92 \x01"; // "ü", an arrow and a control character
    const auto a = build_overlay(markups_only({m}), cam, 200, 200, 1.0f);
    m.points[0].label = "Nasion ? ? ?";
    EXPECT_EQ(a.size(), build_overlay(markups_only({m}), cam, 200, 200, 1.0f).size()) << "one '?' per character";
    // Scale 2: the glyph's extent around its point doubles.
    m.points[0].label.clear();
    auto extent = [&](float s) {
        float e = 0;
        for (const auto& x : build_overlay(markups_only({m}), cam, 200, 200, s))
            e = std::max(e, glm::length(x.pixel - glm::vec2(100)));
        return e;
    };
    EXPECT_NEAR(extent(2.0f) / extent(1.0f), 2.0, 1e-5);
}

TEST(Overlay, TheHeadExampleShowsTheDocumentedValues) {
    // datasets/markups/headsq-face.mrk.json, as docs/markups.md and its README describe it; our writer keeps it.
    const auto f = load_markups(test::data("markups/headsq-face.mrk.json"));
    ASSERT_EQ(f.markups.size(), 4u);
    EXPECT_EQ(f.markups[0].points.size(), 3u);
    EXPECT_EQ(markup_measurement_text(f.markups[1]), "145.3 mm");
    EXPECT_EQ(markup_measurement_text(f.markups[2]), "46.8 mm");
    EXPECT_EQ(markup_measurement_text(f.markups[3]), "70.8\xC2\xB0");
    EXPECT_EQ(markup_color(f.markups[2], -1), glm::vec3(1.0f, 0.85f, 0.2f));
    test::TempDir dir;
    save_markups(f, dir / "copy.mrk.json");
    const auto g = load_markups(dir / "copy.mrk.json");
    ASSERT_EQ(g.markups.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(g.markups[i].name, f.markups[i].name);
        ASSERT_EQ(g.markups[i].points.size(), f.markups[i].points.size());
        for (std::size_t k = 0; k < f.markups[i].points.size(); ++k)
            EXPECT_EQ(g.markups[i].points[k].position, f.markups[i].points[k].position);
    }
}
