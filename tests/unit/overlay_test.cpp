// The overlay's markups on the CPU: the measurement text a Line or an Angle
// shows (the file's value, else computed from the points), the colours,
// which control points are drawn, what each vertex carries for the depth
// comparison, labels in Unicode at their size in points, never dimmed,
// placed apart with leader lines, and the scale; the markups' names in their
// labels; the legend, also of many surfaces (compacted, never dropped for that).
#include "renderer/frame/annotations.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <glm/glm.hpp>

#include "io/color.hpp"
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
    const auto v = build_overlay(markups_only({m}), cam, 200, 100, 1.0f).vertices;
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
    const Overlay none = build_overlay(markups_only({m}), cam, 200, 100, 1.0f);
    EXPECT_TRUE(none.vertices.empty());
    EXPECT_TRUE(none.labels.empty());
}

TEST(Overlay, LineVerticesCarryTheirEndsDepthAndDashDistance) {
    const Camera cam = front_camera();
    // From 300 mm deep to 400 mm deep, across the image.
    const auto v =
        build_overlay(markups_only({markup(MarkupType::Line, {{-20, 0, 0}, {20, 100, 0}})}), cam, 200, 200, 1.0f)
            .vertices;
    float max_along = 0;
    std::size_t line_vertices = 0;
    for (const auto& x : v) {
        if (x.anchor.x >= 0 || x.inv_depth == 0) continue; // glyphs; the label and its leader line (2D)
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

TEST(Overlay, LabelsAreUnicodeAtTheirSizeInPoints) {
    const Camera cam = front_camera();
    Markup m = markup(MarkupType::Fiducial, {{0, 0, 0}});
    m.points[0].label = "Nasion \xC3\xBC \xE2\x86\x92 \xC2\xB1"; // "ü", an arrow, plus-minus
    const Overlay o = build_overlay(markups_only({m}), cam, 300, 200, 1.0f);
    ASSERT_EQ(o.labels.size(), 1u);
    const LabelBox& l = o.labels[0];
    EXPECT_EQ(l.text, m.points[0].label);
    EXPECT_FALSE(l.moved);
    EXPECT_EQ(l.color, markup_color(m, 0));
    EXPECT_EQ(l.halo, glm::vec3(0.0f));
    // To the point's right, centred on it vertically.
    EXPECT_GT(l.lo.x, 150 + 6);
    EXPECT_NEAR(0.5 * (l.lo.y + l.hi.y), 100.0, 2.0);
    // Every character a glyph of its own (nothing became '?'): halo and text, two triangles each.
    std::size_t text = 0, halo = 0;
    for (const auto& v : o.vertices) {
        text += v.atlas_channel == 0.0f;
        halo += v.atlas_channel == 1.0f;
        if (v.atlas_channel >= 0) {
            EXPECT_EQ(v.inv_depth, 0.0f) << "labels are 2D: never compared with the depth, never dimmed";
            EXPECT_EQ(v.hidden_alpha, 1.0f);
        }
    }
    EXPECT_EQ(text, 6u * 9u) << "N a s i o n ü → ± (spaces have no ink)";
    EXPECT_EQ(halo, text);
    // What the box reports was drawn: coverage inside the halo, the halo all around.
    const glm::ivec2 size = l.hi - l.lo;
    ASSERT_EQ(l.coverage.size(), std::size_t(size.x * size.y));
    std::size_t full = 0;
    for (std::size_t i = 0; i < l.coverage.size(); ++i) {
        EXPECT_GE(l.halo_alpha[i], l.coverage[i]);
        full += l.coverage[i] == 255;
    }
    EXPECT_GT(full, 50u);
    // 11 pt at 96 dpi is 14.7 px per em: the font's line (1.16 em) and a 2.5 px halo above and below.
    EXPECT_NEAR(size.y, 11.0 * 96 / 72 * 1.16 + 2 * 2.5, 4.0);
    // Scale 2 (or 22 pt) is twice the size.
    const Overlay two = build_overlay(markups_only({m}), cam, 600, 400, 2.0f);
    ASSERT_EQ(two.labels.size(), 1u);
    const glm::vec2 size2 = glm::vec2(two.labels[0].hi - two.labels[0].lo);
    EXPECT_NEAR(size2.x / size.x, 2.0, 0.06);
    EXPECT_NEAR(size2.y / size.y, 2.0, 0.15) << "the line's height is hinted to whole pixels, the halo rounded up";
    Annotations big = markups_only({m});
    big.label_pt = 22;
    const Overlay pt = build_overlay(big, cam, 600, 400, 1.0f);
    EXPECT_EQ(pt.labels[0].hi - pt.labels[0].lo, two.labels[0].hi - two.labels[0].lo);
    // Scale 2: the glyph's extent around its point doubles.
    m.points[0].label.clear();
    auto extent = [&](float s) {
        float e = 0;
        for (const auto& x : build_overlay(markups_only({m}), cam, 200, 200, s).vertices)
            e = std::max(e, glm::length(x.pixel - glm::vec2(100)));
        return e;
    };
    EXPECT_NEAR(extent(2.0f) / extent(1.0f), 2.0, 1e-5);
}

TEST(Overlay, CrowdedLabelsArePlacedApartWithLeaderLines) {
    const Camera cam = front_camera();
    // Twelve labelled points within a few millimetres, a line and an angle through them.
    Markup points = markup(MarkupType::Fiducial, {});
    for (int i = 0; i < 12; ++i)
        points.points.push_back(point({double(i % 4) * 3 - 5, 0, double(i / 4) * 3 - 3}, "F-" + std::to_string(i + 1)));
    Annotations a = markups_only({points, markup(MarkupType::Line, {{-10, 0, -5}, {10, 0, 5}}),
                                  markup(MarkupType::Angle, {{-8, 0, 8}, {0, 0, 0}, {8, 0, 8}})});
    a.labels.push_back({{0, 0, 0}, "centre"});
    a.orientation = a.scale_bar = true;
    const Overlay o = build_overlay(a, cam, 400, 300, 1.0f);
    ASSERT_EQ(o.labels.size(), 4u + 1u + 12u + 1u + 1u + 1u) << "letters, scale bar, points, line, angle, plain label";
    std::size_t moved = 0, fixed = 0;
    for (std::size_t i = 0; i < o.labels.size(); ++i) {
        const LabelBox& l = o.labels[i];
        EXPECT_TRUE(l.lo.x >= 0 && l.lo.y >= 0 && l.hi.x <= 400 && l.hi.y <= 300) << l.text << " inside the image";
        for (std::size_t k = 0; k < i; ++k) {
            const LabelBox& m = o.labels[k];
            const bool apart = l.hi.x <= m.lo.x || m.hi.x <= l.lo.x || l.hi.y <= m.lo.y || m.hi.y <= l.lo.y;
            EXPECT_TRUE(apart) << "'" << l.text << "' and '" << m.text << "' overlap";
        }
        moved += l.moved;
        fixed += l.fixed;
    }
    EXPECT_EQ(fixed, 5u);
    EXPECT_GT(moved, 5u);
    // A leader line per moved label: 2D segments (outline and colour) in the label's colour, not dashed.
    std::size_t leader = 0;
    for (const auto& l : o.labels)
        if (l.moved)
            for (const auto& v : o.vertices)
                leader += v.atlas_channel < 0 && v.inv_depth == 0 && v.along < 0 && glm::vec3(v.color) == l.color;
    EXPECT_GE(leader, moved * 6);
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

TEST(Overlay, LegendTextNamesValueAndOpacity) {
    EXPECT_EQ(legend_text({"iso 500", glm::vec3(1), 0.35f, "500 HU"}), "iso 500 \xC2\xB7 500 HU \xC2\xB7 35 %");
    EXPECT_EQ(legend_text({"iso 1150", glm::vec3(1), 1.0f, "1150 HU"}), "iso 1150 \xC2\xB7 1150 HU");
    EXPECT_EQ(legend_text({"bunny.vtp", glm::vec3(1), 1.0f, ""}), "bunny.vtp") << "a mesh: its name only";
    EXPECT_EQ(legend_text({"skull", glm::vec3(1), 0.999f, ""}), "skull") << "rounds to 100 %";
}

TEST(Overlay, LegendKeepsClearOfLettersScaleBarAndLabels) {
    const Camera cam = front_camera();
    // Labelled points crowding the image's top left, where the legend goes when it fits.
    Markup points = markup(MarkupType::Fiducial, {});
    for (int i = 0; i < 6; ++i)
        points.points.push_back(point({-30.0 + 6.0 * (i % 3), 0, 25.0 - 6.0 * (i / 3)}, "P" + std::to_string(i + 1)));
    // At 320 x 240 the legend (about 240 px wide) fits only between the top and the left letter, without the points.
    for (const auto& [w, h, scale, n] : {std::tuple{400, 300, 1.0f, 6}, {320, 240, 1.0f, 0}, {800, 600, 2.0f, 6}}) {
        Annotations a = markups_only(n ? std::vector<Markup>{points} : std::vector<Markup>{});
        a.orientation = a.scale_bar = true;
        a.legend = {{"iso 500", {0.8f, 0.5f, 0.4f}, 0.4f, "500 HU"},
                    {"iso 1150", {0.9f, 0.9f, 0.85f}, 1.0f, "1150 HU"}};
        const Overlay o = build_overlay(a, cam, w, h, scale);
        ASSERT_EQ(o.labels.size(), 4u + 1u + std::size_t(n) + 2u) << "letters, scale bar, points, legend at " << w;
        std::vector<const LabelBox*> rows;
        for (const auto& l : o.labels)
            if (l.legend) rows.push_back(&l);
        ASSERT_EQ(rows.size(), 2u);
        EXPECT_EQ(rows[0]->text, "iso 500 \xC2\xB7 500 HU \xC2\xB7 40 %");
        const auto apart = [](glm::ivec2 lo, glm::ivec2 hi, const LabelBox& m) {
            return hi.x <= m.lo.x || m.hi.x <= lo.x || hi.y <= m.lo.y || m.hi.y <= lo.y;
        };
        for (const LabelBox* r : rows) {
            EXPECT_TRUE(r->fixed && !r->moved);
            EXPECT_TRUE(r->lo.x >= 0 && r->lo.y >= 0 && r->hi.x <= w && r->hi.y <= h) << r->text << " at " << w;
            EXPECT_EQ(r->swatch_hi - r->swatch_lo, glm::ivec2(r->swatch_hi.y - r->swatch_lo.y));
            EXPECT_LE(r->swatch_hi.x, r->lo.x) << "the swatch left of its text";
            for (const auto& m : o.labels) {
                if (m.legend) continue;
                EXPECT_TRUE(apart(r->lo, r->hi, m)) << r->text << " and '" << m.text << "' at " << w << "x" << h;
                EXPECT_TRUE(apart(r->swatch_lo, r->swatch_hi, m)) << "swatch and '" << m.text << "'";
            }
        }
        // The swatch's opaque half: the surface's colour in sRGB.
        const glm::vec3 want(srgb_from_linear(0.8), srgb_from_linear(0.5), srgb_from_linear(0.4));
        std::size_t swatch = 0;
        for (const auto& v : o.vertices)
            swatch += glm::length(glm::vec3(v.color) - want) < 1e-5f && v.color.a == 1.0f && v.atlas_channel < 0;
        EXPECT_EQ(swatch, 6u);
    }
}

TEST(Overlay, LegendLeftOutWhereItHasNoPlace) {
    // 160 px is narrower than the legend's rows: no place clear of the letters and the scale bar.
    Annotations a;
    a.legend = {{"iso 500", {0.8f, 0.5f, 0.4f}, 0.4f, "500 HU"}, {"iso 1150", {0.9f, 0.9f, 0.85f}, 1.0f, "1150 HU"}};
    const Overlay small = build_overlay(a, front_camera(), 160, 120, 1.0f);
    EXPECT_EQ(small.labels.size(), 4u + 1u) << "the letters and the scale bar, no legend";
    for (const auto& l : small.labels) EXPECT_FALSE(l.legend);
    a.orientation = a.scale_bar = false;
    const Overlay alone = build_overlay(a, front_camera(), 300, 120, 1.0f);
    EXPECT_EQ(alone.labels.size(), 2u) << "without letters it fits";
}

TEST(Overlay, MarkupLabelsCarryTheirNames) {
    // As 3D Slicer labels them: a line its name and length, an angle its name
    // and angle, a point its own label, else its point list's name.
    Markup gap = markup(MarkupType::Line, {{-18.3, 0, 20}, {18.3, 0, 20}}); // 36.6 mm
    gap.name = "Vessel gap";
    const Markup plain = markup(MarkupType::Line, {{-20, 0, -30}, {20, 0, -30}});      // 40 mm, no name
    Markup jaw = markup(MarkupType::Angle, {{-30, 0, 0}, {-20, 0, -10}, {-10, 0, 0}}); // a right angle
    jaw.name = "Jaw";
    Markup nidus = markup(MarkupType::Fiducial, {{25, 0, 5}});
    nidus.name = "AVM nidus";
    nidus.points.push_back(point({25, 0, -15}, "feeder"));
    const Markup unnamed = markup(MarkupType::Fiducial, {{0, 0, 0}}); // no name, no label: no text
    const Overlay o = build_overlay(markups_only({gap, plain, jaw, nidus, unnamed}), front_camera(), 400, 300, 1.0f);
    std::vector<std::string> texts;
    for (const auto& l : o.labels) texts.push_back(l.text);
    std::sort(texts.begin(), texts.end());
    const std::vector<std::string> want{"40.0 mm", "AVM nidus", "Jaw: 90.0\xC2\xB0", "Vessel gap: 36.6 mm", "feeder"};
    EXPECT_EQ(texts, want);
    for (const auto& l : o.labels) {
        std::size_t ink = 0;
        for (const auto c : l.coverage) ink += c == 255;
        EXPECT_GT(ink, 8u * l.text.size() / 2) << l.text << ": its glyphs are drawn";
    }
    // The point list's name beside its unlabelled point, to its right (the placement rule of a point's label).
    for (const auto& l : o.labels)
        if (l.text == "AVM nidus") {
            EXPECT_FALSE(l.moved);
            EXPECT_EQ(l.color, markup_color(nidus, 0));
        }
}

TEST(Overlay, MarkupLabelTextFollowsSlicer) {
    Markup line = markup(MarkupType::Line, {{0, 0, 0}, {0, 36.6, 0}});
    EXPECT_EQ(markup_label_text(line), "36.6 mm") << "unnamed: the length";
    line.name = "Vessel gap";
    EXPECT_EQ(markup_label_text(line), "Vessel gap: 36.6 mm");
    line.points[1].status = PositionStatus::Undefined;
    EXPECT_EQ(markup_label_text(line), "Vessel gap") << "no value: the name";
    Markup angle = markup(MarkupType::Angle, {{1, 0, 0}, {0, 0, 0}, {0, 0, 1}});
    angle.name = "Jaw";
    EXPECT_EQ(markup_label_text(angle), "Jaw: 90.0\xC2\xB0");
    Markup points = markup(MarkupType::Fiducial, {{0, 0, 0}, {1, 0, 0}});
    points.points[1].label = "F-2";
    EXPECT_EQ(markup_label_text(points, 0), "") << "no label, no name: nothing";
    points.name = "AVM nidus";
    EXPECT_EQ(markup_label_text(points, 0), "AVM nidus") << "no label: the list's name";
    EXPECT_EQ(markup_label_text(points, 1), "F-2") << "the point's own label first";
    EXPECT_EQ(markup_label_text(points, 2), "") << "no such point";
    EXPECT_EQ(markup_label_text(points), "") << "a point list has no label of its own";
    Markup curve = markup(MarkupType::Curve, {{0, 0, 0}});
    curve.name = "vessel";
    EXPECT_EQ(markup_label_text(curve, 0), "") << "a curve's points: their own labels only";
    curve.points[0].label = "C-1";
    EXPECT_EQ(markup_label_text(curve, 0), "C-1");
}

namespace {

// Legend entries as core::legend_entries makes them for a CT: "iso V", "V HU".
std::vector<Annotations::LegendEntry> iso_entries(int n) {
    std::vector<Annotations::LegendEntry> e;
    for (int i = 0; i < n; ++i) {
        const std::string v = std::to_string(100 + 150 * i);
        e.push_back({"iso " + v, glm::vec3(0.1f * float(i % 10), 0.5f, 0.8f), 1.0f, v + " HU"});
    }
    return e;
}

// The legend's rows as drawn, top to bottom.
std::vector<const LabelBox*> legend_rows(const Overlay& o) {
    std::vector<const LabelBox*> rows;
    for (const auto& l : o.labels)
        if (l.legend) rows.push_back(&l);
    std::sort(rows.begin(), rows.end(), [](const LabelBox* a, const LabelBox* b) { return a->lo.y < b->lo.y; });
    return rows;
}

} // namespace

TEST(Overlay, LegendOfManySurfacesIsDrawnCompactedNotDropped) {
    // 400 x 300: the left and right letters leave about 125 px above and below them, room for
    // four rows at 11 pt (24 px a row); before, a taller legend was left out.
    for (const int n : {6, 8, 12, 40}) {
        Annotations a;
        a.legend = iso_entries(n);
        const Overlay o = build_overlay(a, front_camera(), 400, 300, 1.0f);
        const auto rows = legend_rows(o);
        ASSERT_GE(rows.size(), 2u) << n << " surfaces: a legend is drawn";
        // The first rows are the first entries, in order, with their swatches; a last "+ K more" row stands for the rest.
        std::size_t shown = 0;
        while (shown < rows.size() && rows[shown]->swatch_hi.x > rows[shown]->swatch_lo.x) {
            const std::string v = std::to_string(100 + 150 * shown);
            EXPECT_EQ(rows[shown]->text, "iso " + v + " \xC2\xB7 " + v + " HU");
            ++shown;
        }
        ASSERT_GE(shown, 1u);
        if (shown < std::size_t(n)) {
            ASSERT_EQ(rows.size(), shown + 1) << "one row after the entries";
            EXPECT_EQ(rows.back()->text, "+ " + std::to_string(n - int(shown)) + " more");
        } else {
            EXPECT_EQ(rows.size(), shown);
        }
        EXPECT_LT(shown, 40u) << "40 rows do not fit in 300 px";
        for (const LabelBox* r : rows) {
            EXPECT_TRUE(r->fixed && !r->moved);
            EXPECT_TRUE(r->lo.x >= 0 && r->lo.y >= 0 && r->hi.x <= 400 && r->hi.y <= 300) << r->text;
            std::size_t ink = 0;
            for (const auto c : r->coverage) ink += c == 255;
            EXPECT_GT(ink, 20u) << r->text;
            for (const auto& m : o.labels)
                if (!m.legend) {
                    const bool apart = r->hi.x <= m.lo.x || m.hi.x <= r->lo.x || r->hi.y <= m.lo.y || m.hi.y <= r->lo.y;
                    EXPECT_TRUE(apart) << r->text << " and '" << m.text << "'";
                }
        }
        // Rows one under another, the same height apart.
        for (std::size_t i = 1; i < rows.size(); ++i)
            EXPECT_EQ(rows[i]->lo.y - rows[i - 1]->lo.y, rows[1]->lo.y - rows[0]->lo.y) << n;
    }
    // Where all rows fit, all are drawn at the labels' size, as two rows are.
    Annotations a;
    a.legend = iso_entries(6);
    const Overlay six = build_overlay(a, front_camera(), 1024, 1024, 1.0f);
    a.legend = iso_entries(2);
    const Overlay pair = build_overlay(a, front_camera(), 1024, 1024, 1.0f);
    const auto big = legend_rows(six), two = legend_rows(pair);
    ASSERT_EQ(big.size(), 6u);
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(big[0]->hi.y - big[0]->lo.y, two[0]->hi.y - two[0]->lo.y);
}
