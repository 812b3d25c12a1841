// Sparse volume storage: an OpenVDB float grid, kept as read (never densified
// on load). Only io/ and renderer code that needs the tree includes OpenVDB.
#pragma once

#include <cstddef>
#include <cstdint>

#include <openvdb/openvdb.h>

#include "io/volume.hpp"

namespace iso {

struct SparseGrid {
    openvdb::FloatGrid::ConstPtr grid;
    // Our index (0,0,0) is the grid's index `offset` (the active bounding box's min corner).
    openvdb::Coord offset;
};

std::size_t sparse_memory_bytes(const SparseGrid& g);
double sparse_value(const SparseGrid& g, std::int64_t i, std::int64_t j, std::int64_t k);
ValueRange sparse_value_range(const SparseGrid& g);

} // namespace iso
