#include "renderer/surface/stream.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "renderer/surface/arena.hpp"

namespace iso {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::atomic<std::size_t> g_threads_running{0};
// Counts a pipeline thread from its start to the end of its function.
struct Running {
    Running() { ++g_threads_running; }
    ~Running() { --g_threads_running; }
};

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

// The index pass's slabs: each slice costs `slice`, any slab the reader's
// extra slices (OpenVDB) once, besides `fixed` (two copies of the index and a
// read buffer); `per` slices a slab, as many as fit the budget (at least one).
struct IndexPassSlabs {
    std::size_t slice = 0, fixed = 0;
    std::int64_t per = 1;
};
IndexPassSlabs index_pass_slabs(const VolumeHeader& h, std::size_t chunks, std::size_t memory_budget) {
    IndexPassSlabs s;
    s.slice = std::size_t(h.slab_memory_bytes(1) - h.slab_memory_bytes(0));
    s.fixed = 2 * index_bytes(chunks) + read_buffer(h) + std::size_t(h.slab_memory_bytes(0));
    s.per = std::max<std::int64_t>(1, memory_budget > s.fixed ? std::int64_t((memory_budget - s.fixed) / s.slice) : 1);
    return s;
}

std::size_t surface_count(const StreamOptions& opt) { return std::max<std::size_t>(1, opt.labels ? opt.label_values.size() : opt.isos.size()); }

} // namespace

namespace {

// The plan for chunk size C; with `overlap`, two slabs' samples and output
// if they fit one chunk layer per slab (else StreamPlan::overlap is false and
// the slabs are planned one at a time).
StreamPlan plan_chunks(const VolumeHeader& h, const StreamOptions& opt, const ChunkIndex* index, int C, bool overlap) {
    StreamPlan p;
    const std::size_t sample = voxel_size(h.type);
    const int threads = effective_threads(opt.extract.threads);
    const std::size_t surfaces = surface_count(opt);
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
    const int max_layers = opt.max_layers_per_slab > 0 ? std::min(opt.max_layers_per_slab, layers) : layers;
    // The tallest slabs whose samples and estimated output fit: with overlap,
    // two slabs' samples (one extracted, the next read) and two slabs' output
    // (one welded and written, the next extracted) are held at once.
    auto choose = [&](std::size_t in_flight) {
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
            if (p.fixed_bytes + in_flight * (slab_bytes(h, C, L) + worst * per_chunk) > opt.memory_budget) break;
            best = L;
            fits = true;
            estimate = worst * per_chunk;
        }
        p.layers_per_slab = best;
        p.fits = fits;
        p.output_estimate = estimate;
    };
    p.overlap = false;
    if (overlap) {
        choose(2);
        p.overlap = p.fits;
    }
    if (!p.overlap) choose(1);
    p.slabs = std::size_t((layers + p.layers_per_slab - 1) / p.layers_per_slab);
    // One slab cannot overlap with anything.
    if (p.slabs < 2) p.overlap = false;
    p.slab_bytes = slab_bytes(h, C, p.layers_per_slab);
    return p;
}

} // namespace

StreamPlan plan_stream(const VolumeHeader& h, const StreamOptions& opt, const ChunkIndex* index) {
    if (index) return plan_chunks(h, opt, index, index->chunk_size(), opt.overlap);
    if (opt.extract.chunk_size < 2) throw Error("--chunk", "chunk size must be at least 2 cells");
    // Without an index: halve the chunk size while one chunk layer's samples
    // (two with overlap: the one extracted and the next one read) and the
    // fixed costs do not fit and halving makes them smaller (more chunks cost
    // more index and table entries). If the overlapped plan does not fit at
    // that size, the chunk size is chosen again for one slab at a time (a
    // smaller chunk size would only cost).
    const std::size_t sample = voxel_size(h.type);
    const int threads = effective_threads(opt.extract.threads);
    const std::size_t surfaces = surface_count(opt);
    auto pick = [&](std::size_t in_flight) {
        int c = opt.extract.chunk_size;
        while (c > 4) {
            const std::size_t now = fixed_bytes(h, c, sample, threads, surfaces) + in_flight * slab_bytes(h, c, 1);
            const std::size_t half = fixed_bytes(h, c / 2, sample, threads, surfaces) + in_flight * slab_bytes(h, c / 2, 1);
            if (now <= opt.memory_budget || half >= now) break;
            c /= 2;
        }
        return c;
    };
    const int c1 = pick(1);
    if (opt.overlap) {
        const int c2 = pick(2);
        if (fixed_bytes(h, c2, sample, threads, surfaces) + 2 * slab_bytes(h, c2, 1) <= opt.memory_budget) {
            StreamPlan p = plan_chunks(h, opt, nullptr, c2, true);
            if (p.overlap || c2 == c1) return p;
        }
    }
    return plan_chunks(h, opt, nullptr, c1, false);
}

