// The legend of annotated exports (docs/text.md, "Legend"), rendered through
// the core API, written as PNG and read back: a row per visible surface with
// its name, iso value in HU (a CT volume) and opacity; the swatch's opaque
// half is the surface's colour in sRGB, its other half that colour at the
// surface's opacity over the checker; its text reaches WCAG AA contrast
// against its halo; it meets no orientation letter, the scale bar's text or a
// markup's label; it is recorded in the metadata, and absent with the legend
// or the annotations off; with many surfaces it is still drawn (smaller, or
// its first rows and "+ K more").
#include <cmath>
#include <cstdio>

#include <glm/glm.hpp>

#include "gl_test.hpp"
#include "io/color.hpp"
#include "io/image.hpp"
#include "io/markups.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "tests/support/contrast.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/pixels.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using Legend = test::GlTest;

namespace {

// The bundled head as a CT volume (its NRRD header has no modality; a CT
// series or MetaImage says "CT"): skin at 40 % over opaque bone.
void open_ct_head(core::Scene& scene) {
    Volume v = core::open_volume(test::data("headsq.nhdr"));
    v.meta.modality = "CT";
    scene.set_volume(std::move(v), test::data("headsq.nhdr"));
    const auto ids = scene.add_isosurfaces({500, 1150});
    scene.info(ids[0]).opacity = 0.4f;
}

std::vector<const LabelBox*> legend_rows(const std::vector<LabelBox>& labels) {
    std::vector<const LabelBox*> rows;
    for (const auto& l : labels)
        if (l.legend) rows.push_back(&l);
    return rows;
}

bool apart(glm::ivec2 lo, glm::ivec2 hi, const LabelBox& m) {
    return hi.x <= m.lo.x || m.hi.x <= lo.x || hi.y <= m.lo.y || m.hi.y <= lo.y;
}

glm::ivec3 srgb8(glm::vec3 linear) {
    return glm::ivec3(std::lround(srgb_from_linear(linear.r) * 255), std::lround(srgb_from_linear(linear.g) * 255),
                      std::lround(srgb_from_linear(linear.b) * 255));
}

// Every pixel inside the swatch's opaque half (its outermost pixels left
// out: rasterisation at the edge) against the colour meant; the largest
// difference in 8-bit levels.
int swatch_error(const Image& img, const LabelBox& row, glm::ivec3 want) {
    int worst = 0;
    for (int y = row.swatch_lo.y + 1; y < row.swatch_hi.y - 1; ++y)
        for (int x = row.swatch_lo.x + 1; x < row.swatch_hi.x - 1; ++x) {
            const test::Rgb p = test::rgb_at(img, x, y);
            worst = std::max({worst, std::abs(p.r - want.r), std::abs(p.g - want.g), std::abs(p.b - want.b)});
        }
    return worst;
}

// Each legend row legible and clear of every other label.
void expect_clear_and_legible(const std::vector<LabelBox>& labels, const Image& img) {
    for (const LabelBox* r : legend_rows(labels)) {
        EXPECT_TRUE(r->lo.x >= 0 && r->lo.y >= 0 && r->hi.x <= img.width && r->hi.y <= img.height) << r->text;
        const test::Measured m = test::measure_label(img, *r);
        std::printf("legend '%s' at %d,%d: contrast %.2f:1 (text L %.3f, ring L %.3f)\n", r->text.c_str(), r->lo.x,
                    r->lo.y, m.ratio, m.text_l, m.ring_l);
        EXPECT_GE(m.ratio, 4.5) << r->text << " (WCAG AA)";
        for (const auto& o : labels) {
            if (o.legend) continue;
            EXPECT_TRUE(apart(r->lo, r->hi, o)) << "'" << r->text << "' and '" << o.text << "'";
            EXPECT_TRUE(apart(r->swatch_lo, r->swatch_hi, o))
                << "the swatch of '" << r->text << "' and '" << o.text << "'";
        }
    }
}

} // namespace

