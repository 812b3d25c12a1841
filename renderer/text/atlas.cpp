#include "renderer/text/atlas.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstring>

namespace iso::text {

void GlyphAtlas::add(const std::shared_ptr<const GlyphBitmap>& g) {
    if (g && g->width > 0 && where_.emplace(g.get(), glm::ivec2(-1)).second) glyphs_.push_back(g);
}

AtlasImage GlyphAtlas::pack() {
    // Tallest first, so that each shelf wastes little height.
    std::vector<const GlyphBitmap*> order;
    int widest = 0;
    for (const auto& g : glyphs_) {
        order.push_back(g.get());
        widest = std::max(widest, g->width);
    }
    std::stable_sort(order.begin(), order.end(),
                     [](const GlyphBitmap* a, const GlyphBitmap* b) { return a->height > b->height; });
    AtlasImage img;
    img.width = int(std::bit_ceil(unsigned(std::max(512, widest))));
    int x = 0, y = 0, shelf = 0;
    for (const GlyphBitmap* g : order) {
        if (x + g->width > img.width) {
            x = 0;
            y += shelf;
            shelf = 0;
        }
        where_[g] = {x, y};
        x += g->width;
        shelf = std::max(shelf, g->height);
    }
    img.height = int(std::bit_ceil(unsigned(std::max(16, y + shelf))));
    img.texels.assign(std::size_t(img.width) * img.height * 2, 0);
    for (const GlyphBitmap* g : order) {
        const glm::ivec2 at = where_[g];
        for (int r = 0; r < g->height; ++r)
            for (int c = 0; c < g->width; ++c) {
                const std::size_t src = std::size_t(r) * g->width + c;
                const std::size_t dst = (std::size_t(at.y + r) * img.width + (at.x + c)) * 2;
                img.texels[dst] = g->coverage[src];
                img.texels[dst + 1] = g->halo[src];
            }
    }
    return img;
}

glm::ivec2 GlyphAtlas::texel(const GlyphBitmap* g) const {
    const auto it = where_.find(g);
    assert(it != where_.end() && it->second.x >= 0 && "GlyphAtlas::texel: added and packed first");
    return it->second;
}

} // namespace iso::text
