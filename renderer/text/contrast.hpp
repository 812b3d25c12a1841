// Contrast as WCAG 2.x defines it, for choosing a label's halo: relative
// luminance of an sRGB colour and the ratio (L1 + 0.05) / (L2 + 0.05) of
// two of them, 1 to 21. AA asks 4.5 for normal text.
#pragma once

#include <glm/vec3.hpp>

namespace iso::text {

double relative_luminance(const glm::vec3& srgb); // components in [0, 1]
double contrast_ratio(const glm::vec3& srgb_a, const glm::vec3& srgb_b);

// The halo for text of this colour: black or white, whichever contrasts
// more. One of them always reaches sqrt(21) = 4.58 (at L = 0.179 the two
// ratios meet), so with an opaque halo every text colour passes 4.5:1.
glm::vec3 halo_color(const glm::vec3& text_srgb);

} // namespace iso::text
