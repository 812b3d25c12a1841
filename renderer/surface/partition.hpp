// Splitting a volume's chunks among the ranks of an MPI job (docs/cluster.md,
// "Plan"). Chunk ids are cut into contiguous ranges (a range of ids is a run
// of whole chunk rows and layers: a rank reads only the k-slices its chunks
// need) balanced by the work each chunk costs: the number of surfaces it can
// hold by the min/max index. Chunks that no surface crosses cost nothing (the
// extractor skips them without reading a sample), so they do not count.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "renderer/surface/components.hpp"
#include "renderer/surface/extract.hpp"

namespace iso {

// The work of each chunk for these surfaces: how many of `values` it can hold
// (iso values; with `labels`, label values, active as in extract_labels()).
std::vector<std::uint32_t> chunk_weights(const ChunkIndex& index, std::span<const double> values, bool labels = false);

// Cuts [0, weights.size()) into `nranks` contiguous ranges, in rank order,
// covering every id once, whose weight sums differ as little as contiguity
// allows: range r ends where the running weight first reaches r+1 / nranks of
// the total (rounded to nearest). Zero-weight chunks between two ranges go to
// the later one. A range may be empty (more ranks than weighted chunks: the
// rank still takes part and writes an empty piece). nranks >= 1.
std::vector<ChunkRange> partition_weights(std::span<const std::uint32_t> weights, int nranks);

// partition_weights(chunk_weights(index, values, labels), nranks).
std::vector<ChunkRange> partition_chunks(const ChunkIndex& index, std::span<const double> values, int nranks,
                                         bool labels = false);

} // namespace iso
