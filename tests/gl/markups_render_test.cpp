// Markups drawn into rendered images: a point lands on the pixel the camera
// projects it to (computed here from the camera's axes and field of view,
// not through its matrices) at full strength in front of a surface and
// dimmed behind it; hidden line parts are dimmed and dashed; a line's length
// and an angle's value are written beside them, with their names (and a
// point list's name beside an unlabelled point) in exports; --scale
// scales glyphs and lines; and `isoscope render --markups` end to end, bad files included.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "io/image.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/gpu/renderer.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using MarkupsRender = test::GlTest;
using iso::test::Rgb;
using iso::test::rgb_at;
using iso::test::TempDir;

namespace {

constexpr int kSize = 200;

// A flat square facing the camera: x and z in [-40, 40] mm, at y = 0.
Mesh wall() {
    Mesh m;
    m.positions = {{-40, 0, -40}, {40, 0, -40}, {40, 0, 40}, {-40, 0, 40}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

bool near_colour(Rgb a, Rgb b, int tol) {
    return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

// Where the camera sees an LPS point: pixels from the image's top-left
// corner, from the camera's axes and field of view.
glm::dvec2 projected(const Camera& cam, glm::dvec3 p, int w, int h) {
    const glm::dvec3 f = cam.forward(), right = glm::normalize(glm::cross(f, cam.up)), up = glm::cross(right, f);
    const glm::dvec3 d = p - cam.eye;
    const double z = glm::dot(d, f), t = std::tan(glm::radians(cam.fov_y_degrees) * 0.5), aspect = double(w) / h;
    return {(glm::dot(d, right) / (z * t * aspect) + 1) * 0.5 * w, (1 - glm::dot(d, up) / (z * t)) * 0.5 * h};
}

Markup fiducial(glm::dvec3 p, glm::dvec3 colour) {
    Markup m;
    m.type = MarkupType::Fiducial;
    MarkupControlPoint c;
    c.position = p;
    m.points.push_back(c);
    m.selected_color = colour;
    return m;
}

Markup polyline(MarkupType t, std::vector<glm::dvec3> ps, glm::dvec3 colour) {
    Markup m;
    m.type = t;
    for (const auto& p : ps) {
        MarkupControlPoint c;
        c.position = p;
        m.points.push_back(c);
    }
    m.selected_color = colour;
    return m;
}

// The wall in grey, flat shaded on a black background, seen from the front.
struct Stage {
    Renderer ren;
    Camera cam;
    Annotations ann;
    RenderOptions opt;
    Stage() {
        SceneObject o;
        o.color = glm::vec3(0.2f);
        ren.add(wall(), o);
        cam.set_view(PatientView::Anterior, ren.bounds());
        ann.scale_bar = ann.orientation = false;
        opt.width = opt.height = kSize;
        opt.look.background = {0, 0, 0};
        opt.look.flat_shading = true;
        opt.annotations = &ann;
    }
    Image render(float scale = 1.0f) {
        opt.scale = scale;
        return ren.render(cam, opt).image;
    }
    glm::dvec2 px(glm::dvec3 p) const { return projected(cam, p, kSize, kSize); }
};

// Pixels of exactly this colour (within 2 levels) in a box around `c`.
std::size_t count(const Image& img, Rgb colour, glm::dvec2 c, int half, int tol = 2) {
    std::size_t n = 0;
    for (int y = std::max(0, int(c.y) - half); y <= std::min(img.height - 1, int(c.y) + half); ++y)
        for (int x = std::max(0, int(c.x) - half); x <= std::min(img.width - 1, int(c.x) + half); ++x)
            n += near_colour(rgb_at(img, x, y), colour, tol);
    return n;
}

} // namespace

TEST_F(MarkupsRender, PointInFrontIsFullStrengthBehindIsDimmed) {
    Stage st;
    const glm::dvec3 front(-20, -20, 10), behind(20, 20, -10), beside(55, 10, 0); // beside the wall, behind its plane
    st.ann.markups = {fiducial(front, {0, 1, 0}), fiducial(behind, {0, 1, 0}), fiducial(beside, {0, 1, 0})};
    const Image img = st.render();
    const Image bare = [&] {
        st.ann.markups.clear();
        return st.render();
    }();
    const Rgb green{0, 255, 0};
    // In front: the glyph's pixels are the colour, centred on the projection.
    const glm::dvec2 f = st.px(front);
    glm::dvec2 sum(0.0);
    std::size_t n = 0;
    for (int y = int(f.y) - 12; y <= int(f.y) + 12; ++y)
        for (int x = int(f.x) - 12; x <= int(f.x) + 12; ++x)
            if (near_colour(rgb_at(img, x, y), green, 2)) {
                sum += glm::dvec2(x + 0.5, y + 0.5);
                ++n;
            }
    ASSERT_GT(n, 30u) << "the glyph in front is drawn at full strength";
    EXPECT_NEAR(sum.x / n, f.x, 0.75);
    EXPECT_NEAR(sum.y / n, f.y, 0.75);
    EXPECT_TRUE(near_colour(rgb_at(img, int(f.x), int(f.y)), green, 2));
    // Behind: the colour at 35 % over the wall, no outline; the wall and the image elsewhere unchanged.
    const glm::dvec2 b = st.px(behind);
    const Rgb wall_px = rgb_at(bare, int(b.x), int(b.y)), dim = rgb_at(img, int(b.x), int(b.y));
    ASSERT_GT(wall_px.r, 20) << "the wall is there";
    EXPECT_EQ(count(img, green, b, 12), 0u) << "nothing at full strength behind the wall";
    EXPECT_NEAR(dim.g, 0.35 * 255 + 0.65 * wall_px.g, 2.0);
    EXPECT_NEAR(dim.r, 0.65 * wall_px.r, 2.0);
    EXPECT_GT(dim.g, wall_px.g + 40);
    EXPECT_LT(dim.g, 255 - 40);
    EXPECT_NEAR(count(img, dim, b, 12, 1), double(n), 4.0) << "the dimmed glyph is the same cross";
    // Behind the wall's plane but beside it, nothing hides it: full strength on the background.
    EXPECT_TRUE(near_colour(rgb_at(img, int(st.px(beside).x), int(st.px(beside).y)), green, 2));
    EXPECT_NEAR(double(count(img, green, st.px(beside), 12)), double(n), 4.0);
    // Above the occlusion tolerance only: a point 0.5 mm behind the wall's surface is not hidden.
    st.ann.markups = {fiducial({0, 0.5, 0}, {0, 1, 0})};
    EXPECT_TRUE(near_colour(rgb_at(st.render(), kSize / 2, kSize / 2), green, 2));
}

TEST_F(MarkupsRender, HiddenPartsOfALineAreDimmedAndDashed) {
    Stage st;
    // Through the wall at x = 0: the left half in front, the right half behind.
    const glm::dvec3 a(-30, -20, -20), c(30, 20, -20);
    st.ann.markups = {polyline(MarkupType::Line, {a, c}, {1, 0, 1})};
    const Image img = st.render();
    st.ann.markups.clear();
    const Image bare = st.render();
    const Rgb magenta{255, 0, 255};
    // Sample along the projected 3D segment.
    std::size_t front_full = 0, back_full = 0, back_dim = 0, back_gap = 0, samples = 0;
    for (int k = 1; k < 40; ++k) {
        // In front: from 10 % (clear of the end's glyph and its outline) to 44 % (2.4 mm before the wall);
        // behind: from 55 % (2 mm behind, past the 1 mm tolerance) to 94 %.
        const double t = k / 40.0;
        const glm::dvec2 p = st.px(glm::mix(a, c, 0.1 + t * 0.35)), q = st.px(glm::mix(a, c, 0.55 + t * 0.4));
        front_full += near_colour(rgb_at(img, int(p.x), int(p.y)), magenta, 2);
        const Rgb r = rgb_at(img, int(q.x), int(q.y));
        back_full += near_colour(r, magenta, 2);
        back_dim += r.r > 100 && r.r < 200 && r.b > 100 && r.b < 200;
        back_gap += near_colour(r, rgb_at(bare, int(q.x), int(q.y)), 2); // the wall, untouched
        ++samples;
    }
    EXPECT_EQ(front_full, samples) << "in front: solid, full strength";
    EXPECT_EQ(back_full, 0u) << "behind: never full strength";
    EXPECT_GT(back_dim, samples / 4) << "behind: dimmed dashes";
    EXPECT_GT(back_gap, samples / 4) << "behind: gaps between the dashes";
}

TEST_F(MarkupsRender, LengthAndAngleLabelsAreWritten) {
    Stage st;
    // A horizontal line in front of the wall with its length stored (as Slicer does) and an angle.
    Markup line = polyline(MarkupType::Line, {{-30, -10, 20}, {30, -10, 20}}, {0, 1, 1});
    line.measurements.push_back({"length", 42.3, "mm"});
    const Markup angle = polyline(MarkupType::Angle, {{-25, -10, -5}, {0, -10, -30}, {25, -10, -5}}, {1, 1, 0});
    EXPECT_EQ(markup_measurement_text(line), "42.3 mm");
    EXPECT_EQ(markup_measurement_text(angle), "90.0\xC2\xB0");
    st.ann.markups = {line, angle};
    const Image img = st.render();
    // The length: text pixels in the line's colour above its midpoint (the line itself is excluded).
    const glm::dvec2 mid = st.px({0, -10, 20});
    std::size_t text = 0;
    for (int y = int(mid.y) - 24; y < int(mid.y) - 4; ++y)
        for (int x = int(mid.x) - 30; x <= int(mid.x) + 30; ++x)
            text += near_colour(rgb_at(img, x, y), {0, 255, 255}, 2);
    EXPECT_GT(text, 40u) << "\"42.3 mm\" above the line";
    // The angle: text pixels below the vertex (away from both arms, which open upwards).
    const glm::dvec2 v = st.px({0, -10, -30});
    std::size_t value = 0;
    for (int y = int(v.y) + 6; y < int(v.y) + 30; ++y)
        for (int x = int(v.x) - 25; x <= int(v.x) + 25; ++x) value += near_colour(rgb_at(img, x, y), {255, 255, 0}, 2);
    EXPECT_GT(value, 30u) << "\"90.0 deg\" below the vertex";
    // Without the labels' markups, those boxes hold no such pixels (the wall and background are grey and black).
    st.ann.markups.clear();
    EXPECT_EQ(count(st.render(), {0, 255, 255}, mid, 30), 0u);
}

TEST_F(MarkupsRender, ScaleTwoDoublesGlyphsAndLines) {
    Stage st;
    const glm::dvec3 p(-20, -20, 20);
    st.ann.markups = {fiducial(p, {0, 1, 0}), polyline(MarkupType::Line, {{-30, -20, -20}, {30, -20, -20}}, {1, 0, 1})};
    auto covered = [&](float scale, Rgb colour, glm::dvec2 c, int half) {
        return double(count(st.render(scale), colour, c, half));
    };
    const glm::dvec2 glyph = st.px(p), line = st.px({0, -20, -20});
    const double g1 = covered(1, {0, 255, 0}, glyph, 20), g2 = covered(2, {0, 255, 0}, glyph, 20);
    ASSERT_GT(g1, 30.0);
    EXPECT_NEAR(g2 / g1, 4.0, 0.4) << "the cross is twice as long and twice as thick";
    // The line's middle stretch (no glyph there): twice as wide.
    auto band = [&](float scale) {
        const Image img = st.render(scale);
        std::size_t n = 0;
        for (int y = int(line.y) - 4; y <= int(line.y) + 4; ++y) // the length label is above, farther out
            for (int x = int(line.x) - 20; x < int(line.x) + 20; ++x)
                n += near_colour(rgb_at(img, x, y), {255, 0, 255}, 2);
        return double(n);
    };
    const double l1 = band(1), l2 = band(2);
    ASSERT_GT(l1, 60.0);
    EXPECT_NEAR(l2 / l1, 2.0, 0.2);
}

// ---- isoscope render --markups ---------------------------------------------

TEST(MarkupsCli, RenderDrawsAndRecordsTheMarkups) {
    TempDir dir;
    const std::string file = test::data("markups/slicer-line-ras.mrk.json");
    const std::string base = test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --size 160x160 ";
    const auto r = test::run_command(base + "--markups " + file + " -o " + (dir / "out.png"), true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("converted from RAS"), std::string::npos)
        << "the reader's warning, naming the file: " << r.out;
    ImageMetadata meta;
    const Image img = load_image(dir / "out.png", &meta);
    EXPECT_NE(meta.text["isoscope:markups"].find("slicer-line-ras.mrk.json"), std::string::npos);
    EXPECT_EQ(meta.text["isoscope:markups_sha256"].size(), 64u);
    EXPECT_NE(meta.text["isoscope:markups_drawn"].find("Line: 2 defined point(s), 80.5 mm"), std::string::npos)
        << meta.text["isoscope:markups_drawn"];
    // The markup changed the image; with --no-annotations it is still drawn (alone).
    ASSERT_EQ(test::run_command(base + "-o " + (dir / "bare.png"), true).exit_code, 0);
    const Image bare = load_image(dir / "bare.png");
    std::size_t changed = 0;
    for (std::size_t i = 0; i < img.bytes.size(); ++i) changed += img.bytes[i] != bare.bytes[i];
    EXPECT_GT(changed, 100u);
    ASSERT_EQ(
        test::run_command(base + "--no-annotations --markups " + file + " -o " + (dir / "only.png"), true).exit_code,
        0);
    ASSERT_EQ(test::run_command(base + "--no-annotations -o " + (dir / "none.png"), true).exit_code, 0);
    EXPECT_NE(load_image(dir / "only.png").bytes, load_image(dir / "none.png").bytes);
    // Repeatable: both files are recorded.
    const auto two =
        test::run_command(base + "--markups " + file + " --markups " +
                              test::data("markups/slicer-points-lps.mrk.json") + " -o " + (dir / "two.png"),
                          true);
    ASSERT_EQ(two.exit_code, 0) << two.out;
    ImageMetadata meta2;
    load_image(dir / "two.png", &meta2);
    EXPECT_NE(meta2.text["isoscope:markups"].find("slicer-points-lps.mrk.json"), std::string::npos);
    EXPECT_NE(meta2.text["isoscope:markups_drawn"].find("Fiducial: 2 defined point(s)"), std::string::npos)
        << meta2.text["isoscope:markups_drawn"];
}

TEST(MarkupsCli, MissingOrMalformedMarkupsFailNamingTheFile) {
    TempDir dir;
    const std::string base = test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --size 64x64 ";
    {
        std::ofstream(dir / "broken.mrk.json")
            << "{\"@schema\": \"https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/"
               "Markups/Resources/Schema/markups-schema-v1.0.3.json#\", \"markups\": [ {\"type\": ";
        std::ofstream(dir / "angle.mrk.json")
            << R"({"@schema": "markups-schema-v1.0.3.json", "markups": [{"type": "Angle",
            "controlPoints": [{"position": [0, 0, 0]}, {"position": [1, 0, 0]}]}]})";
    }
    for (const std::string name : {"missing.mrk.json", "broken.mrk.json", "angle.mrk.json"}) {
        const auto r = test::run_command(base + "--markups " + (dir / name) + " -o " + (dir / "x.png"), true);
        EXPECT_EQ(r.exit_code, 1) << name << ": " << r.out;
        EXPECT_NE(r.out.find("isoscope: error: " + (dir / name) + ": "), std::string::npos) << r.out;
        EXPECT_FALSE(std::filesystem::exists(dir / "x.png")) << name;
    }
    // Markups go on the colour image only.
    const auto aov = test::run_command(base + "--aov depth --markups " +
                                           test::data("markups/slicer-line-ras.mrk.json") + " -o " + (dir / "d.exr"),
                                       true);
    EXPECT_EQ(aov.exit_code, 1);
    EXPECT_NE(aov.out.find("--markups"), std::string::npos) << aov.out;
}

