// The overlay's text engine without GL: UTF-8 decoding (valid, invalid and
// truncated input, as Unicode's table 3-8 example gives it), the DejaVu
// face through fontconfig (the signs measurement labels use are real
// glyphs; missing ones are .notdef), layout that grows with the size and
// kerns, clear errors for a missing or unreadable font, greedy label
// placement that never overlaps, and the halo's contrast for every colour.
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "io/error.hpp"
#include "renderer/text/atlas.hpp"
#include "renderer/text/contrast.hpp"
#include "renderer/text/font.hpp"
#include "renderer/text/placement.hpp"
#include "renderer/text/utf8.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using namespace iso::text;

namespace {

constexpr char32_t F = kReplacement;

// 11 pt at 96 dpi, the overlay's label size at scale 1.
constexpr float kLabelPx = 11.0f * 96.0f / 72.0f;

// WCAG 2.x relative luminance, written out here from the definition (the
// sRGB curve with its 0.03928 threshold) rather than through the product's.
double luminance(glm::dvec3 c) {
    const auto lin = [](double v) { return v <= 0.03928 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); };
    return 0.2126 * lin(c.r) + 0.7152 * lin(c.g) + 0.0722 * lin(c.b);
}
double ratio(glm::dvec3 a, glm::dvec3 b) {
    const double la = luminance(a), lb = luminance(b);
    return (std::max(la, lb) + 0.05) / (std::min(la, lb) + 0.05);
}

} // namespace

TEST(Utf8, ValidSequencesOfEveryLength) {
    // a, e acute (2 bytes), degree sign (2), the CJK "middle" (3), a grinning face (4).
    EXPECT_EQ(decode_utf8("a\xC3\xA9\xC2\xB0\xE4\xB8\xAD\xF0\x9F\x98\x80"),
              (std::u32string{U'a', 0xE9, 0xB0, 0x4E2D, 0x1F600}));
    EXPECT_EQ(decode_utf8(""), std::u32string());
    EXPECT_EQ(decode_utf8(std::string_view("a\0b", 3)), (std::u32string{U'a', 0, U'b'})) << "NUL is a character";
    EXPECT_EQ(decode_utf8("\xF4\x8F\xBF\xBF"), std::u32string{0x10FFFF}) << "the last code point";
}

TEST(Utf8, InvalidBytesBecomeOneReplacementPerMaximalSubpart) {
    // Unicode 15, table 3-8: 61 F1 80 80 E1 80 C2 62 80 63 80 BF 64.
    EXPECT_EQ(decode_utf8("\x61\xF1\x80\x80\xE1\x80\xC2\x62\x80\x63\x80\xBF\x64"),
              (std::u32string{U'a', F, F, F, U'b', F, U'c', F, F, U'd'}));
    EXPECT_EQ(decode_utf8("\xC0\xAF"), (std::u32string{F, F})) << "overlong '/'";
    EXPECT_EQ(decode_utf8("\xE0\x80\xAF"), (std::u32string{F, F, F})) << "overlong 3-byte";
    EXPECT_EQ(decode_utf8("\xED\xA0\x80"), (std::u32string{F, F, F})) << "a surrogate";
    EXPECT_EQ(decode_utf8("\xF4\x90\x80\x80"), (std::u32string{F, F, F, F})) << "above U+10FFFF";
    EXPECT_EQ(decode_utf8("\xFE\xFF"), (std::u32string{F, F}));
    EXPECT_EQ(decode_utf8("x\xB0y"), (std::u32string{U'x', F, U'y'})) << "a Latin-1 degree sign";
}

TEST(Utf8, SequencesCutShortAreOneReplacement) {
    EXPECT_EQ(decode_utf8("a\xE2\x82"), (std::u32string{U'a', F})) << "cut by the end";
    EXPECT_EQ(decode_utf8("\xF0\x9F\x98"), std::u32string{F});
    EXPECT_EQ(decode_utf8("\xC2"), std::u32string{F});
    EXPECT_EQ(decode_utf8("\xE2\x82z"), (std::u32string{F, U'z'})) << "the breaking byte starts anew";
    EXPECT_EQ(decode_utf8("\xC2\xC2\xB0"), (std::u32string{F, 0xB0}));
}

