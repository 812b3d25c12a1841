// Edges bucketed by their lower vertex (edges.hpp): a counting sort in two
// parallel passes over the triangles, the counts and the slots taken with
// relaxed atomic increments.
#include "renderer/surface/edges.hpp"

#include <algorithm>
#include <atomic>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace iso {

EdgeBuckets bucket_edges(std::span<const std::array<std::uint32_t, 3>> W, std::size_t nv, bool skip_collapsed) {
    const std::size_t nt = W.size();
    const auto collapsed = [&](const std::array<std::uint32_t, 3>& w) {
        return skip_collapsed && (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]);
    };
    EdgeBuckets e;
    auto& off = e.offset;
    off.assign(nv + 1, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const auto& w = W[t];
            if (collapsed(w)) continue;
            for (int k = 0; k < 3; ++k)
                std::atomic_ref<std::uint32_t>(off[std::min(w[k], w[(k + 1) % 3]) + 1])
                    .fetch_add(1, std::memory_order_relaxed);
        }
    });
    std::partial_sum(off.begin(), off.end(), off.begin());
    e.entries.resize(off[nv]);
    std::vector<std::uint32_t> cursor(off.begin(), off.end() - 1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const auto& w = W[t];
            if (collapsed(w)) continue;
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = w[k], b = w[(k + 1) % 3];
                const std::uint32_t l = std::min(a, b), u = std::max(a, b);
                const std::uint32_t slot =
                    std::atomic_ref<std::uint32_t>(cursor[l]).fetch_add(1, std::memory_order_relaxed);
                e.entries[slot] = (u << 1) | std::uint32_t(a < b);
            }
        }
    });
    return e;
}

} // namespace iso
