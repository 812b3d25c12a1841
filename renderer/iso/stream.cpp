#include "renderer/iso/stream.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <set>

#include "renderer/iso/arena.hpp"

namespace iso {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr std::size_t kMiB = std::size_t(1) << 20;
// Conversion buffer of a slab read: volume_stream.cpp converts 1 MiB (at
// least a slice) at a time when the stored type or values change; samples
// read as they are stored go straight into the slab.
std::size_t read_buffer(const VolumeHeader& h) {
    if (!h.rescale && h.type == h.stored) return 0;
    return std::max(kMiB, std::size_t(h.dims[0] * h.dims[1]) * voxel_size(h.stored));
}

std::string mib(std::size_t bytes) {
    char s[32];
    std::snprintf(s, sizeof s, "%.1f MiB", double(bytes) / double(kMiB));
    return s;
}

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

std::size_t index_bytes(std::size_t chunks) { return chunks * (2 * sizeof(double) + 2 * sizeof(double) + 1); }

std::array<int, 3> chunk_counts(const std::array<std::int64_t, 3>& dims, int C) {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) c[a] = int((std::max<std::int64_t>(dims[a] - 1, 0) + C - 1) / C);
    return c;
}

bool chunk_active(const ChunkIndex& idx, std::size_t id, const std::vector<double>& values, bool labels) {
    for (double v : values) {
        if (idx.active(id, v)) return true;
        if (labels && idx.active(id, std::nextafter(v, HUGE_VAL))) return true;
    }
    return false;
}

std::size_t fixed_bytes(const VolumeHeader& h, int C, std::size_t sample, int threads, std::size_t surfaces) {
    const auto c = chunk_counts(h.dims, C);
    const std::size_t n = std::size_t(c[0]) * c[1] * c[2];
    // Index; per surface, the chunk table extract_chunks() returns; scratch.
    return index_bytes(n) + surfaces * n * sizeof(ChunkMesh) + std::size_t(threads) * scratch_bytes(C, sample) + read_buffer(h);
}

std::size_t slab_bytes(const VolumeHeader& h, int C, int layers) {
    const std::int64_t slices = std::min<std::int64_t>(std::int64_t(layers) * C + 3, h.dims[2]);
    return std::size_t(h.slab_memory_bytes(slices));
}

std::size_t surface_count(const StreamOptions& opt) { return std::max<std::size_t>(1, opt.labels ? opt.label_values.size() : opt.isos.size()); }

} // namespace

