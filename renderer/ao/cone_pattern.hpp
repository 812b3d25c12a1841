// The CPU side of cone-traced ambient occlusion's sample patterns (docs/ao.md):
// cone directions, Poisson-disk columns and jitter sets. The GL passes live in
// renderer/passes/ (ambient_occlusion.cpp and the files it calls), the
// settings and the read-back slicemap in renderer/frame/ao_settings.hpp.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "renderer/frame/ao_settings.hpp"

namespace iso {

// Cone axes in the tangent frame (z = normal), cosine-weighted and of equal
// projected-disk area (Malley's method over a sunflower partition of the unit
// disk); w = sine of the half-angle, chosen so the cones' solid angles add up
// to the hemisphere.
std::vector<glm::vec4> cone_directions(int n);

// n points in the unit disk, pairwise at least ~0.8 of the densest packing
// distance apart (dart throwing with a shrinking radius), deterministic in `seed`.
std::vector<glm::vec2> poisson_disk(int n, std::uint32_t seed);

// Everything the cone-tracing shader reads from its pattern buffer for one
// frame: [cones][sets: (cos a, sin a, sphere offset, 0)][sets x samples: (x, y, 0, 0)].
// Successive frames (frame = 0, 1, ...) give new, independent jitter sets.
std::vector<glm::vec4> cone_pattern(const ConeAoSettings& s, std::uint32_t frame);

} // namespace iso
