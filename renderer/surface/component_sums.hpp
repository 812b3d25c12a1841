// Sums over each component's triangles that do not depend on the thread
// count: the measures of a surface (analysis.cpp) and of a piece of one
// (components.cpp) add their per-triangle terms this way.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

#include <tbb/parallel_for.h>

namespace iso {

inline constexpr std::uint32_t kNotInAComponent = ~std::uint32_t(0);

// Per component c < ncomp, `add(sum, t)` over its triangles t (comp(t) == c;
// items t of comp(t) == kNotInAComponent are left out):
// the triangles ordered by component (a stable counting sort), summed in
// fixed blocks of 16384 in parallel, each block's runs of one component kept
// as partial sums and the partials merged (`merge(into, partial)`) in block
// order. The same sums whatever the thread count; for up to one block, the
// sums in triangle order.
template <class Sum, class Comp, class Add, class Merge>
std::vector<Sum> sum_by_component(std::size_t nt, std::uint32_t ncomp, Comp comp, Add add, Merge merge) {
    std::vector<std::uint32_t> order;
    if (ncomp > 1) {
        std::vector<std::size_t> next(std::size_t(ncomp) + 1, 0);
        std::size_t kept = 0;
        for (std::size_t t = 0; t < nt; ++t)
            if (const std::uint32_t c = comp(t); c != kNotInAComponent) ++next[c + 1], ++kept;
        std::partial_sum(next.begin(), next.end(), next.begin());
        order.resize(kept);
        for (std::size_t t = 0; t < nt; ++t)
            if (const std::uint32_t c = comp(t); c != kNotInAComponent) order[next[c]++] = std::uint32_t(t);
        nt = kept;
    }
    struct Partial {
        std::uint32_t comp;
        Sum sum;
    };
    constexpr std::size_t kBlock = 16384;
    std::vector<std::vector<Partial>> partials((nt + kBlock - 1) / kBlock);
    tbb::parallel_for(std::size_t(0), partials.size(), [&](std::size_t blk) {
        auto& out = partials[blk];
        for (std::size_t o = blk * kBlock, e = std::min(nt, o + kBlock); o < e; ++o) {
            const std::size_t t = order.empty() ? o : order[o];
            const std::uint32_t c = comp(t);
            if (c == kNotInAComponent) continue;
            if (out.empty() || out.back().comp != c) out.push_back({c, Sum{}});
            add(out.back().sum, t);
        }
    });
    std::vector<Sum> sums(ncomp);
    for (const auto& blk : partials)
        for (const auto& part : blk) merge(sums[part.comp], part.sum);
    return sums;
}

} // namespace iso