StreamPlan plan_stream(const VolumeHeader& h, const StreamOptions& opt, const ChunkIndex* index) {
    StreamPlan p;
    const std::size_t sample = voxel_size(h.type);
    const int threads = effective_threads(opt.extract.threads);
    const std::size_t surfaces = surface_count(opt);
    int C = index ? index->chunk_size() : opt.extract.chunk_size;
    if (C < 2) throw Error("--chunk", "chunk size must be at least 2 cells");
    // Without an index: halve the chunk size while one chunk layer's samples
    // and the fixed costs do not fit and halving makes them smaller (more
    // chunks cost more index and table entries).
    if (!index)
        while (C > 4) {
            const std::size_t now = fixed_bytes(h, C, sample, threads, surfaces) + slab_bytes(h, C, 1);
            const std::size_t half = fixed_bytes(h, C / 2, sample, threads, surfaces) + slab_bytes(h, C / 2, 1);
            if (now <= opt.memory_budget || half >= now) break;
            C /= 2;
        }
    p.chunk_size = C;
    p.fixed_bytes = fixed_bytes(h, C, sample, threads, surfaces);
    const auto counts = chunk_counts(h.dims, C);
    const std::size_t layer = std::size_t(counts[0]) * counts[1];
    const std::size_t total = layer * std::size_t(counts[2]);
    const std::size_t first = std::min(opt.first_chunk, total), last = std::min(opt.last_chunk, total);
    if (first >= last) {
        p.slabs = 0;
        return p;
    }
    p.first_layer = int(first / layer);
    p.last_layer = int((last - 1) / layer);
    const int layers = p.last_layer - p.first_layer + 1;
    if (p.fixed_bytes + slab_bytes(h, C, 1) > opt.memory_budget)
        throw Error("--memory", mib(opt.memory_budget) + " is too small for this volume: one slab of " +
                                    std::to_string(std::min<std::int64_t>(C + 3, h.dims[2])) + " slices (" +
                                    std::to_string(h.dims[0]) + " x " + std::to_string(h.dims[1]) + " " +
                                    voxel_type_name(h.type) + ") with chunk size " + std::to_string(C) + " needs " +
                                    mib(p.fixed_bytes + slab_bytes(h, C, 1)));
    // Active chunks per layer (all chunks, without an index).
    std::vector<std::size_t> active(std::size_t(layers), layer);
    if (index) {
        const std::vector<double>& values = opt.labels ? opt.label_values : opt.isos;
        for (int l = 0; l < layers; ++l) {
            std::size_t n = 0;
            const std::size_t base = std::size_t(p.first_layer + l) * layer;
            for (std::size_t id = std::max(base, first); id < std::min(base + layer, last); ++id)
                n += chunk_active(*index, id, values, opt.labels);
            active[std::size_t(l)] = n;
        }
    }
    const std::size_t per_chunk = chunk_output_estimate(C) * surfaces;
    int best = 1;
    p.fits = false;
    for (int L = 1; L <= layers; ++L) {
        std::size_t worst = 0;
        for (int l = 0; l < layers; l += L) {
            std::size_t n = 0;
            for (int j = l; j < std::min(l + L, layers); ++j) n += active[std::size_t(j)];
            worst = std::max(worst, n);
        }
        if (p.fixed_bytes + slab_bytes(h, C, L) + worst * per_chunk > opt.memory_budget) break;
        best = L;
        p.fits = true;
        p.output_estimate = worst * per_chunk;
    }
    p.layers_per_slab = best;
    p.slabs = std::size_t((layers + best - 1) / best);
    p.slab_bytes = slab_bytes(h, C, best);
    return p;
}

std::shared_ptr<const ChunkIndex> build_chunk_index(VolumeStream& src, int chunk_size, std::size_t memory_budget,
                                                    const ProgressFn& progress, std::vector<double>* labels_out) {
    const VolumeHeader& h = src.header();
    // A slice more costs `slice`; any slab costs the reader's extra slices (OpenVDB) once.
    const std::size_t slice = std::size_t(h.slab_memory_bytes(1) - h.slab_memory_bytes(0));
    const auto counts = chunk_counts(h.dims, chunk_size);
    const std::size_t n = std::size_t(counts[0]) * counts[1] * counts[2];
    const std::size_t fixed = 2 * index_bytes(n) + read_buffer(h) + std::size_t(h.slab_memory_bytes(0));
    const std::int64_t per = std::max<std::int64_t>(1, memory_budget > fixed ? std::int64_t((memory_budget - fixed) / slice) : 1);
    ChunkSummaries sum(h.dims, chunk_size, h.type);
    std::set<double> labels;
    for (std::int64_t k0 = 0; k0 < h.dims[2]; k0 += per) {
        const std::int64_t k1 = std::min(k0 + per - 1, h.dims[2] - 1);
        report(progress, double(k0) / double(h.dims[2]), "indexing volume", "streaming");
        const Volume slab = src.read_slab(k0, k1);
        sum.add({&slab, h.dims, k0, h.index_to_lps});
        if (labels_out) {
            for (double v : distinct_labels(slab)) labels.insert(v);
            if (labels.size() > 4096)
                throw Error(h.path, "has more than 4096 distinct values: it does not look like a label map");
        }
    }
    report(progress, 1.0, "indexing volume", "streaming");
    if (labels_out) labels_out->assign(labels.begin(), labels.end());
    return std::make_shared<const ChunkIndex>(sum.finish());
}

