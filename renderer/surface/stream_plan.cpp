// The streaming planner (stream.hpp's plan_stream, docs/isosurface.md "Out of
// core"): what the engine holds for a chunk size and a slab height, and the
// tallest slabs that fit the memory budget.
#include "renderer/surface/stream_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "renderer/surface/arena.hpp"
#include "renderer/surface/stream.hpp"

namespace iso {

namespace {

constexpr std::size_t kMiB = std::size_t(1) << 20;

// Conversion buffer of a slab read: volume_stream.cpp converts 1 MiB (at
// least a slice) at a time when the stored type or values change; samples
// read as they are stored go straight into the slab.
std::size_t read_buffer(const VolumeHeader& h) {
    if (!h.rescale && h.type == h.stored) return 0;
    return std::max(kMiB, std::size_t(h.dims[0] * h.dims[1]) * voxel_size(h.stored));
}

} // namespace

namespace detail {

std::string mib(std::size_t bytes) {
    char s[32];
    std::snprintf(s, sizeof s, "%.1f MiB", double(bytes) / double(kMiB));
    return s;
}

std::size_t index_bytes(std::size_t chunks) { return chunks * (2 * sizeof(double) + 2 * sizeof(double) + 1); }

bool chunk_active(const ChunkIndex& idx, std::size_t id, const std::vector<double>& values, bool labels) {
    for (double v : values) {
        if (idx.active(id, v)) return true;
        if (labels && idx.active(id, std::nextafter(v, HUGE_VAL))) return true;
    }
    return false;
}

IndexPassSlabs index_pass_slabs(const VolumeHeader& h, std::size_t chunks, std::size_t memory_budget) {
    IndexPassSlabs s;
    s.slice = std::size_t(h.slab_memory_bytes(1) - h.slab_memory_bytes(0));
    s.fixed = 2 * index_bytes(chunks) + read_buffer(h) + std::size_t(h.slab_memory_bytes(0));
    s.per = std::max<std::int64_t>(1, memory_budget > s.fixed ? std::int64_t((memory_budget - s.fixed) / s.slice) : 1);
    return s;
}

} // namespace detail

namespace {

using detail::mib;

std::size_t scratch_bytes(int C, std::size_t sample) {
    // As Extractor's scratch_estimate, plus the staging mesh of one chunk.
    const std::size_t n = std::size_t(C + 1), h = std::size_t(C + 3);
    return h * h * h * sample + n * n * n * (1 + 4 * sizeof(std::uint32_t)) + n + std::size_t(C) * C * 96;
}

// Output of one active chunk: about 2 C^2 triangles and C^2 vertices for a
// surface crossing it, held as chunk meshes (with their border lists and
// vector slack) and once welded, with margin for oblique and folded surfaces,
// plus the chunk's own vectors (the measured peak is reported).
std::size_t chunk_output_estimate(int C) { return std::size_t(C) * std::size_t(C) * 256 + 2048; }

std::array<int, 3> chunk_counts(const std::array<std::int64_t, 3>& dims, int C) {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) c[a] = int((std::max<std::int64_t>(dims[a] - 1, 0) + C - 1) / C);
    return c;
}

std::size_t surface_count(const StreamOptions& opt) {
    return std::max<std::size_t>(1, opt.labels ? opt.label_values.size() : opt.isos.size());
}

// What is held whatever the slab height: the index; per surface, the chunk
// table extract_chunks() returns; each thread's scratch; the read buffer.
std::size_t fixed_bytes(const VolumeHeader& h, const StreamOptions& opt, int C) {
    const auto c = chunk_counts(h.dims, C);
    const std::size_t n = std::size_t(c[0]) * c[1] * c[2];
    const std::size_t threads = std::size_t(effective_threads(opt.extract.threads));
    return detail::index_bytes(n) + surface_count(opt) * n * sizeof(ChunkMesh) +
           threads * scratch_bytes(C, voxel_size(h.type)) + read_buffer(h);
}

std::size_t slab_bytes(const VolumeHeader& h, int C, int layers) {
    const std::int64_t slices = std::min<std::int64_t>(std::int64_t(layers) * C + 3, h.dims[2]);
    return std::size_t(h.slab_memory_bytes(slices));
}

// Not even one chunk layer's slab fits beside the fixed costs.
Error budget_too_small(const VolumeHeader& h, const StreamOptions& opt, int C, std::size_t needed) {
    return Error("memory budget", mib(opt.memory_budget) + " is too small for this volume: one slab of " +
                                      std::to_string(std::min<std::int64_t>(C + 3, h.dims[2])) + " slices (" +
                                      std::to_string(h.dims[0]) + " x " + std::to_string(h.dims[1]) + " " +
                                      voxel_type_name(h.type) + ") with chunk size " + std::to_string(C) + " needs " +
                                      mib(needed));
}

// The chunk layers [first_layer, first_layer + layers) that hold the chunk ids
// [first, last), `layer` chunks each.
struct LayerRange {
    int first_layer = 0, layers = 0;
    std::size_t layer = 0, first = 0, last = 0;
};

// Active chunks of the range per layer (every chunk of it, without an index).
std::vector<std::size_t> active_per_layer(const ChunkIndex* index, const StreamOptions& opt, const LayerRange& r) {
    std::vector<std::size_t> active(std::size_t(r.layers), r.layer);
    if (!index) return active;
    const std::vector<double>& values = opt.labels ? opt.label_values : opt.isos;
    for (int l = 0; l < r.layers; ++l) {
        std::size_t n = 0;
        const std::size_t base = std::size_t(r.first_layer + l) * r.layer;
        for (std::size_t id = std::max(base, r.first); id < std::min(base + r.layer, r.last); ++id)
            n += detail::chunk_active(*index, id, values, opt.labels);
        active[std::size_t(l)] = n;
    }
    return active;
}

// The tallest slabs (at most `max_layers` chunk layers) whose samples and
// estimated output fit with `in_flight` of each held at once: with overlap,
// two slabs' samples (one extracted, the next read) and two slabs' output
// (one welded and written, the next extracted).
void choose_layers(StreamPlan& p, const VolumeHeader& h, const StreamOptions& opt,
                   const std::vector<std::size_t>& active, int max_layers, std::size_t per_chunk,
                   std::size_t in_flight) {
    const int layers = int(active.size());
    int best = 1;
    bool fits = false;
    std::size_t estimate = 0;
    for (int L = 1; L <= max_layers; ++L) {
        std::size_t worst = 0;
        for (int l = 0; l < layers; l += L) {
            std::size_t n = 0;
            for (int j = l; j < std::min(l + L, layers); ++j) n += active[std::size_t(j)];
            worst = std::max(worst, n);
        }
        if (p.fixed_bytes + in_flight * (slab_bytes(h, p.chunk_size, L) + worst * per_chunk) > opt.memory_budget) break;
        best = L;
        fits = true;
        estimate = worst * per_chunk;
    }
    p.layers_per_slab = best;
    p.fits = fits;
    p.output_estimate = estimate;
}

// The plan for chunk size C; with `overlap`, two slabs' samples and output
// if they fit one chunk layer per slab (else StreamPlan::overlap is false and
// the slabs are planned one at a time).
StreamPlan plan_chunks(const VolumeHeader& h, const StreamOptions& opt, const ChunkIndex* index, int C, bool overlap) {
    StreamPlan p;
    p.chunk_size = C;
    p.fixed_bytes = fixed_bytes(h, opt, C);
    const auto counts = chunk_counts(h.dims, C);
    LayerRange r;
    r.layer = std::size_t(counts[0]) * counts[1];
    const std::size_t total = r.layer * std::size_t(counts[2]);
    r.first = std::min(opt.first_chunk, total);
    r.last = std::min(opt.last_chunk, total);
    if (r.first >= r.last) {
        p.slabs = 0;
        return p;
    }
    p.first_layer = r.first_layer = int(r.first / r.layer);
    p.last_layer = int((r.last - 1) / r.layer);
    r.layers = p.last_layer - p.first_layer + 1;
    if (p.fixed_bytes + slab_bytes(h, C, 1) > opt.memory_budget)
        throw budget_too_small(h, opt, C, p.fixed_bytes + slab_bytes(h, C, 1));
    const std::vector<std::size_t> active = active_per_layer(index, opt, r);
    const std::size_t per_chunk = chunk_output_estimate(C) * surface_count(opt);
    const int max_layers = opt.max_layers_per_slab > 0 ? std::min(opt.max_layers_per_slab, r.layers) : r.layers;
    p.overlap = false;
    if (overlap) {
        choose_layers(p, h, opt, active, max_layers, per_chunk, 2);
        p.overlap = p.fits;
    }
    if (!p.overlap) choose_layers(p, h, opt, active, max_layers, per_chunk, 1);
    p.slabs = std::size_t((r.layers + p.layers_per_slab - 1) / p.layers_per_slab);
    // One slab cannot overlap with anything.
    if (p.slabs < 2) p.overlap = false;
    p.slab_bytes = slab_bytes(h, C, p.layers_per_slab);
    return p;
}

// Without an index: the chunk size halves while the fixed costs and
// `in_flight` one-layer slabs do not fit and halving makes them smaller
// (more chunks cost more index and table entries), down to 4.
int fitting_chunk_size(const VolumeHeader& h, const StreamOptions& opt, std::size_t in_flight) {
    int c = opt.extract.chunk_size;
    while (c > 4) {
        const std::size_t now = fixed_bytes(h, opt, c) + in_flight * slab_bytes(h, c, 1);
        const std::size_t half = fixed_bytes(h, opt, c / 2) + in_flight * slab_bytes(h, c / 2, 1);
        if (now <= opt.memory_budget || half >= now) break;
        c /= 2;
    }
    return c;
}

} // namespace

StreamPlan plan_stream(const VolumeHeader& h, const StreamOptions& opt, const ChunkIndex* index) {
    if (index) return plan_chunks(h, opt, index, index->chunk_size(), opt.overlap);
    if (opt.extract.chunk_size < 2) throw Error("chunk size", "must be at least 2 cells");
    // With overlap the chunk size is first chosen for two one-layer slabs
    // (the one extracted and the next one read). If the overlapped plan does
    // not fit at that size, it is chosen again for one slab at a time (a
    // smaller chunk size would only cost).
    const int c1 = fitting_chunk_size(h, opt, 1);
    if (opt.overlap) {
        const int c2 = fitting_chunk_size(h, opt, 2);
        if (fixed_bytes(h, opt, c2) + 2 * slab_bytes(h, c2, 1) <= opt.memory_budget) {
            StreamPlan p = plan_chunks(h, opt, nullptr, c2, true);
            if (p.overlap || c2 == c1) return p;
        }
    }
    return plan_chunks(h, opt, nullptr, c1, false);
}

} // namespace iso