std::shared_ptr<const ChunkIndex> build_chunk_index(VolumeStream& src, int chunk_size, std::size_t memory_budget,
                                                    const ProgressFn& progress, std::vector<double>* labels_out) {
    const VolumeHeader& h = src.header();
    const auto counts = chunk_counts(h.dims, chunk_size);
    const std::int64_t per = index_pass_slabs(h, std::size_t(counts[0]) * counts[1] * counts[2], memory_budget).per;
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
        st.index_seconds = seconds_since(t);
        st.read_seconds += st.index_seconds;
        // The index pass held its index, a read buffer and slabs of as many slices as fit.
        const IndexPassSlabs ip = index_pass_slabs(h, index->chunk_count(), opt.memory_budget);
        st.peak_bytes = std::max(st.peak_bytes, ip.fixed + src.resident_bytes() +
                                                    std::min<std::size_t>(std::size_t(ip.per), std::size_t(h.dims[2])) * ip.slice);
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
    const char* stage = opt.labels ? "extracting label surfaces" : "extracting isosurface";

    // The slabs with active chunks, in order (the others are skipped unread).
    struct SlabJob {
        std::size_t piece = 0;                // piece number (slab of the plan)
        std::size_t a = 0, b = 0;             // its chunk ids [a, b)
        std::vector<std::size_t> ids;         // its active chunks
        std::int64_t k0 = 0, k1 = 0;          // its samples, halo included
        double f0 = 0, f1 = 0;                // its share of the progress
    };
    std::vector<SlabJob> jobs;
    std::vector<std::size_t> job_of(plan.slabs, std::size_t(-1));
    for (std::size_t i = 0; i < plan.slabs; ++i) {
        const int l0 = plan.first_layer + int(i) * plan.layers_per_slab;
        const int l1 = std::min(l0 + plan.layers_per_slab - 1, plan.last_layer);
        SlabJob j;
        j.piece = i;
        j.a = std::max(first, std::size_t(l0) * layer);
        j.b = std::min(last, std::size_t(l1 + 1) * layer);
        j.f0 = index_share + (1.0 - index_share) * double(i) / double(plan.slabs);
        j.f1 = index_share + (1.0 - index_share) * double(i + 1) / double(plan.slabs);
        for (std::size_t id = j.a; id < j.b; ++id)
            if (chunk_active(*index, id, values, opt.labels)) j.ids.push_back(id);
        if (j.ids.empty()) continue;
        j.k0 = Extractor::layer_samples(h.dims, index->chunk_size(), l0)[0];
        j.k1 = Extractor::layer_samples(h.dims, index->chunk_size(), l1)[1];
        job_of[i] = jobs.size();
        jobs.push_back(std::move(j));
    }

    // What the steps hold, counted as they allocate and free (from three
    // threads with overlap): its high-water mark is StreamStats::peak_bytes.
    struct Meter {
        std::atomic<std::size_t> now{0}, peak{0};
        void add(std::size_t n) {
            const std::size_t v = now.fetch_add(n) + n;
            std::size_t p = peak.load();
            while (v > p && !peak.compare_exchange_weak(p, v)) {}
        }
        void sub(std::size_t n) { now.fetch_sub(n); }
        void transient(std::size_t n) { add(n), sub(n); }
    } meter;
    meter.add(fixed);
    for (const auto& j : jobs) meter.add(sizeof(SlabJob) + j.ids.capacity() * sizeof(std::size_t)); // the job list, held throughout
    std::size_t sink_bytes = sink.memory_bytes();
    meter.add(sink_bytes);

    struct Slab {
        Volume samples;
        std::size_t bytes = 0; // as counted
    };
    struct Output {
        const SlabJob* job = nullptr;
        std::vector<ChunkedSurface> surfaces;
        std::size_t bytes = 0; // as counted
    };
    double read_s = 0, extract_s = 0, weld_s = 0, write_s = 0, wait_s = 0;

    // 2. Read a slab: the layers' samples and their gradient halo (counted
    //    before the read, which allocates them at once).
    auto read = [&](const SlabJob& j) {
        const auto t = Clock::now();
        Slab s;
        // (with what the reader holds meanwhile: OpenVDB's child and its leaves)
        const std::size_t expected = src.streaming() ? std::size_t(h.slab_memory_bytes(j.k1 - j.k0 + 1)) : 0;
        meter.add(expected);
        try {
            s.samples = src.read_slab(j.k0, j.k1);
        } catch (...) {
            meter.sub(expected);
            throw;
        }
        s.bytes = s.samples.memory_bytes();
        if (s.bytes > expected) meter.add(s.bytes - expected);
        else meter.sub(expected - s.bytes);
        read_s += seconds_since(t);
        return s;
    };
    // 3. Extract its chunks; the samples are freed at once.
    ExtractOptions eo = opt.extract;
    eo.chunk_size = index->chunk_size();
    eo.memory_budget = opt.memory_budget;
    // Extraction and welding take the caller's thread count also when they
    // overlap with each other and the reader: giving the writer a core of its
    // own (the extraction one thread fewer) measured no different for .pvtp
    // and makes the extraction the longer step for .ply (docs/isosurface.md).
    eo.threads = threads;
    eo.keep_keys = false;
    std::atomic<bool> failed{false}; // the reader or the writer failed: the extraction stops
    auto extract = [&](const SlabJob& j, Slab&& slab) {
        const auto t = Clock::now();
        const VolumeWindow w{&slab.samples, h.dims, j.k0, h.index_to_lps};
        const ProgressFn part = sub(j.f0, j.f0 + 0.8 * (j.f1 - j.f0));
        eo.progress = [&, part](double f, std::string_view what) {
            return !failed.load(std::memory_order_relaxed) && (!part || part(f, what));
        };
        Output out;
        out.job = &j;
        ExtractStats es;
        if (opt.labels) {
            out.surfaces = extract_label_chunks(w, *index, values, j.ids, eo);
        } else {
            Extractor x(w, eo, index);
            out.surfaces = x.extract_chunks(values, j.ids, &es);
        }
        for (const auto& s : out.surfaces) out.bytes += s.memory_bytes();
        meter.add(out.bytes + es.peak_scratch_bytes);
        meter.sub(es.peak_scratch_bytes);
        slab.samples = Volume{}; // the samples are no longer needed
        meter.sub(slab.bytes);
        extract_s += seconds_since(t);
        return out;
    };
    // 4. Weld each surface's piece, name its seam vertices (the border
    //    vertices of chunks with a neighbour outside [a, b)) and hand it to
    //    the sink. `stop`: give up between surfaces (another step failed).
    auto write = [&](Output&& out, const std::atomic<bool>* stop) {
        const SlabJob& j = *out.job;
        for (std::size_t s = 0; s < nsurf; ++s) {
            if (stop && stop->load()) return;
            auto t = Clock::now();
            ChunkedSurface piece;
            piece.iso = out.surfaces[s].iso;
            std::vector<std::size_t> piece_ids;
            const std::size_t surface_bytes = out.surfaces[s].memory_bytes();
            for (auto id : j.ids)
                if (!out.surfaces[s].chunks[id].positions.empty()) {
                    piece.chunks.push_back(std::move(out.surfaces[s].chunks[id]));
                    piece_ids.push_back(id);
                }
            const std::size_t piece_bytes = piece.memory_bytes();
            meter.add(piece_bytes);
            meter.sub(surface_bytes);
            out.bytes -= surface_bytes;
            out.surfaces[s] = ChunkedSurface{};
            WeldMap map;
            MeshPiece mp;
            mp.surface = s;
            mp.index = j.piece;
            mp.mesh = weld(piece, threads, &map);
            for (std::size_t n = 0; n < piece_ids.size(); ++n) {
                const auto c = index->coords(piece_ids[n]);
                bool lower = false, upper = false;
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                            if (x < 0 || y < 0 || z < 0 || x >= counts[0] || y >= counts[1] || z >= counts[2]) continue;
                            const std::size_t nid = std::size_t(x) + std::size_t(counts[0]) * (std::size_t(y) + std::size_t(counts[1]) * std::size_t(z));
                            lower |= nid < j.a;
                            upper |= nid >= j.b;
                        }
                if (!lower && !upper) continue;
                for (const auto& [key, local] : piece.chunks[n].border) {
                    if (lower) mp.lower.emplace_back(key, map.remap[n][local]);
                    if (upper) mp.upper.emplace_back(key, map.remap[n][local]);
                }
            }
            meter.transient(mp.memory_bytes() + map.remap.size() * 24 + mp.mesh.positions.size() * sizeof(std::uint32_t));
            piece = ChunkedSurface{};
            meter.sub(piece_bytes);
            weld_s += seconds_since(t);
            t = Clock::now();
            sink.piece(std::move(mp));
            write_s += seconds_since(t);
            // The sink's seam maps (read here only: piece() and memory_bytes() stay on one thread).
            const std::size_t now = sink.memory_bytes();
            if (now > sink_bytes) meter.add(now - sink_bytes);
            else meter.sub(sink_bytes - now);
            sink_bytes = now;
        }
        meter.sub(out.bytes);
    };

    // The job of slab i after reporting progress, or null for a slab skipped unread.
    auto job_for = [&](std::size_t i) -> const SlabJob* {
        report(opt.progress, index_share + (1.0 - index_share) * double(i) / double(plan.slabs), stage, "streaming");
        if (job_of[i] == std::size_t(-1)) {
            ++st.slabs_skipped;
            return nullptr;
        }
        return &jobs[job_of[i]];
    };

    if (!plan.overlap) {
        for (std::size_t i = 0; i < plan.slabs; ++i) {
            const SlabJob* job = job_for(i);
            if (!job) continue;
            const SlabJob& j = *job;
            Slab slab = read(j);
            ++st.slabs_read;
            st.chunks_visited += j.ids.size();
            write(extract(j, std::move(slab)), nullptr);
        }
    } else {
        // The pipeline. Hand-overs hold one item each and a step waits for
        // the next one to take it, so at most two slabs of samples (the one
        // extracted, the next being read) and two slabs' output (one being
        // welded and written, the next being extracted) exist at once, as the
        // planner counted. std::thread and a condition variable rather than a
        // TBB flow graph: the reader blocks in pread()/zlib and must not take
        // one of the TBB threads that extraction and welding use.
        struct Pipe {
            std::mutex m;
            std::condition_variable cv;
            std::atomic<bool> stop{false};      // the caller is leaving (an error, a cancel)
            std::size_t taken = 0;              // slabs the extraction has taken from the reader
            std::optional<Slab> ready;          // the slab read and not yet taken
            std::exception_ptr read_error;
            std::optional<Output> handed;       // the output handed to the writer and not yet taken
            bool writing = false, closed = false;
            std::exception_ptr write_error;
        } pipe;
        auto fail = [&](std::exception_ptr& slot) {
            {
                std::lock_guard l(pipe.m);
                slot = std::current_exception();
            }
            failed = true;
            pipe.cv.notify_all();
        };
        // Any way out of here stops and joins both threads first (declared
        // after everything they use, so destroyed before it).
        struct Threads {
            Pipe& pipe;
            std::thread reader, writer;
            ~Threads() {
                {
                    std::lock_guard l(pipe.m);
                    pipe.stop = true;
                }
                pipe.cv.notify_all();
                if (reader.joinable()) reader.join();
                if (writer.joinable()) writer.join();
            }
        } threads_{pipe};
        threads_.reader = std::thread([&] {
            const Running running;
            try {
                for (std::size_t n = 0; n < jobs.size(); ++n) {
                    {
                        // Slab n is read once slab n-1 has been taken (the extraction holds it).
                        std::unique_lock l(pipe.m);
                        pipe.cv.wait(l, [&] { return pipe.stop || pipe.taken >= n; });
                        if (pipe.stop) return;
                    }
                    Slab s = read(jobs[n]);
                    {
                        std::lock_guard l(pipe.m);
                        if (pipe.stop) {
                            meter.sub(s.bytes);
                            return;
                        }
                        pipe.ready = std::move(s);
                    }
                    pipe.cv.notify_all();
                }
            } catch (...) {
                fail(pipe.read_error);
            }
        });
        threads_.writer = std::thread([&] {
            const Running running;
            try {
                for (;;) {
                    std::optional<Output> out;
                    {
                        std::unique_lock l(pipe.m);
                        pipe.cv.wait(l, [&] { return pipe.stop || pipe.handed || pipe.closed; });
                        if (pipe.stop || !pipe.handed) return;
                        out = std::move(pipe.handed);
                        pipe.handed.reset();
                        pipe.writing = true;
                    }
                    write(std::move(*out), &pipe.stop);
                    {
                        std::lock_guard l(pipe.m);
                        pipe.writing = false;
                    }
                    pipe.cv.notify_all();
                }
            } catch (...) {
                fail(pipe.write_error);
            }
        });
        // The writer's error, else the reader's, as it was thrown (iso::Error, Cancelled, bad_alloc ...).
        auto rethrow_failure = [&] {
            std::lock_guard l(pipe.m);
            if (pipe.write_error) std::rethrow_exception(pipe.write_error);
            if (pipe.read_error) std::rethrow_exception(pipe.read_error);
        };
        // Waits until the writer has written what it was handed.
        auto drain = [&] {
            const auto t = Clock::now();
            std::unique_lock l(pipe.m);
            pipe.cv.wait(l, [&] { return pipe.write_error || (!pipe.handed && !pipe.writing); });
            wait_s += seconds_since(t);
        };
        try {
            for (std::size_t i = 0; i < plan.slabs; ++i) {
                const SlabJob* job = job_for(i);
                if (!job) continue;
                const SlabJob& j = *job;
                Slab slab;
                {
                    const auto t = Clock::now();
                    std::unique_lock l(pipe.m);
                    pipe.cv.wait(l, [&] { return pipe.ready || pipe.read_error || pipe.write_error; });
                    wait_s += seconds_since(t);
                    if (!pipe.ready) {
                        l.unlock();
                        rethrow_failure();
                    }
                    slab = std::move(*pipe.ready);
                    pipe.ready.reset();
                    ++pipe.taken;
                }
                pipe.cv.notify_all();
                ++st.slabs_read;
                st.chunks_visited += j.ids.size();
                Output out = extract(j, std::move(slab));
                drain();
                rethrow_failure();
                {
                    std::lock_guard l(pipe.m);
                    pipe.handed = std::move(out);
                }
                pipe.cv.notify_all();
            }
            drain();
            rethrow_failure();
            {
                std::lock_guard l(pipe.m);
                pipe.closed = true;
            }
            pipe.cv.notify_all();
            threads_.writer.join();
            threads_.reader.join();
            rethrow_failure();
        } catch (const Cancelled&) {
            // The extraction stopped because the reader or the writer failed: their error, not a cancel.
            rethrow_failure();
            throw;
        }
    }
    st.read_seconds += read_s;
    st.extract_seconds = extract_s;
    st.weld_seconds = weld_s;
    st.write_seconds = write_s;
    st.wait_seconds = wait_s;
    st.peak_bytes = std::max(st.peak_bytes, meter.peak.load());
    st.source_restarts = src.restarts();
    report(opt.progress, 1.0, stage, "streaming");
    const auto t = Clock::now();
    sink.finish();
    st.write_seconds += seconds_since(t);
    return st;
}

std::size_t stream_threads_running() { return g_threads_running.load(); }

} // namespace iso