StreamStats stream_extract(VolumeStream& src, const StreamOptions& opt_in, MeshSink& sink) {
    StreamOptions opt = opt_in;
    const VolumeHeader& h = src.header();
    StreamStats st;
    if (!opt.labels && opt.isos.empty()) throw Error("streaming", "no iso value");
    for (double v : opt.isos)
        if (!std::isfinite(v)) throw Error("extract", "iso value is not a finite number");
    const int threads = effective_threads(opt.extract.threads);
    std::shared_ptr<const ChunkIndex> index = opt.index;
    if (index && index->dims() != h.dims) throw Error("streaming", "the given chunk index is of another volume");
    const bool find_labels = opt.labels && opt.label_values.empty();
    if (opt.labels) {
        std::sort(opt.label_values.begin(), opt.label_values.end());
        opt.label_values.erase(std::unique(opt.label_values.begin(), opt.label_values.end()), opt.label_values.end());
    }
    // What the source holds (a volume loaded whole, a gzip stream's last slices) takes its share of the budget.
    if (src.resident_bytes() >= opt.memory_budget)
        throw Error("--memory", mib(opt.memory_budget) + " is less than the " + mib(src.resident_bytes()) +
                                    " the volume's source holds");
    opt.memory_budget -= src.resident_bytes();
    // 1. The index pass (its share of the progress: 30 %).
    const double index_share = index ? 0.0 : 0.3;
    auto sub = [&](double a, double b) -> ProgressFn {
        if (!opt.progress) return {};
        return [&, a, b](double f, std::string_view stage) { return opt.progress(a + (b - a) * f, stage); };
    };
    if (!index) {
        const StreamPlan pre = plan_stream(h, opt, nullptr);
        const auto t = Clock::now();
        std::vector<double> found;
        index = build_chunk_index(src, pre.chunk_size, opt.memory_budget, sub(0.0, index_share), find_labels ? &found : nullptr);
        if (find_labels) opt.label_values = found;
        st.index_pass = true;
        st.read_seconds += seconds_since(t);
        // The index pass held its index, a read buffer and slabs of as many slices as fit.
        const std::size_t slice = std::size_t(h.slab_memory_bytes(1) - h.slab_memory_bytes(0));
        const std::size_t idx_fixed = 2 * index_bytes(index->chunk_count()) + read_buffer(h) + std::size_t(h.slab_memory_bytes(0));
        const std::size_t slices = opt.memory_budget > idx_fixed ? std::max<std::size_t>(1, (opt.memory_budget - idx_fixed) / slice) : 1;
        st.peak_bytes = std::max(st.peak_bytes, idx_fixed + src.resident_bytes() +
                                                    std::min<std::size_t>(slices, std::size_t(h.dims[2])) * slice);
    }
    const std::vector<double>& values = opt.labels ? opt.label_values : opt.isos;
    st.values = values;
    const StreamPlan plan = plan_stream(h, opt, index.get());
    st.plan = plan;
    if (!plan.fits)
        st.warnings.push_back("the surface's estimated size in one chunk layer does not fit " + mib(opt.memory_budget) +
                              " with the samples: slabs of one layer, the output may exceed the budget (give more --memory or a smaller --chunk)");
    const std::size_t nsurf = values.size();
    sink.begin(nsurf, plan.slabs, opt.extract.normals);
    if (nsurf == 0 || plan.slabs == 0) {
        report(opt.progress, 1.0, "extracting isosurface", "streaming");
        sink.finish();
        return st;
    }
    const auto counts = index->counts();
    const std::size_t layer = index->layer_size(), total = index->chunk_count();
    const std::size_t first = std::min(opt.first_chunk, total), last = std::min(opt.last_chunk, total);
    const std::size_t fixed = index_bytes(total) + src.resident_bytes();

    ExtractOptions eo = opt.extract;
    eo.chunk_size = index->chunk_size();
    eo.memory_budget = opt.memory_budget;
    eo.threads = threads;
    eo.keep_keys = false;
    for (std::size_t i = 0; i < plan.slabs; ++i) {
        const int l0 = plan.first_layer + int(i) * plan.layers_per_slab;
        const int l1 = std::min(l0 + plan.layers_per_slab - 1, plan.last_layer);
        const std::size_t a = std::max(first, std::size_t(l0) * layer), b = std::min(last, std::size_t(l1 + 1) * layer);
        const double f0 = index_share + (1.0 - index_share) * double(i) / double(plan.slabs);
        const double f1 = index_share + (1.0 - index_share) * double(i + 1) / double(plan.slabs);
        report(opt.progress, f0, opt.labels ? "extracting label surfaces" : "extracting isosurface", "streaming");
        std::vector<std::size_t> ids;
        for (std::size_t id = a; id < b; ++id)
            if (chunk_active(*index, id, values, opt.labels)) ids.push_back(id);
        if (ids.empty()) {
            ++st.slabs_skipped;
            continue;
        }
        // 2. Read the slab: the layers' samples and their gradient halo.
        const std::int64_t k0 = Extractor::layer_samples(h.dims, index->chunk_size(), l0)[0];
        const std::int64_t k1 = Extractor::layer_samples(h.dims, index->chunk_size(), l1)[1];
        auto t = Clock::now();
        Volume slab = src.read_slab(k0, k1);
        st.read_seconds += seconds_since(t);
        ++st.slabs_read;
        st.chunks_visited += ids.size();
        // 3. Extract its chunks.
        t = Clock::now();
        const VolumeWindow w{&slab, h.dims, k0, h.index_to_lps};
        eo.progress = sub(f0, f0 + 0.8 * (f1 - f0));
        std::vector<ChunkedSurface> surfaces;
        ExtractStats es;
        if (opt.labels) {
            surfaces = extract_label_chunks(w, *index, values, ids, eo);
        } else {
            Extractor x(w, eo, index);
            surfaces = x.extract_chunks(values, ids, &es);
        }
        std::size_t held = slab.memory_bytes() + es.peak_scratch_bytes + fixed + sink.memory_bytes();
        for (const auto& s : surfaces) held += s.memory_bytes();
        st.peak_bytes = std::max(st.peak_bytes, held);
        held -= slab.memory_bytes();
        slab = Volume{}; // the samples are no longer needed
        st.extract_seconds += seconds_since(t);
        // 4. Weld each surface's piece and name its seam vertices: the border
        //    vertices of chunks with a neighbour outside [a, b).
        for (std::size_t s = 0; s < nsurf; ++s) {
            t = Clock::now();
            ChunkedSurface piece;
            piece.iso = surfaces[s].iso;
            std::vector<std::size_t> piece_ids;
            const std::size_t surface_bytes = surfaces[s].memory_bytes();
            for (auto id : ids)
                if (!surfaces[s].chunks[id].positions.empty()) {
                    piece.chunks.push_back(std::move(surfaces[s].chunks[id]));
                    piece_ids.push_back(id);
                }
            held -= surface_bytes;
            surfaces[s] = ChunkedSurface{};
            held += piece.memory_bytes();
            WeldMap map;
            MeshPiece mp;
            mp.surface = s;
            mp.index = i;
            mp.mesh = weld(piece, threads, &map);
            for (std::size_t j = 0; j < piece_ids.size(); ++j) {
                const auto c = index->coords(piece_ids[j]);
                bool lower = false, upper = false;
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                            if (x < 0 || y < 0 || z < 0 || x >= counts[0] || y >= counts[1] || z >= counts[2]) continue;
                            const std::size_t nid = std::size_t(x) + std::size_t(counts[0]) * (std::size_t(y) + std::size_t(counts[1]) * std::size_t(z));
                            lower |= nid < a;
                            upper |= nid >= b;
                        }
                if (!lower && !upper) continue;
                for (const auto& [key, local] : piece.chunks[j].border) {
                    if (lower) mp.lower.emplace_back(key, map.remap[j][local]);
                    if (upper) mp.upper.emplace_back(key, map.remap[j][local]);
                }
            }
            st.peak_bytes = std::max(st.peak_bytes, held + mp.memory_bytes() + map.remap.size() * 24 +
                                                        mp.mesh.positions.size() * sizeof(std::uint32_t));
            held -= piece.memory_bytes();
            piece = ChunkedSurface{};
            st.extract_seconds += seconds_since(t);
            t = Clock::now();
            sink.piece(std::move(mp));
            st.write_seconds += seconds_since(t);
            st.peak_bytes = std::max(st.peak_bytes, held + sink.memory_bytes());
        }
    }
    st.source_restarts = src.restarts();
    report(opt.progress, 1.0, opt.labels ? "extracting label surfaces" : "extracting isosurface", "streaming");
    const auto t = Clock::now();
    sink.finish();
    st.write_seconds += seconds_since(t);
    return st;
}

} // namespace iso
