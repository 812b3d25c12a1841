// The streaming planner's sizes that the driver also counts (stream_plan.cpp):
// the engine's memory accounting starts from the same figures the plan was
// made with, so that StreamStats::peak_bytes and the plan agree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/volume_stream.hpp"
#include "renderer/surface/extract.hpp"

namespace iso::detail {

// "12.3 MiB", as the engine's messages give sizes.
std::string mib(std::size_t bytes);

// The index's own size for `chunks` chunks (min, max and flags per chunk).
std::size_t index_bytes(std::size_t chunks);

// Does chunk `id` hold a surface of `values`? Labels also look just above
// each value: a label surface is the iso surface between v and the next value.
bool chunk_active(const ChunkIndex& idx, std::size_t id, const std::vector<double>& values, bool labels);

// The index pass's slabs: each slice costs `slice`, any slab the reader's
// extra slices (OpenVDB) once, besides `fixed` (two copies of the index and a
// read buffer); `per` slices a slab, as many as fit the budget (at least one).
struct IndexPassSlabs {
    std::size_t slice = 0, fixed = 0;
    std::int64_t per = 1;
};
IndexPassSlabs index_pass_slabs(const VolumeHeader& h, std::size_t chunks, std::size_t memory_budget);

} // namespace iso::detail