TEST(Utf8, AnyBytesDecodeWithinBounds) {
    // Every string of up to 2 bytes and random longer ones: no more code points than bytes,
    // and only scalar values (no surrogates, nothing above U+10FFFF).
    std::mt19937 rng(7);
    std::vector<std::string> inputs;
    for (int a = 0; a < 256; ++a) {
        inputs.push_back(std::string(1, char(a)));
        for (int b = 0; b < 256; ++b) inputs.push_back(std::string{char(a), char(b)});
    }
    for (int i = 0; i < 20000; ++i) {
        std::string s(rng() % 9, '\0');
        for (auto& c : s) c = char(rng() & 0xFF);
        inputs.push_back(s);
    }
    for (const auto& s : inputs) {
        const auto d = decode_utf8(s);
        ASSERT_LE(d.size(), s.size());
        for (const char32_t c : d) ASSERT_TRUE(c <= 0x10FFFF && (c < 0xD800 || c > 0xDFFF)) << std::hex << unsigned(c);
    }
}

TEST(Font, DejaVuThroughFontconfigHasTheSignsOfMeasurements) {
    const auto font = overlay_font(kLabelPx);
    EXPECT_NE(font->file().find("DejaVuSans-Bold"), std::string::npos) << font->file();
    // Degree, squared, plus-minus, micro, e acute, U+FFFD: real glyphs, not .notdef (0).
    for (const char32_t c : {U'\u00B0', U'\u00B2', U'\u00B1', U'\u00B5', U'\u00E9', kReplacement})
        EXPECT_NE(font->glyph_index(c), 0u) << "U+" << std::hex << unsigned(c);
    // DejaVu has no CJK: .notdef, which has an outline (a box), so it is drawn.
    EXPECT_EQ(font->glyph_index(0x4E2D), 0u);
    const auto t = layout_text("\xE4\xB8\xAD", *font);
    ASSERT_EQ(t.glyphs.size(), 1u);
    EXPECT_EQ(t.glyphs[0].bitmap, font->bitmap(0));
    EXPECT_GT(t.glyphs[0].bitmap->width, 0);
    // One size, one font object in the process.
    EXPECT_EQ(overlay_font(kLabelPx), font);
}

TEST(Font, LayoutGrowsWithTheSizeAndKerns) {
    const std::string s = "145.3 mm \xC2\xB1 0.2";
    float last = 0;
    for (const float px : {8.0f, kLabelPx, 20.0f, 2 * kLabelPx, 4 * kLabelPx}) {
        const auto t = layout_text(s, *overlay_font(px));
        EXPECT_GT(t.advance, last) << px;
        EXPECT_GT(t.hi.x - t.lo.x, int(t.advance)) << "the box holds the halo too";
        last = t.advance;
    }
    // Unhinted advances: 4x the size is 4x as wide (whole-pixel pens aside).
    const float one = layout_text(s, *overlay_font(kLabelPx)).advance;
    EXPECT_NEAR(layout_text(s, *overlay_font(4 * kLabelPx)).advance / one, 4.0, 0.02);
    // DejaVu's kerning table pulls "AV" together.
    const auto font = overlay_font(kLabelPx);
    ASSERT_TRUE(font->has_kerning());
    const float apart = layout_text("A", *font).advance + layout_text("V", *font).advance;
    EXPECT_LT(layout_text("AV", *font).advance, apart - 0.5f);
}

TEST(Font, GlyphsCarryAnOpaqueHaloAroundTheirInk) {
    const auto font = overlay_font(kLabelPx);
    const auto bm = font->bitmap(font->glyph_index(U'8'));
    ASSERT_GT(bm->width, 0);
    std::size_t full = 0;
    for (int y = 0; y < bm->height; ++y)
        for (int x = 0; x < bm->width; ++x) {
            const auto i = std::size_t(y) * bm->width + x;
            if (bm->coverage[i] < 255) continue;
            ++full;
            // Within the halo radius of a fully inked pixel, the halo is opaque.
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) EXPECT_EQ(bm->halo[std::size_t(y + dy) * bm->width + (x + dx)], 255);
        }
    EXPECT_GT(full, 10u) << "bold stems have a core at full coverage";
    // The padding leaves the bitmap's border clear.
    for (int x = 0; x < bm->width; ++x) EXPECT_EQ(bm->halo[x], 0);
}

