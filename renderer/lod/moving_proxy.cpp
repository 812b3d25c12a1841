// Stand-ins for massive surfaces while the camera moves (cluster_lod.hpp,
// Proxy): vertex clustering (Rossignac and Borrel), what ParaView draws
// while interacting (vtkQuadricClustering), here on the cells' coarsest
// levels of detail and keeping the mesh's own vertices, so that a stand-in
// is a range of indices into the vertex buffer already on the GPU.
//
// Written here rather than with libmeshoptimizer's meshopt_simplifySloppy
// (0.18, experimental): it chooses its grid per call by a binary search of
// whole passes on one thread, so it could not run per cell (cells
// simplified apart would not meet) and takes seconds on the whole mesh;
// one grid for the whole surface is one parallel sort of the vertices and
// its error is the grid cell's diagonal, which a frame can project.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>

#include <glm/glm.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "renderer/lod/cluster_lod.hpp"

namespace iso::lod {

namespace {

using Tri = std::array<std::uint32_t, 3>;
constexpr std::uint32_t kDropped = std::numeric_limits<std::uint32_t>::max();

// A used vertex in its grid cell: the key of the cell, its squared distance
// to the cell's centre, and its index in the sorted list of used vertices.
struct Slot {
    std::uint64_t key;
    float d2;
    std::uint32_t u;
    bool operator<(const Slot& o) const { return key != o.key ? key < o.key : d2 != o.d2 ? d2 < o.d2 : u < o.u; }
};

Slot slot_of(const glm::vec3& p, const glm::vec3& origin, float cell, std::uint32_t u) {
    constexpr float kMax = float((1u << 21) - 1);
    const glm::vec3 i = glm::clamp(glm::floor((p - origin) / cell), glm::vec3(0.0f), glm::vec3(kMax));
    const glm::vec3 d = p - (origin + (i + 0.5f) * cell);
    const auto k = [&](int a) { return std::uint64_t(i[a]); };
    return {k(0) | (k(1) << 21) | (k(2) << 42), glm::dot(d, d), u};
}

// The triangle turned so that its lowest vertex comes first (its winding
// kept), or all kDropped when two corners are one vertex.
Tri canonical(const Tri& t) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return {kDropped, kDropped, kDropped};
    const int m = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
    return {t[std::size_t(m)], t[std::size_t((m + 1) % 3)], t[std::size_t((m + 2) % 3)]};
}

// What the stand-ins start from: each cell's coarsest level whose own
// error is at most `max_error` mm (level 0 where none is), all cells;
// `error` is the largest of the levels taken.
std::vector<Tri> cell_levels(const ClusterLod& lod, float max_error, float& error) {
    std::vector<Tri> tris;
    error = 0.0f;
    for (std::size_t c = 0; c < lod.cells.size(); ++c) {
        const Cell& cell = lod.cells[c];
        std::uint32_t level = cell.levels - 1;
        while (level > 0 && cell.geometric[level] > max_error) --level;
        error = std::max(error, cell.geometric[level]);
        for (std::size_t k = cell.first_cluster; k < lod.clusters.size() && lod.clusters[k].cell == c; ++k) {
            const Cluster& cl = lod.clusters[k];
            if (cl.level != level) continue;
            for (std::uint32_t i = 0; i < cl.index_count; i += 3) {
                const std::uint32_t* v = &lod.indices[cl.first_index + i];
                tris.push_back({v[0], v[1], v[2]});
            }
        }
    }
    return tris;
}

double area_of(const std::vector<Tri>& tris, const std::vector<glm::vec3>& pos) {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, tris.size(), 1 << 14), 0.0,
        [&](const auto& r, double a) {
            for (std::size_t t = r.begin(); t < r.end(); ++t) {
                const Tri& x = tris[t];
                a += 0.5 * double(glm::length(glm::cross(pos[x[1]] - pos[x[0]], pos[x[2]] - pos[x[0]])));
            }
            return a;
        },
        std::plus<>());
}

} // namespace

std::vector<Tri> cluster_vertices(const std::vector<Tri>& tris, const std::vector<glm::vec3>& positions,
                                  const glm::vec3& origin, float cell) {
    std::vector<std::uint32_t> used(tris.size() * 3);
    tbb::parallel_for(std::size_t(0), tris.size(), [&](std::size_t t) {
        for (std::size_t k = 0; k < 3; ++k) used[3 * t + k] = tris[t][k];
    });
    tbb::parallel_sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    std::vector<Slot> slots(used.size());
    tbb::parallel_for(std::size_t(0), used.size(),
                      [&](std::size_t u) { slots[u] = slot_of(positions[used[u]], origin, cell, std::uint32_t(u)); });
    tbb::parallel_sort(slots.begin(), slots.end());
    // Every used vertex's representative: the first of its cell's slots.
    std::vector<std::uint32_t> rep(used.size());
    for (std::size_t i = 0, first = 0; i < slots.size(); ++i) {
        if (slots[i].key != slots[first].key) first = i;
        rep[slots[i].u] = used[slots[first].u];
    }
    const auto rep_of = [&](std::uint32_t v) {
        return rep[std::size_t(std::lower_bound(used.begin(), used.end(), v) - used.begin())];
    };
    std::vector<Tri> out(tris.size());
    tbb::parallel_for(std::size_t(0), tris.size(), [&](std::size_t t) {
        out[t] = canonical({rep_of(tris[t][0]), rep_of(tris[t][1]), rep_of(tris[t][2])});
    });
    tbb::parallel_sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    out.erase(std::lower_bound(out.begin(), out.end(), Tri{kDropped, kDropped, kDropped}), out.end());
    return out;
}

void build_proxies(const Mesh& m, ClusterLod& lod, const std::vector<std::size_t>& targets) {
    lod.proxies.clear();
    const std::size_t full = lod.level0_indices / 3;
    float error = 0.0f;
    std::vector<Tri> tris = cell_levels(lod, std::numeric_limits<float>::max(), error);
    if (tris.empty()) return;
    glm::vec3 origin(std::numeric_limits<float>::max());
    for (const Cell& c : lod.cells) origin = glm::min(origin, c.lo);
    // The surface's area, from the coarsest levels (simplification keeps it
    // closely): a surface crossing a grid of cell s leaves about 2 A / s^2
    // triangles.
    const double area = area_of(tris, m.positions);
    for (const std::size_t target : targets) {
        if (8 * target > full || !(area > 0.0)) continue;
        const float cell = float(std::sqrt(2.0 * area / double(target)));
        // From each cell's coarsest level within half the grid's cell (the
        // simplifier's error stays below the grid's), each stand-in from
        // the levels rather than from the one before, so that errors do not add up.
        const auto kept = cluster_vertices(cell_levels(lod, 0.5f * cell, error), m.positions, origin, cell);
        if (kept.empty()) break;
        error += std::sqrt(3.0f) * cell; // a vertex moves at most its grid cell's diagonal
        Proxy p;
        p.first_index = std::uint32_t(lod.indices.size());
        p.index_count = std::uint32_t(3 * kept.size());
        p.error = error;
        p.cell = cell;
        for (const Tri& t : kept) lod.indices.insert(lod.indices.end(), t.begin(), t.end());
        lod.proxies.push_back(p);
    }
}

} // namespace iso::lod
