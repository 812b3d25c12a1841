// Where labels go so that none covers another: greedy placement over
// candidate places around each label's anchor, nearest first, inside the
// image where possible. Pure geometry in pixels (top-left origin, y down),
// tested without fonts or GL.
#pragma once

#include <vector>

#include <glm/vec2.hpp>

namespace iso::text {

struct Box {
    glm::vec2 lo{0.0f}, hi{0.0f};
    glm::vec2 size() const { return hi - lo; }
    glm::vec2 centre() const { return 0.5f * (lo + hi); }
};
// Boxes that share only an edge do not overlap.
bool overlaps(const Box& a, const Box& b);

struct LabelRequest {
    glm::vec2 size{0.0f};   // the label's box (text and halo), pixels
    glm::vec2 anchor{0.0f}; // the point it labels
    glm::vec2 centre{0.0f}; // its default place: the box's centre there
    bool fixed = false;     // placed where asked, never moved (orientation letters, the scale bar's text)
};

struct Placement {
    Box box;
    bool moved = false; // not at its default place: the overlay draws a leader line to the anchor
};

// Fixed labels first, where asked; then the others in order, each at the
// first candidate place whose box, grown by `gap` on each side, overlaps
// no label placed before it and no obstacle (the markups' point glyphs):
// its default place, then places all around the anchor (the default's
// direction first, then turning either way), just clear of the anchor in 16
// directions, then ring by ring further out with 8 more directions each. The first such place
// inside the image wins; when none is, the first free one. Rings continue
// until a free place is found, so labels never overlap one another (fixed
// labels excepted: they are not moved, also where they meet).
std::vector<Placement> place_labels(const std::vector<LabelRequest>& labels, const std::vector<Box>& obstacles,
                                    glm::vec2 image_size, float gap);

} // namespace iso::text
