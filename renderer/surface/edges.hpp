// The edges of a triangle list, bucketed by their lower vertex in parallel:
// the edge counts of a measured surface (analysis.cpp) and the boundary of a
// piece of a surface (components.cpp) are runs in these buckets.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace iso {

// Bucket l holds entries[offset[l], offset[l + 1]), one per use of an edge
// whose lower vertex is l: (upper << 1) | 1 when the triangle runs lower ->
// upper, (upper << 1) when it runs upper -> lower. Within a bucket the order
// is the threads' (sort a bucket before reading its runs). A triangle with a
// repeated vertex is left out with `skip_collapsed`; otherwise its edges
// count as any other's (a repeated vertex's edge is (l, l)).
// Needs vertices < 2^31 and 3 x triangles < 2^32 (EdgeBuckets::fits).
struct EdgeBuckets {
    std::vector<std::uint32_t> offset, entries;
    static bool fits(std::size_t vertices, std::size_t triangles) {
        return vertices < (std::size_t(1) << 31) && triangles < (std::size_t(1) << 30);
    }
};

EdgeBuckets bucket_edges(std::span<const std::array<std::uint32_t, 3>> triangles, std::size_t vertices,
                         bool skip_collapsed);

} // namespace iso
