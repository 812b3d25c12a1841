#include "renderer/text/font.hpp"

#include <algorithm>
#include <cmath>

#include <fontconfig/fontconfig.h>
#include <glm/glm.hpp>
#include <ft2build.h>
#include FT_FREETYPE_H

#include "io/error.hpp"
#include "renderer/text/utf8.hpp"

namespace iso::text {

namespace {

std::string freetype_reason(FT_Error e) {
    const char* s = FT_Error_String(e); // null unless FreeType was built with error strings
    return s ? std::string(s) : "FreeType error " + std::to_string(int(e));
}

// The halo: every pixel within `r` of an inked pixel q, fully opaque up to
// r - 1 + coverage(q) (an edge pixel's coverage says how far into it the
// outline reaches) and fading over the last pixel, so the text's
// anti-aliased edges blend into the halo's colour, never into the image.
std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& cov, int w, int h, float r) {
    std::vector<std::uint8_t> out(cov.size(), 0);
    const int reach = int(std::ceil(r)) + 1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float c = cov[std::size_t(y) * w + x] / 255.0f;
            if (c <= 0) continue;
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dx = -reach; dx <= reach; ++dx) {
                    const int px = x + dx, py = y + dy;
                    if (px < 0 || py < 0 || px >= w || py >= h) continue;
                    const float a = std::clamp(r + c - std::sqrt(float(dx * dx + dy * dy)), 0.0f, 1.0f);
                    auto& o = out[std::size_t(py) * w + px];
                    o = std::max(o, std::uint8_t(std::lround(a * 255.0f)));
                }
        }
    return out;
}

} // namespace

std::string find_font_file(const std::string& pattern) {
    const auto fail = [&](const std::string& why) { return Error("font '" + pattern + "'", why); };
    if (!FcInit()) throw fail("fontconfig could not load its configuration");
    FcPattern* pat = FcNameParse(reinterpret_cast<const FcChar8*>(pattern.c_str()));
    if (!pat) throw fail("not a fontconfig pattern");
    FcConfigSubstitute(nullptr, pat, FcMatchPattern);
    FcDefaultSubstitute(pat);
    FcResult res = FcResultNoMatch;
    FcPattern* match = FcFontMatch(nullptr, pat, &res);
    std::string wanted, family, file;
    FcChar8* s = nullptr;
    if (FcPatternGetString(pat, FC_FAMILY, 0, &s) == FcResultMatch) wanted = reinterpret_cast<const char*>(s);
    if (match && FcPatternGetString(match, FC_FAMILY, 0, &s) == FcResultMatch)
        family = reinterpret_cast<const char*>(s);
    if (match && FcPatternGetString(match, FC_FILE, 0, &s) == FcResultMatch) file = reinterpret_cast<const char*>(s);
    if (match) FcPatternDestroy(match);
    FcPatternDestroy(pat);
    if (file.empty()) throw fail("fontconfig finds no font at all (install fonts-dejavu-core)");
    // fontconfig always answers with its best font; another family is a fallback, not the font asked for.
    if (!wanted.empty() && FcStrCmpIgnoreCase(reinterpret_cast<const FcChar8*>(wanted.c_str()),
                                              reinterpret_cast<const FcChar8*>(family.c_str())) != 0)
        throw fail("not installed: fontconfig offers only '" + family + "' (" + file +
                   ") instead (install fonts-dejavu-core)");
    return file;
}

struct Font::FreeType {
    FT_Library library = nullptr;
    FT_Face face = nullptr;
    ~FreeType() {
        if (face) FT_Done_Face(face);
        if (library) FT_Done_FreeType(library);
    }
};

Font::Font(const std::string& file, float pixel_size)
    : file_(file), pixel_size_(pixel_size), halo_(std::max(1.5f, 0.17f * pixel_size)),
      ft_(std::make_unique<FreeType>()) {
    const auto fail = [&](const std::string& why) { return Error(file, "font: " + why); };
    if (!(pixel_size >= 1.0f && pixel_size <= 2048.0f))
        throw fail("size " + std::to_string(pixel_size) + " px is outside 1..2048");
    // One library per font: FreeType's library is not to be shared between
    // threads without a lock around creating and freeing faces.
    if (const FT_Error e = FT_Init_FreeType(&ft_->library)) throw fail("FreeType: " + freetype_reason(e));
    if (const FT_Error e = FT_New_Face(ft_->library, file.c_str(), 0, &ft_->face))
        throw fail("FreeType cannot open it: " + freetype_reason(e));
    FT_Face f = ft_->face;
    if (!FT_IS_SCALABLE(f)) throw fail("not a scalable (outline) font");
    if (const FT_Error e = FT_Set_Char_Size(f, 0, FT_F26Dot6(std::lround(pixel_size * 64.0f)), 72, 72))
        throw fail("FreeType cannot set " + std::to_string(pixel_size) + " px: " + freetype_reason(e));
    ascent_ = float(f->size->metrics.ascender) / 64.0f;
    descent_ = -float(f->size->metrics.descender) / 64.0f;
    kerning_ = FT_HAS_KERNING(f);
}

