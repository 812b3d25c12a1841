// A closed surface turned into voxels on a volume's grid: the voxels whose
// centres it encloses (what a label map stores, and what 3D Slicer's
// closed-surface-to-binary-labelmap conversion makes). By parity along the
// grid's first axis: every row of voxel centres is crossed by the surface
// an even number of times, and the centres between the 1st and 2nd, 3rd and
// 4th crossing ... are inside. A triangle claims a row when the row's point
// lies inside its projection, with the top-left rule on shared edges, so a
// row through an edge or a vertex is counted once (or, at a silhouette
// fold, twice, which keeps the parity): no row leaks and none is missed.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include <glm/mat4x4.hpp>

#include "io/mesh.hpp"

namespace iso {

// Sets out[linear index] = value for every voxel whose centre `m` encloses,
// on the grid of `dims` with `index_to_lps` (x fastest). Returns how many.
// An open surface gives what its crossings pair up as (rows with an odd
// count drop their last crossing).
std::size_t voxelize(const Mesh& m, const glm::dmat4& index_to_lps, std::array<std::int64_t, 3> dims,
                     std::span<std::uint16_t> out, std::uint16_t value);

} // namespace iso
