#include "renderer/lod/cluster_lod.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>

#include <glm/glm.hpp>
#include <meshoptimizer.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

namespace iso::lod {

namespace {

using Tri = std::array<std::uint32_t, 3>;

struct Box {
    glm::vec3 lo{1e30f}, hi{-1e30f};
    void add(const glm::vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
};

// A triangle's centroid and id, packed so that the median splits move
// memory in order instead of chasing ids into a centroid array.
struct Key {
    glm::vec3 c;
    std::uint32_t id;
};

// Splits `keys` at the median of the longest axis of their bounds until each
// part holds at most `leaf`; the parts, in order, as [begin, end) offsets.
// Parallel above 64k.
void split(Key* keys, std::size_t begin, std::size_t end, std::size_t leaf,
           std::vector<std::pair<std::size_t, std::size_t>>& out) {
    if (end - begin <= leaf) {
        if (end > begin) out.emplace_back(begin, end);
        return;
    }
    Box b;
    for (std::size_t i = begin; i < end; ++i) b.add(keys[i].c);
    const glm::vec3 e = b.hi - b.lo;
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(keys + begin, keys + mid, keys + end, [axis](const Key& a, const Key& c) {
        return a.c[axis] < c.c[axis] || (a.c[axis] == c.c[axis] && a.id < c.id); // ties by id: the same cells every run
    });
    if (end - begin < 65536) {
        split(keys, begin, mid, leaf, out);
        split(keys, mid, end, leaf, out);
        return;
    }
    std::vector<std::pair<std::size_t, std::size_t>> right;
    tbb::parallel_invoke([&] { split(keys, begin, mid, leaf, out); }, [&] { split(keys, mid, end, leaf, right); });
    out.insert(out.end(), right.begin(), right.end());
}

// Global vertex ids to a cell's local ones, in first-seen order (open
// addressing: a cell has a few ten thousand vertices).
class LocalIds {
public:
    explicit LocalIds(std::size_t expected) {
        std::size_t cap = 64;
        while (cap < 2 * expected) cap *= 2;
        slots_.assign(cap, {kEmpty, 0});
    }
    std::uint32_t operator()(std::uint32_t g) {
        std::size_t h = (g * 0x9E3779B1u) & (slots_.size() - 1);
        while (slots_[h].first != kEmpty && slots_[h].first != g) h = (h + 1) & (slots_.size() - 1);
        if (slots_[h].first == kEmpty) {
            slots_[h] = {g, std::uint32_t(global.size())};
            global.push_back(g);
        }
        return slots_[h].second;
    }
    std::vector<std::uint32_t> global; // local id -> global id

private:
    static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> slots_;
};

// One level of one cell cut into clusters: their triangles (global vertex
// ids) in cluster order, and the clusters (first_index relative to them).
struct LevelOut {
    std::vector<std::uint32_t> indices;
    std::vector<Cluster> clusters;
    std::vector<std::uint32_t> order; // level 0: the mesh's triangle of each, in the same order
};

Cluster cluster_of(const std::vector<glm::vec3>& pos, const std::uint32_t* tri, std::size_t n) {
    Cluster c;
    Box b;
    glm::dvec3 sum(0.0);
    std::vector<glm::vec3> normals;
    normals.reserve(n);
    for (std::size_t t = 0; t < n; ++t) {
        const glm::vec3 a = pos[tri[3 * t]], p = pos[tri[3 * t + 1]], q = pos[tri[3 * t + 2]];
        b.add(a);
        b.add(p);
        b.add(q);
        const glm::vec3 fn = glm::cross(p - a, q - a);
        const float len = glm::length(fn);
        if (!(len > 0.0f)) continue; // degenerate: faces nowhere, draws nothing
        normals.push_back(fn / len);
        sum += glm::dvec3(normals.back());
    }
    c.lo = b.lo;
    c.hi = b.hi;
    c.centre = 0.5f * (b.lo + b.hi);
    c.radius = 0.5f * glm::length(b.hi - b.lo);
    const double len = glm::length(sum);
    if (len > 1e-6 * double(normals.size()) && !normals.empty()) {
        c.axis = glm::vec3(sum / len);
        float m = 1.0f;
        for (const auto& nn : normals) m = std::min(m, glm::dot(nn, c.axis));
        // A cone of 90 degrees or more culls nothing; keep a margin for rounding.
        c.cos_angle = m > 1e-3f ? m - 1e-4f : -1.0f;
    }
    return c;
}

// `tris` (global vertex ids, 3 each) cut into clusters of at most `leaf`
// triangles, spatially; `ids` (the mesh's triangle of each, or empty).
LevelOut clusters_of(const std::vector<std::uint32_t>& tris, const std::vector<std::uint32_t>& ids,
                     const std::vector<glm::vec3>& pos, std::size_t leaf) {
    const std::size_t n = tris.size() / 3;
    std::vector<Key> keys(n);
    for (std::size_t t = 0; t < n; ++t)
        keys[t] = {(pos[tris[3 * t]] + pos[tris[3 * t + 1]] + pos[tris[3 * t + 2]]) / 3.0f, std::uint32_t(t)};
    std::vector<std::pair<std::size_t, std::size_t>> parts;
    split(keys.data(), 0, n, leaf, parts);
    LevelOut out;
    out.indices.reserve(tris.size());
    if (!ids.empty()) out.order.reserve(n);
    for (const auto& [b, e] : parts) {
        const std::size_t first = out.indices.size();
        for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t t = keys[i].id;
            out.indices.insert(out.indices.end(), {tris[3 * t], tris[3 * t + 1], tris[3 * t + 2]});
            if (!ids.empty()) out.order.push_back(ids[t]);
        }
        Cluster c = cluster_of(pos, out.indices.data() + first, e - b);
        c.first_index = std::uint32_t(first);
        c.index_count = std::uint32_t(3 * (e - b));
        out.clusters.push_back(c);
    }
    return out;
}

// The longest edge of `tris`.
float longest_edge(const std::vector<std::uint32_t>& tris, const std::vector<glm::vec3>& pos) {
    float longest = 0.0f;
    for (std::size_t i = 0; i < tris.size(); i += 3)
        for (int k = 0; k < 3; ++k)
            longest = std::max(longest,
                               glm::distance(pos[tris[i + std::size_t(k)]], pos[tris[i + std::size_t((k + 1) % 3)]]));
    return longest;
}

struct CellOut {
    Cell cell;
    std::vector<LevelOut> levels;
};

// One cell: its levels (simplified from the one before, border locked) and clusters.
CellOut build_cell(const Mesh& m, const Key* tri, std::size_t n, const BuildOptions& o) {
    // Local vertices for the simplifier (its memory is per vertex given).
    LocalIds local(2 * n / 3 + 16);
    std::vector<std::uint32_t> level(3 * n), ids(n);
    for (std::size_t i = 0; i < n; ++i) {
        ids[i] = tri[i].id;
        for (int k = 0; k < 3; ++k) level[3 * i + std::size_t(k)] = local(m.triangles[tri[i].id][std::size_t(k)]);
    }
    const std::vector<std::uint32_t>& global = local.global;
    std::vector<glm::vec3> local_pos(global.size());
    for (std::size_t i = 0; i < global.size(); ++i) local_pos[i] = m.positions[global[i]];
    CellOut out;
    Box b;
    for (const auto& p : local_pos) b.add(p);
    out.cell.lo = b.lo;
    out.cell.hi = b.hi;
    const float scale = meshopt_simplifyScale(&local_pos[0].x, local_pos.size(), sizeof(glm::vec3));
    float error = 0.0f;
    for (int l = 0;; ++l) {
        out.cell.geometric[std::size_t(l)] = error;
        // Never below the finer level's (coarser levels are chosen only farther away).
        if (l > 0)
            out.cell.error[std::size_t(l)] =
                std::max({error, 0.5f * longest_edge(level, local_pos), out.cell.error[std::size_t(l - 1)]});
        out.levels.push_back(
            clusters_of(level, l == 0 ? ids : std::vector<std::uint32_t>{}, local_pos, o.cluster_triangles));
        out.cell.levels = std::uint32_t(l + 1);
        if (l + 1 >= kMaxLevels || level.size() < 3 * 64) break;
        std::vector<std::uint32_t> next(level.size());
        const std::size_t target = std::size_t(double(level.size() / 3) * o.level_ratio) * 3;
        float step_error = 0.0f;
        next.resize(meshopt_simplify(next.data(), level.data(), level.size(), &local_pos[0].x, local_pos.size(),
                                     sizeof(glm::vec3), target, 1.0f, meshopt_SimplifyLockBorder, &step_error));
        if (double(next.size()) > o.min_reduction * double(level.size()) || next.empty()) break;
        error += step_error * scale;
        level = std::move(next);
    }
    // Back to the mesh's vertex ids (the clusters' bounds and cones, made
    // from the local copies of the same positions, stay as they are).
    for (auto& lv : out.levels)
        for (auto& v : lv.indices) v = global[v];
    return out;
}

} // namespace

std::size_t ClusterLod::memory_bytes() const {
    return indices.size() * 4 + triangle_order.size() * 4 + cells.size() * sizeof(Cell) +
           clusters.size() * sizeof(Cluster);
}

ClusterLod build_cluster_lod(const Mesh& m, const BuildOptions& o, const ProgressFn& progress) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t n = m.triangles.size();
    std::vector<Key> keys(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 16), [&](const auto& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            const auto& tr = m.triangles[t];
            keys[t] = {(m.positions[tr[0]] + m.positions[tr[1]] + m.positions[tr[2]]) / 3.0f, std::uint32_t(t)};
        }
    });
    std::vector<std::pair<std::size_t, std::size_t>> parts;
    const std::size_t leaf = n < 2 * o.cell_triangles ? std::max<std::size_t>(n, 1) : o.cell_triangles;
    split(keys.data(), 0, n, leaf, parts);
    std::vector<CellOut> cells(parts.size());
    std::atomic<std::size_t> done{0};
    std::atomic<bool> stop{false};
    tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
        if (stop) return;
        cells[c] = build_cell(m, keys.data() + parts[c].first, parts[c].second - parts[c].first, o);
        const std::size_t k = ++done;
        if (progress && (k % 16 == 0 || k == parts.size()) && !progress(double(k) / double(parts.size()), "levels"))
            stop = true;
    });
    if (stop) throw Cancelled("levels of detail");
    ClusterLod out;
    out.indices.reserve(n * 3 + n);
    out.triangle_order.reserve(n);
    // Level 0 of every cell first (the whole mesh, contiguous), then the coarser levels.
    std::vector<std::vector<Cluster>> per_cell(cells.size());
    for (int l = 0; l < kMaxLevels; ++l)
        for (std::size_t c = 0; c < cells.size(); ++c) {
            auto& co = cells[c];
            if (std::size_t(l) >= co.levels.size()) {
                if (l > 0) out.level_triangles[std::size_t(l)] += co.levels.back().indices.size() / 3;
                continue;
            }
            auto& lv = co.levels[std::size_t(l)];
            const std::uint32_t base = std::uint32_t(out.indices.size());
            out.indices.insert(out.indices.end(), lv.indices.begin(), lv.indices.end());
            if (l == 0) out.triangle_order.insert(out.triangle_order.end(), lv.order.begin(), lv.order.end());
            for (auto cl : lv.clusters) {
                cl.first_index += base;
                cl.cell = std::uint32_t(c);
                cl.level = std::uint32_t(l);
                per_cell[c].push_back(cl);
            }
            out.level_triangles[std::size_t(l)] += lv.indices.size() / 3;
            out.max_levels = std::max(out.max_levels, l + 1);
            lv = LevelOut{};
            if (l == 0) out.level0_indices = out.indices.size();
        }
    for (std::size_t c = 0; c < cells.size(); ++c) {
        cells[c].cell.first_cluster = std::uint32_t(out.clusters.size());
        out.cells.push_back(cells[c].cell);
        out.clusters.insert(out.clusters.end(), per_cell[c].begin(), per_cell[c].end());
    }
    build_proxies(m, out, o.proxy_triangles);
    out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

float error_limit_mm(const glm::vec3& eye, const glm::vec3& lo, const glm::vec3& hi, float pixels_per_mm_at_1mm,
                     float max_error_px, float near_plane) {
    const float d = std::max(glm::length(eye - glm::clamp(eye, lo, hi)), near_plane);
    return max_error_px * d / pixels_per_mm_at_1mm;
}

std::uint32_t select_level(const Cell& cell, const glm::vec3& eye, float pixels_per_mm_at_1mm, float max_error_px,
                           float near_plane) {
    const float limit = error_limit_mm(eye, cell.lo, cell.hi, pixels_per_mm_at_1mm, max_error_px, near_plane);
    for (std::uint32_t l = cell.levels; l-- > 1;)
        if (cell.error[l] <= limit) return l;
    return 0;
}

} // namespace iso::lod