TEST_F(Legend, CtHeadExportNamesValuesInHuAndColours) {
    core::Scene scene;
    open_ct_head(scene);
    core::RenderRequest req;
    req.width = 640;
    req.height = 480;
    req.view = "left";
    req.markups = load_markups(test::data("markups/headsq-face.mrk.json")).markups;
    const core::RenderOutput out = core::render_image(scene, req);
    test::TempDir dir;
    save_image(out.image, dir / "legend.png", out.meta);
    ImageMetadata meta;
    const Image img = load_image(dir / "legend.png", &meta);
    const auto rows = legend_rows(out.labels);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0]->text, "iso 500 \xC2\xB7 500 HU \xC2\xB7 40 %");
    EXPECT_EQ(rows[1]->text, "iso 1150 \xC2\xB7 1150 HU");
    const auto ids = scene.surfaces();
    for (std::size_t i = 0; i < 2; ++i) {
        const glm::vec3 c = scene.info(ids[i]).color;
        const int err = swatch_error(img, *rows[i], srgb8(c));
        std::printf("swatch %zu: %dx%d px, largest difference %d/255 from %s\n", i,
                    rows[i]->swatch_hi.x - rows[i]->swatch_lo.x, rows[i]->swatch_hi.y - rows[i]->swatch_lo.y, err,
                    hex_from_linear(c).c_str());
        EXPECT_LE(err, 1) << "the swatch is the surface's colour (8-bit rounding)";
    }
    // The translucent half's first checker cell (light grey 0.85): the skin at 40 % over it, blended in sRGB.
    const glm::ivec2 cell = rows[0]->swatch_lo + glm::ivec2(rows[0]->swatch_hi.x - rows[0]->swatch_lo.x + 1, 1);
    const glm::vec3 c = glm::vec3(srgb8(scene.info(ids[0]).color)) / 255.0f;
    const glm::ivec3 blended = glm::ivec3(glm::round((0.85f * 0.6f + c * 0.4f) * 255.0f));
    const test::Rgb p = test::rgb_at(img, cell.x, cell.y);
    EXPECT_NEAR(p.r, blended.r, 2);
    EXPECT_NEAR(p.g, blended.g, 2);
    EXPECT_NEAR(p.b, blended.b, 2);
    expect_clear_and_legible(out.labels, img);
    EXPECT_GT(out.labels.size(), 4u + 1u + 2u) << "letters, scale bar, the face's labels and the legend";
    const std::string skin = hex_from_linear(scene.info(ids[0]).color),
                      bone = hex_from_linear(scene.info(ids[1]).color);
    EXPECT_EQ(meta.text["isoscope:legend"], "iso 500: 500 HU, colour " + skin +
                                                ", opacity 40 %\niso 1150: 1150 HU, colour " + bone +
                                                ", opacity 100 %");
}

TEST_F(Legend, SmallExportKeepsClearOfTheLettersAndTheScaleBar) {
    core::Scene scene;
    open_ct_head(scene);
    for (const auto& [w, h, scale] : {std::tuple{360, 270, 1.0f}, {720, 540, 2.0f}}) {
        core::RenderRequest req;
        req.width = w;
        req.height = h;
        req.scale = scale;
        const core::RenderOutput out = core::render_image(scene, req);
        ASSERT_EQ(legend_rows(out.labels).size(), 2u) << w << "x" << h;
        expect_clear_and_legible(out.labels, out.image);
    }
    // Narrower than the legend's rows: left out rather than over the letters, and the metadata says so.
    core::RenderRequest req;
    req.width = 200;
    req.height = 150;
    const core::RenderOutput out = core::render_image(scene, req);
    EXPECT_TRUE(legend_rows(out.labels).empty());
    EXPECT_EQ(out.labels.size(), 4u + 1u);
    EXPECT_NE(out.meta.text.at("isoscope:legend").find("iso 500"), std::string::npos);
    EXPECT_EQ(out.meta.text.at("isoscope:legend_note"),
              "not drawn: no place for it clear of the orientation letters and the scale bar at 200x150");
}

TEST_F(Legend, AbsentWhenOffOrWithoutAnnotations) {
    core::Scene scene;
    open_ct_head(scene);
    core::RenderRequest req;
    req.width = 400;
    req.height = 300;
    const core::RenderOutput with = core::render_image(scene, req);
    EXPECT_EQ(legend_rows(with.labels).size(), 2u);
    req.legend = false;
    const core::RenderOutput off = core::render_image(scene, req);
    EXPECT_TRUE(legend_rows(off.labels).empty());
    EXPECT_EQ(off.labels.size(), 4u + 1u) << "the letters and the scale bar stay";
    EXPECT_EQ(off.meta.text.count("isoscope:legend"), 0u);
    EXPECT_GT(test::differing(with.image, off.image), 500u) << "the legend's box is drawn";
    req.legend = true;
    req.annotations = false;
    const core::RenderOutput bare = core::render_image(scene, req);
    EXPECT_TRUE(bare.labels.empty());
    EXPECT_EQ(bare.meta.text.count("isoscope:legend"), 0u);
}

