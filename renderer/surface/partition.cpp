// Contiguous, weight-balanced ranges of chunk ids (partition.hpp).
#include "renderer/surface/partition.hpp"

#include <cmath>

#include "io/error.hpp"

namespace iso {

std::vector<std::uint32_t> chunk_weights(const ChunkIndex& index, std::span<const double> values, bool labels) {
    std::vector<std::uint32_t> w(index.chunk_count(), 0);
    for (std::size_t id = 0; id < w.size(); ++id)
        for (double v : values)
            w[id] +=
                labels ? (index.active(id, v) || index.active(id, std::nextafter(v, HUGE_VAL))) : index.active(id, v);
    return w;
}

std::vector<ChunkRange> partition_weights(std::span<const std::uint32_t> weights, int nranks) {
    if (nranks < 1) throw Error("partition_chunks", "need at least one rank");
    std::uint64_t total = 0;
    for (auto w : weights) total += w;
    std::vector<ChunkRange> out(static_cast<std::size_t>(nranks));
    // Rank r ends after the chunk where the running sum first reaches
    // round((r + 1) * total / nranks); zero-weight chunks after it start the next.
    std::size_t id = 0;
    std::uint64_t run = 0;
    for (int r = 0; r < nranks; ++r) {
        out[r].first = id;
        if (r == nranks - 1) {
            id = weights.size();
        } else {
            const std::uint64_t target =
                (std::uint64_t(r + 1) * total * 2 + std::uint64_t(nranks)) / (2 * std::uint64_t(nranks));
            while (run < target && id < weights.size()) run += weights[id++];
        }
        out[r].last = id;
    }
    if (total == 0) { // nothing to do anywhere: rank 0 takes every (empty) chunk
        out[0] = {0, weights.size()};
        for (int r = 1; r < nranks; ++r) out[r] = {weights.size(), weights.size()};
    }
    return out;
}

std::vector<ChunkRange> partition_chunks(const ChunkIndex& index, std::span<const double> values, int nranks,
                                         bool labels) {
    const auto w = chunk_weights(index, values, labels);
    return partition_weights(w, nranks);
}

} // namespace iso