Font::~Font() = default;

std::uint32_t Font::glyph_index(char32_t c) const {
    const std::lock_guard lock(mutex_);
    return FT_Get_Char_Index(ft_->face, FT_ULong(c));
}

float Font::kerning(std::uint32_t left, std::uint32_t right) const {
    if (!kerning_ || !left || !right) return 0.0f;
    const std::lock_guard lock(mutex_);
    FT_Vector d{0, 0};
    if (FT_Get_Kerning(ft_->face, left, right, FT_KERNING_UNFITTED, &d)) return 0.0f;
    return float(d.x) / 64.0f;
}

float Font::advance(std::uint32_t glyph) const {
    const std::lock_guard lock(mutex_);
    return load(glyph).advance;
}

std::shared_ptr<const GlyphBitmap> Font::bitmap(std::uint32_t glyph) const {
    const std::lock_guard lock(mutex_);
    return load(glyph).bitmap;
}

const Font::Glyph& Font::load(std::uint32_t index) const {
    if (const auto it = glyphs_.find(index); it != glyphs_.end()) return it->second;
    FT_Face f = ft_->face;
    // Light hinting: outlines snapped vertically only, so stems stay crisp
    // on the baseline and the x-height and widths stay true to the design.
    if (const FT_Error e = FT_Load_Glyph(f, index, FT_LOAD_TARGET_LIGHT | FT_LOAD_RENDER))
        throw Error(file_, "font: FreeType cannot render glyph " + std::to_string(index) + ": " + freetype_reason(e));
    const FT_GlyphSlot g = f->glyph;
    const FT_Bitmap& bm = g->bitmap;
    if (bm.pixel_mode != FT_PIXEL_MODE_GRAY)
        throw Error(file_, "font: FreeType rendered glyph " + std::to_string(index) + " not as 8-bit grey");
    Glyph out;
    out.advance = float(g->linearHoriAdvance) / 65536.0f; // unhinted: spacing true to the design
    auto b = std::make_shared<GlyphBitmap>();
    if (bm.width > 0 && bm.rows > 0) {
        const int pad = int(std::ceil(halo_)) + 1;
        b->width = int(bm.width) + 2 * pad;
        b->height = int(bm.rows) + 2 * pad;
        b->offset = {g->bitmap_left - pad, -g->bitmap_top - pad};
        b->coverage.assign(std::size_t(b->width) * b->height, 0);
        for (unsigned y = 0; y < bm.rows; ++y)
            for (unsigned x = 0; x < bm.width; ++x)
                b->coverage[std::size_t(y + pad) * b->width + (x + pad)] = bm.buffer[std::ptrdiff_t(y) * bm.pitch + x];
        b->halo = dilate(b->coverage, b->width, b->height, halo_);
    }
    out.bitmap = std::move(b);
    return glyphs_.emplace(index, std::move(out)).first->second;
}

std::shared_ptr<const Font> overlay_font(float pixel_size) {
    static std::mutex mutex;
    static std::map<long, std::shared_ptr<const Font>> fonts; // by 1/64 px
    static std::string file;
    const long key = std::lround(pixel_size * 64.0f);
    const std::lock_guard lock(mutex);
    if (const auto it = fonts.find(key); it != fonts.end()) return it->second;
    if (file.empty()) file = find_font_file(kFontPattern);
    // A few sizes per process (labels, orientation letters, times each
    // export scale); a session that asks for many starts afresh (fonts in
    // use live on in their frames).
    if (fonts.size() >= 64) fonts.clear();
    auto font = std::make_shared<const Font>(file, float(key) / 64.0f);
    fonts.emplace(key, font);
    return font;
}

TextLayout layout_text(std::string_view utf8, const Font& font) {
    TextLayout t;
    t.ascent = font.ascent();
    t.descent = font.descent();
    t.halo = font.halo_radius();
    const int grow = int(std::ceil(t.halo));
    float pen = 0;
    std::uint32_t previous = 0;
    for (const char32_t c : decode_utf8(utf8)) {
        const std::uint32_t g = font.glyph_index(c);
        pen += font.kerning(previous, g);
        const auto bm = font.bitmap(g);
        if (bm->width > 0) t.glyphs.push_back({bm, {int(std::lround(pen)), 0}});
        pen += font.advance(g);
        previous = g;
    }
    t.advance = pen;
    t.lo = {-grow, -int(std::ceil(t.ascent)) - grow};
    t.hi = {int(std::ceil(pen)) + grow, int(std::ceil(t.descent)) + grow};
    for (const auto& pg : t.glyphs) {
        t.lo = glm::min(t.lo, pg.pen + pg.bitmap->offset);
        t.hi = glm::max(t.hi, pg.pen + pg.bitmap->offset + glm::ivec2(pg.bitmap->width, pg.bitmap->height));
    }
    return t;
}

} // namespace iso::text