TEST(Font, MissingOrUnreadableFontsAreErrorsNamingThem) {
    try {
        find_font_file("Isoscope No Such Family");
        ADD_FAILURE() << "a fallback family was taken for the one asked";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("Isoscope No Such Family"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("not installed"), std::string::npos) << e.what();
    }
    test::TempDir dir;
    test::write_file(dir / "not-a-font.ttf", "hello");
    for (const std::string& file : {dir / "missing.ttf", dir / "not-a-font.ttf"}) {
        try {
            Font f(file, kLabelPx);
            ADD_FAILURE() << file;
        } catch (const Error& e) {
            EXPECT_EQ(e.where(), file);
            EXPECT_NE(e.reason().find("FreeType cannot open it"), std::string::npos) << e.what();
        }
    }
}

TEST(Font, SharedByThreadsThatLayOutAtOnce) {
    // The desktop app's view and its export lay out text on different threads, through the same fonts.
    const std::vector<std::string> texts{"145.3 mm", "70.8\xC2\xB0", "\xC3\xA9t\xC3\xA9 \xC2\xB1 2 \xC2\xB5m",
                                         "Nasion"};
    const std::vector<float> sizes{13.0f, 17.5f, 31.0f};
    std::vector<std::vector<float>> widths(4);
    std::vector<std::thread> threads;
    for (std::size_t t = 0; t < widths.size(); ++t)
        threads.emplace_back([&, t] {
            for (int round = 0; round < 20; ++round)
                for (const float px : sizes)
                    for (const auto& s : texts) widths[t].push_back(layout_text(s, *overlay_font(px)).advance);
        });
    for (auto& th : threads) th.join();
    for (std::size_t t = 1; t < widths.size(); ++t) EXPECT_EQ(widths[t], widths[0]);
}

TEST(Atlas, PacksEachBitmapOnceTexelForTexel) {
    const auto font = overlay_font(kLabelPx);
    const auto t = layout_text("aba\xC2\xB0", *font);
    GlyphAtlas atlas;
    for (const auto& g : t.glyphs) atlas.add(g.bitmap);
    const AtlasImage img = atlas.pack();
    EXPECT_EQ(img.width, 512);
    EXPECT_EQ(img.height & (img.height - 1), 0) << "a power of two";
    for (const auto& g : t.glyphs) {
        const glm::ivec2 at = atlas.texel(g.bitmap.get());
        const auto& bm = *g.bitmap;
        for (int y = 0; y < bm.height; ++y)
            for (int x = 0; x < bm.width; ++x) {
                const std::size_t i = (std::size_t(at.y + y) * img.width + at.x + x) * 2;
                ASSERT_EQ(img.texels[i], bm.coverage[std::size_t(y) * bm.width + x]);
                ASSERT_EQ(img.texels[i + 1], bm.halo[std::size_t(y) * bm.width + x]);
            }
    }
    EXPECT_EQ(atlas.texel(t.glyphs[0].bitmap.get()), atlas.texel(t.glyphs[2].bitmap.get())) << "'a' once";
}

