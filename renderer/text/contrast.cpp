#include "renderer/text/contrast.hpp"

#include <algorithm>

#include "io/color.hpp"

namespace iso::text {

double relative_luminance(const glm::vec3& c) {
    return 0.2126 * linear_from_srgb(c.r) + 0.7152 * linear_from_srgb(c.g) + 0.0722 * linear_from_srgb(c.b);
}

double contrast_ratio(const glm::vec3& a, const glm::vec3& b) {
    const double la = relative_luminance(a), lb = relative_luminance(b);
    return (std::max(la, lb) + 0.05) / (std::min(la, lb) + 0.05);
}

glm::vec3 halo_color(const glm::vec3& text) {
    const glm::vec3 black(0.0f), white(1.0f);
    return contrast_ratio(text, black) >= contrast_ratio(text, white) ? black : white;
}

} // namespace iso::text