TEST_F(Legend, MeshesByNameAndVolumesWithoutAUnitWithoutOne) {
    core::Scene scene;
    scene.open(test::data("headsq.nhdr")); // no modality: no unit
    const auto ids = scene.add_isosurfaces({500});
    core::SurfaceInfo ball;
    ball.name = "ball.stl";
    ball.color = {0.2f, 0.4f, 0.9f};
    scene.add_mesh(test::uv_sphere(scene.bounds().center(), 20, 16, 32), ball);
    const auto hidden = scene.add_isosurfaces({1150});
    scene.info(hidden[0]).visible = false;
    core::RenderRequest req;
    req.width = 320;
    req.height = 240;
    req.look.transparency = false; // every surface opaque: the legend says 100 %
    scene.info(ids[0]).opacity = 0.5f;
    const core::RenderOutput out = core::render_image(scene, req);
    const auto rows = legend_rows(out.labels);
    ASSERT_EQ(rows.size(), 2u) << "visible surfaces only";
    EXPECT_EQ(rows[0]->text, "iso 500");
    EXPECT_EQ(rows[1]->text, "ball.stl");
    EXPECT_LE(swatch_error(out.image, *rows[1], srgb8(ball.color)), 1);
}

TEST_F(Legend, ManySurfacesAreListedNotDropped) {
    // Six and then twelve isosurfaces of the CT head in a 400 x 300 export:
    // a legend taller than the room beside the left and right letters at
    // 11 pt, which used to be left out. Now it is drawn: all its rows,
    // smaller, or its first rows and "+ K more" for the rest.
    core::Scene scene;
    Volume v = core::open_volume(test::data("headsq.nhdr"));
    v.meta.modality = "CT";
    scene.set_volume(std::move(v), test::data("headsq.nhdr"));
    std::vector<double> isos;
    for (int i = 0; i < 12; ++i) isos.push_back(200 + 120 * i);
    const auto ids = scene.add_isosurfaces(isos);
    for (const std::size_t visible : {6u, 12u}) {
        for (std::size_t i = 0; i < ids.size(); ++i) scene.info(ids[i]).visible = i < visible;
        core::RenderRequest req;
        req.width = 400;
        req.height = 300;
        const core::RenderOutput out = core::render_image(scene, req);
        req.legend = false;
        const core::RenderOutput off = core::render_image(scene, req);
        const auto rows = legend_rows(out.labels);
        ASSERT_GE(rows.size(), 2u) << visible << " surfaces: a legend is drawn";
        std::size_t shown = 0;
        for (; shown < rows.size() && rows[shown]->swatch_hi.x > rows[shown]->swatch_lo.x; ++shown) {
            const std::string value = std::to_string(int(isos[shown]));
            EXPECT_EQ(rows[shown]->text, "iso " + value + " \xC2\xB7 " + value + " HU") << "in the scene's order";
            EXPECT_LE(swatch_error(out.image, *rows[shown], srgb8(scene.info(ids[shown]).color)), 1)
                << rows[shown]->text;
        }
        ASSERT_GE(shown, 1u);
        std::printf("%zu surfaces: %zu rows shown, %d px high each\n", visible, shown, rows[0]->hi.y - rows[0]->lo.y);
        if (visible == 12) {
            // Twelve rows cannot fit in 300 px beside the letters even at 65 % (16 px a row).
            ASSERT_LT(shown, visible);
            ASSERT_EQ(rows.size(), shown + 1);
            EXPECT_EQ(rows.back()->text, "+ " + std::to_string(visible - shown) + " more");
            EXPECT_EQ(out.meta.text.at("isoscope:legend_note"),
                      "the first " + std::to_string(shown) + " of 12 rows drawn, then \"+ K more\": no place for " +
                          "all at 400x300");
            EXPECT_NE(out.meta.text.at("isoscope:legend").find("iso 1520: 1520 HU"), std::string::npos)
                << "the metadata lists every row";
        } else {
            EXPECT_EQ(rows.size(), visible) << "six rows fit, smaller";
            EXPECT_EQ(out.meta.text.count("isoscope:legend_note"), 0u);
        }
        expect_clear_and_legible(out.labels, out.image);
        // Every row's text is in the image: where its glyphs are fully covered, the pixels are the text's
        // colour and differ from the same frame drawn without the legend.
        for (const LabelBox* r : rows) {
            std::size_t ink = 0, changed = 0;
            const int w = r->hi.x - r->lo.x;
            for (int y = r->lo.y; y < r->hi.y; ++y)
                for (int x = r->lo.x; x < r->hi.x; ++x)
                    if (r->coverage[std::size_t((y - r->lo.y) * w + (x - r->lo.x))] == 255) {
                        ++ink;
                        const test::Rgb a = test::rgb_at(out.image, x, y), b = test::rgb_at(off.image, x, y);
                        changed += a.r != b.r || a.g != b.g || a.b != b.b;
                    }
            EXPECT_GT(ink, 20u) << r->text;
            EXPECT_EQ(changed, ink) << r->text;
        }
    }
}