TEST(Placement, CrowdedLabelsNeverOverlap) {
    // 36 labels on 6 anchors in a 320 x 240 image, two fixed ones and a glyph to keep off.
    std::vector<LabelRequest> req;
    for (int i = 0; i < 36; ++i) {
        const glm::vec2 anchor(60.0f + 40.0f * float(i % 6), 120.0f + float(i % 3));
        req.push_back({{30.0f + float(i % 5) * 8.0f, 18.0f}, anchor, anchor + glm::vec2(30, 0), false});
    }
    req.push_back({{20, 30}, {310, 120}, {305, 120}, true});
    req.push_back({{20, 30}, {10, 120}, {15, 120}, true});
    const std::vector<Box> glyphs{{{55, 113}, {69, 127}}};
    const auto placed = place_labels(req, glyphs, {320, 240}, 2.0f);
    ASSERT_EQ(placed.size(), req.size());
    std::size_t inside = 0, moved = 0;
    for (std::size_t i = 0; i < placed.size(); ++i) {
        const Box& a = placed[i].box;
        EXPECT_NEAR(a.size().x, req[i].size.x, 1e-3f);
        EXPECT_NEAR(a.size().y, req[i].size.y, 1e-3f);
        EXPECT_FALSE(overlaps(a, glyphs[0])) << i;
        for (std::size_t k = 0; k < i; ++k) EXPECT_FALSE(overlaps(a, placed[k].box)) << i << " and " << k;
        inside += a.lo.x >= 0 && a.lo.y >= 0 && a.hi.x <= 320 && a.hi.y <= 240;
        moved += placed[i].moved;
    }
    EXPECT_EQ(inside, placed.size()) << "room enough inside the image for all";
    EXPECT_GE(moved, 30u);
    EXPECT_FALSE(placed[36].moved);
    EXPECT_EQ(placed[36].box.centre(), glm::vec2(305, 120)) << "fixed labels stay";
    // Far more than fit: still none overlaps (some leave the image).
    std::vector<LabelRequest> many(400, LabelRequest{{40, 20}, {50, 50}, {80, 50}, false});
    const auto all = place_labels(many, {}, {200, 100}, 1.0f);
    for (std::size_t i = 0; i < all.size(); ++i)
        for (std::size_t k = 0; k < i; ++k) ASSERT_FALSE(overlaps(all[i].box, all[k].box)) << i << " and " << k;
}

TEST(Placement, AFreeLabelStaysAndOneAtTheEdgeMovesInside) {
    const auto p = place_labels({{{40, 20}, {100, 100}, {130, 100}, false}}, {}, {200, 200}, 2.0f);
    EXPECT_FALSE(p[0].moved);
    EXPECT_EQ(p[0].box.centre(), glm::vec2(130, 100));
    // Its default place would cross the right edge: it goes to the anchor's left instead.
    const auto q = place_labels({{{40, 20}, {190, 100}, {220, 100}, false}}, {}, {200, 200}, 2.0f);
    EXPECT_TRUE(q[0].moved);
    EXPECT_LE(q[0].box.hi.x, 200.0f);
    EXPECT_LT(q[0].box.centre().x, 190.0f);
}

TEST(Contrast, TheHaloMeetsWcagAaForEveryColour) {
    // The default markup colours (annotations.cpp) and the other text's, with the halo the overlay picks.
    const std::vector<std::pair<const char*, glm::vec3>> defaults{
        {"point list", {1.0f, 0.5f, 0.5f}}, {"line", {0.35f, 0.85f, 1.0f}}, {"angle", {0.55f, 1.0f, 0.35f}},
        {"curve", {1.0f, 0.65f, 0.25f}},    {"text", {1.0f, 1.0f, 0.92f}},  {"face line (file)", {1.0f, 0.85f, 0.2f}}};
    for (const auto& [name, c] : defaults) {
        const glm::vec3 h = halo_color(c);
        EXPECT_EQ(h, glm::vec3(0.0f)) << name << ": light text, dark halo";
        const double r = ratio(c, h);
        EXPECT_GE(r, 4.5) << name;
        EXPECT_NEAR(contrast_ratio(c, h), r, 0.01) << name;
        std::printf("%-18s %.2f:1\n", name, r);
    }
    // Any colour at all: black or white reaches sqrt(21) = 4.58.
    double worst = 21;
    for (int r = 0; r <= 16; ++r)
        for (int g = 0; g <= 16; ++g)
            for (int b = 0; b <= 16; ++b) {
                const glm::vec3 c(r / 16.0f, g / 16.0f, b / 16.0f);
                worst = std::min(worst, ratio(c, halo_color(c)));
            }
    EXPECT_GE(worst, 4.5);
    EXPECT_EQ(halo_color({0.1f, 0.1f, 0.5f}), glm::vec3(1.0f)) << "dark text, light halo";
}
