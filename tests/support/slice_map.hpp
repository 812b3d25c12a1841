// Where a cone-AO slicemap (renderer/frame/ao_settings.hpp) puts a point, as
// its shaders compute it, for the tests that read the slicemap back.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "renderer/frame/ao_settings.hpp"

namespace iso::test {

// The first voxel whose centre lies at or beyond linear depth z (the solid pass's).
inline int voxel_at(const SliceMap& sm, double z) {
    return int(std::clamp(std::ceil((z - sm.z_near) / sm.voxel_length() - 0.5), 0.0, double(sm.bits())));
}

// The texel a world point projects to (rows bottom-up, as GL).
inline glm::ivec2 texel_of(const SliceMap& sm, glm::dvec3 world) {
    const glm::dvec4 c = sm.projection * sm.view * glm::dvec4(world, 1.0);
    return {int(std::floor((c.x / c.w * 0.5 + 0.5) * sm.width)), int(std::floor((c.y / c.w * 0.5 + 0.5) * sm.height))};
}

} // namespace iso::test
