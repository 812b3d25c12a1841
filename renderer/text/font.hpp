// The overlay's text engine: fontconfig finds the font, FreeType rasterises
// its glyphs at a size in pixels (points x dpi / 72 x the export scale), each
// with a halo channel: the glyph's coverage dilated by a radius that grows
// with the size, drawn under the text in a contrasting colour. Text is laid
// out on one line, glyph by glyph from the font's cmap, with the face's
// kerning when it has a kerning table: no HarfBuzz shaping (no ligatures,
// no complex scripts or right-to-left text), which measurement labels,
// names and units in Latin, Greek and Cyrillic do not need. A code point the
// face has no glyph for is drawn as the face's .notdef (glyph 0).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec2.hpp>

namespace iso::text {

// The overlay's face, looked up through fontconfig. Bold: at label sizes
// (11 pt on a 96 dpi screen, 15 px per em) the book weight's stems are about
// 1.3 px wide, so hardly a pixel of them reaches full coverage and every
// stroke is a blend of text and halo; bold stems (2-2.5 px) keep a core of
// pixels at the text's own colour over any background.
inline constexpr const char* kFontPattern = "DejaVu Sans:style=Bold";

// One glyph as the overlay draws it, padded for its halo: row-major bytes
// from the top row, width x height each.
struct GlyphBitmap {
    int width = 0, height = 0;
    glm::ivec2 offset{0}; // its top-left pixel relative to the pen on the baseline (pixels, y down)
    std::vector<std::uint8_t> coverage, halo;
};

// The file fontconfig gives for `pattern` (e.g. kFontPattern); throws
// iso::Error naming the pattern when it finds no font of that family
// (fontconfig falls back to any font; that is not what we asked for).
std::string find_font_file(const std::string& pattern);

// A face at one size. Thread safe: FreeType's face is used under the font's
// own mutex (FreeType objects must not be used from two threads at once);
// the bitmaps it hands out are immutable and outlive the font.
class Font {
public:
    // Throws iso::Error naming the file when FreeType cannot open it as a
    // scalable font or set the size. `pixel_size`: pixels per em.
    Font(const std::string& file, float pixel_size);
    ~Font();
    Font(const Font&) = delete;
    Font& operator=(const Font&) = delete;

    const std::string& file() const { return file_; }
    float pixel_size() const { return pixel_size_; }
    float halo_radius() const { return halo_; } // pixels
    float ascent() const { return ascent_; }    // above the baseline, pixels
    float descent() const { return descent_; }  // below it, pixels (positive)
    bool has_kerning() const { return kerning_; }

    std::uint32_t glyph_index(char32_t c) const;                  // 0: the face's .notdef
    float advance(std::uint32_t glyph) const;                     // pixels
    float kerning(std::uint32_t left, std::uint32_t right) const; // pixels, 0 when the face has none
    // Rasterised on first use, then kept.
    std::shared_ptr<const GlyphBitmap> bitmap(std::uint32_t glyph) const;

private:
    struct Glyph {
        float advance = 0;
        std::shared_ptr<const GlyphBitmap> bitmap;
    };
    const Glyph& load(std::uint32_t glyph) const; // with mutex_ held

    std::string file_;
    float pixel_size_, halo_;
    float ascent_ = 0, descent_ = 0;
    bool kerning_ = false;
    struct FreeType;
    std::unique_ptr<FreeType> ft_;
    mutable std::mutex mutex_;
    mutable std::map<std::uint32_t, Glyph> glyphs_;
};

// The overlay's font (kFontPattern) at `pixel_size` pixels per em, made
// once per size in the process and shared by every thread that draws an
// overlay (the desktop app's view and its export run on different threads).
// Throws iso::Error naming the font when it is missing or unreadable.
std::shared_ptr<const Font> overlay_font(float pixel_size);

// One line of text laid out from its origin (the pen's start on the
// baseline): each glyph's pen position snapped to whole pixels, so that
// its bitmap lands texel for pixel.
struct PositionedGlyph {
    std::shared_ptr<const GlyphBitmap> bitmap;
    glm::ivec2 pen{0}; // pixels from the origin, y down
};
struct TextLayout {
    std::vector<PositionedGlyph> glyphs;
    float advance = 0;             // the pen after the last glyph, pixels
    float ascent = 0, descent = 0; // the font's, pixels
    float halo = 0;                // the halo's radius, pixels
    // The box every drawn pixel lies in (glyph bitmaps with their halo, and
    // the font's line box grown by the halo), relative to the origin.
    glm::ivec2 lo{0}, hi{0};
};
TextLayout layout_text(std::string_view utf8, const Font& font);

} // namespace iso::text
