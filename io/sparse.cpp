#include "io/sparse.hpp"

#include <cmath>
#include <limits>

namespace iso {

std::size_t sparse_memory_bytes(const SparseGrid& g) { return static_cast<std::size_t>(g.grid->memUsage()); }

double sparse_value(const SparseGrid& g, std::int64_t i, std::int64_t j, std::int64_t k) {
    const openvdb::Coord c(static_cast<int>(i) + g.offset.x(), static_cast<int>(j) + g.offset.y(),
                           static_cast<int>(k) + g.offset.z());
    return g.grid->tree().getValue(c);
}

ValueRange sparse_value_range(const SparseGrid& g) {
    ValueRange r;
    double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
    auto visit = [&](float x) {
        if (std::isnan(x)) {
            ++r.nan_count;
            return;
        }
        if (std::isinf(x)) {
            ++r.inf_count;
            return;
        }
        lo = std::min(lo, double(x));
        hi = std::max(hi, double(x));
    };
    // Active values (tiles count once: the value is the same over the tile)
    // plus the background, which every inactive voxel takes.
    for (auto it = g.grid->cbeginValueOn(); it; ++it) visit(*it);
    visit(g.grid->background());
    if (lo <= hi) {
        r.min = lo;
        r.max = hi;
    }
    return r;
}

} // namespace iso
