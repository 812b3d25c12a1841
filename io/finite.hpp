// Whether a point's coordinates are all finite (no NaN, no infinity): the
// check readers and measurements make before they trust a point. One
// definition for them all (they each had a file-local copy, which a unity
// batch compiles as one unit).
#pragma once

#include <cmath>

#include <glm/vec3.hpp>

namespace iso {

inline bool finite(const glm::dvec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

} // namespace iso
