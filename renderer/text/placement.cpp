#include "renderer/text/placement.hpp"

#include <cmath>
#include <optional>

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>

namespace iso::text {

bool overlaps(const Box& a, const Box& b) {
    return a.lo.x < b.hi.x && b.lo.x < a.hi.x && a.lo.y < b.hi.y && b.lo.y < a.hi.y;
}

namespace {

Box box_at(glm::vec2 centre, glm::vec2 size) { return {centre - 0.5f * size, centre + 0.5f * size}; }

// How far a box of this size reaches from its centre along the unit direction `u`.
float reach(glm::vec2 size, glm::vec2 u) { return 0.5f * (std::abs(u.x) * size.x + std::abs(u.y) * size.y); }

struct Search {
    const std::vector<Box>& taken;
    glm::vec2 image;
    float gap;
    bool free(const Box& b) const {
        const Box grown{b.lo - gap, b.hi + gap};
        for (const Box& t : taken)
            if (overlaps(grown, t)) return false;
        return true;
    }
    bool inside(const Box& b) const { return b.lo.x >= 0 && b.lo.y >= 0 && b.hi.x <= image.x && b.hi.y <= image.y; }
};

// The candidates of ring `ring` in the order they are tried: 16 directions
// just clear of the anchor, 8 more each ring further out (so that candidates
// stay about as close together as the ring is wide), the default's
// direction first, then turning either way.
std::vector<glm::vec2> ring_centres(const LabelRequest& r, int ring) {
    const glm::vec2 off = r.centre - r.anchor;
    const float dist = glm::length(off);
    const glm::vec2 u0 = dist > 1e-3f ? off / dist : glm::vec2(1, 0);
    const float base = std::atan2(u0.y, u0.x);
    // The default's clearance from the anchor, kept in every direction.
    const float clearance = std::max(dist - reach(r.size, u0), 2.0f);
    const float step = r.size.y + clearance;
    const int n = 16 + 8 * ring;
    std::vector<glm::vec2> out;
    for (int k = 0; k < n; ++k) {
        const int turn = (k + 1) / 2 * (k % 2 ? 1 : -1); // 0, 1, -1, 2, -2, ...
        const float a = base + float(turn) * 2.0f * glm::pi<float>() / float(n);
        const glm::vec2 u(std::cos(a), std::sin(a));
        out.push_back(r.anchor + u * (reach(r.size, u) + clearance + float(ring) * step));
    }
    return out;
}

Placement place_one(const LabelRequest& r, const Search& s) {
    const Box def = box_at(r.centre, r.size);
    if (s.free(def) && s.inside(def)) return {def, false};
    std::optional<Placement> first_free;
    if (s.free(def)) first_free = Placement{def, false};
    // Rings until the image is left behind on every side, then on until free.
    const float extent = glm::length(s.image) + glm::length(r.size);
    for (int ring = 0;; ++ring) {
        bool beyond = true;
        for (const glm::vec2& c : ring_centres(r, ring)) {
            const Box b = box_at(c, r.size);
            beyond = beyond && glm::length(c - r.anchor) > extent;
            if (!s.free(b)) continue;
            if (s.inside(b)) return {b, true};
            if (!first_free) first_free = Placement{b, true};
        }
        if (first_free && beyond) return *first_free;
    }
}

} // namespace

std::vector<Placement> place_labels(const std::vector<LabelRequest>& labels, const std::vector<Box>& obstacles,
                                    glm::vec2 image_size, float gap) {
    std::vector<Placement> out(labels.size());
    std::vector<Box> taken = obstacles;
    for (std::size_t i = 0; i < labels.size(); ++i)
        if (labels[i].fixed) {
            out[i] = {box_at(labels[i].centre, labels[i].size), false};
            taken.push_back(out[i].box);
        }
    const Search search{taken, image_size, gap};
    for (std::size_t i = 0; i < labels.size(); ++i)
        if (!labels[i].fixed) {
            out[i] = place_one(labels[i], search);
            taken.push_back(out[i].box);
        }
    return out;
}

} // namespace iso::text
