// The glyphs one overlay draws, packed into one image of two channels per
// texel (coverage, halo) that the overlay pass uploads as a texture. Built
// per frame from the fonts' cached bitmaps: packing is a copy, the
// rasterising was done once per glyph and size.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>

#include "renderer/text/font.hpp"

namespace iso::text {

// Texels two bytes each (coverage, halo), row-major from the top row.
struct AtlasImage {
    int width = 0, height = 0;
    std::vector<std::uint8_t> texels;
};

class GlyphAtlas {
public:
    // Adds a bitmap (once however often it is added); call before pack().
    void add(const std::shared_ptr<const GlyphBitmap>& g);
    // Packs the bitmaps in shelves, sizes a power of two (so that a steady
    // view keeps its texture) and at least 512 x 16 texels; returns the image.
    AtlasImage pack();
    // The top-left texel of an added bitmap, after pack().
    glm::ivec2 texel(const GlyphBitmap* g) const;

private:
    std::vector<std::shared_ptr<const GlyphBitmap>> glyphs_;
    std::map<const GlyphBitmap*, glm::ivec2> where_;
};

} // namespace iso::text
