// What the disk AO passes keep across frames (renderer/passes/disk_ao.cpp):
// the uploaded hierarchy of the visible surfaces and its element terms. Kept
// outside the graph's pool because its sizes follow the geometry, known
// only once the CPU build has run inside the disk_build pass.
#pragma once

#include <cstdint>
#include <vector>

#include "renderer/ao/disk_geometry.hpp"
#include "renderer/gl/objects.hpp"

namespace iso::passes {

struct DiskState {
    // (id, version) of each surface in the uploaded hierarchy, in order.
    std::vector<std::uint64_t> key;
    std::size_t nodes = 0, triangles = 0;
    // Parents grouped by level, deepest level first: level_first[l] ..
    // level_first[l + 1] in the level list.
    std::vector<int> level_first;
    gl::Buffer node_buf, triangle_buf, level_buf, leaf_count_buf;
    // Element terms, ping-ponged between passes (a pass reads the previous
    // one's and writes its own); `final_terms` indexes the converged ones
    // that the gather reads. Leaf occlusion of the last two passes (the blend).
    gl::Buffer terms[2], occlusion[2];
    int final_terms = 0;
    // What the terms were computed for.
    bool terms_valid = false;
    DiskAoSettings settings;
    double radius = 0;
};

} // namespace iso::passes