TEST_F(MarkupsRender, ExportedLabelsCarryTheMarkupsNames) {
    // Through the core API, as `isoscope render --markups` and File > Export image draw them: a named line
    // shows its name and length, an unnamed one its length, a named angle its name and angle, a point
    // without a label its point list's name, a labelled point its label.
    core::Scene scene;
    core::SurfaceInfo info;
    info.name = "wall";
    info.color = glm::vec3(0.2f);
    scene.add_mesh(wall(), info);
    Markup gap = polyline(MarkupType::Line, {{-18.3, -10, 25}, {18.3, -10, 25}}, {0, 1, 1}); // 36.6 mm
    gap.name = "Vessel gap";
    const Markup plain = polyline(MarkupType::Line, {{-20, -10, -32}, {20, -10, -32}}, {1, 0.5, 0});     // 40 mm
    Markup jaw = polyline(MarkupType::Angle, {{-32, -10, 5}, {-22, -10, -5}, {-12, -10, 5}}, {1, 1, 0}); // 90 deg
    jaw.name = "Jaw";
    Markup nidus = fiducial({15, -10, 5}, {1, 0, 1});
    nidus.name = "AVM nidus";
    MarkupControlPoint feeder;
    feeder.position = {15, -10, -15};
    feeder.label = "feeder";
    nidus.points.push_back(feeder);
    core::RenderRequest req;
    req.width = req.height = 320;
    req.annotations = false; // no letters, scale bar or legend: the markups' labels only
    req.look.background = {0, 0, 0};
    req.markups = {gap, plain, jaw, nidus};
    const core::RenderOutput out = core::render_image(scene, req);
    req.markups.clear();
    const core::RenderOutput bare = core::render_image(scene, req);
    std::vector<std::string> texts;
    for (const auto& l : out.labels) texts.push_back(l.text);
    std::sort(texts.begin(), texts.end());
    EXPECT_EQ(texts,
              (std::vector<std::string>{"40.0 mm", "AVM nidus", "Jaw: 90.0\xC2\xB0", "Vessel gap: 36.6 mm", "feeder"}));
    // Each label's text is drawn where its box says, in its markup's colour: its fully covered pixels are
    // that colour and differ from the frame without markups.
    for (const auto& l : out.labels) {
        const Rgb want{int(std::lround(l.color.r * 255)), int(std::lround(l.color.g * 255)),
                       int(std::lround(l.color.b * 255))};
        std::size_t ink = 0, coloured = 0, changed = 0;
        const int w = l.hi.x - l.lo.x;
        for (int y = std::max(l.lo.y, 0); y < std::min(l.hi.y, out.image.height); ++y)
            for (int x = std::max(l.lo.x, 0); x < std::min(l.hi.x, out.image.width); ++x)
                if (l.coverage[std::size_t((y - l.lo.y) * w + (x - l.lo.x))] == 255) {
                    ++ink;
                    coloured += near_colour(rgb_at(out.image, x, y), want, 2);
                    changed += !near_colour(rgb_at(out.image, x, y), rgb_at(bare.image, x, y), 2);
                }
        EXPECT_GT(ink, 4u * l.text.size()) << l.text;
        EXPECT_EQ(coloured, ink) << l.text;
        EXPECT_EQ(changed, ink) << l.text;
    }
}
