// The streaming driver's steps (stream_steps.hpp): the slab jobs of a plan,
// and reading, extracting and welding/writing one slab.
#include "renderer/surface/stream_steps.hpp"

#include <algorithm>

#include "renderer/surface/arena.hpp"
#include "renderer/surface/stream_plan.hpp"

namespace iso::detail {

ProgressFn progress_part(const ProgressFn& progress, double a, double b) {
    if (!progress) return {};
    return [&progress, a, b](double f, std::string_view stage) { return progress(a + (b - a) * f, stage); };
}

void MemoryMeter::add(std::size_t n) {
    const std::size_t v = now_.fetch_add(n) + n;
    std::size_t p = peak_.load();
    while (v > p && !peak_.compare_exchange_weak(p, v)) {}
}

std::size_t SlabSchedule::memory_bytes() const {
    std::size_t n = 0;
    for (const auto& j : jobs) n += sizeof(SlabJob) + j.ids.capacity() * sizeof(std::size_t);
    return n;
}

SlabSchedule schedule_slabs(const VolumeHeader& h, const StreamPlan& plan, const ChunkIndex& index,
                            const std::vector<double>& values, const StreamOptions& opt, double index_share) {
    const std::size_t layer = index.layer_size(), total = index.chunk_count();
    const std::size_t first = std::min(opt.first_chunk, total), last = std::min(opt.last_chunk, total);
    SlabSchedule s;
    s.job_of.assign(plan.slabs, SlabSchedule::kSkipped);
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
            if (chunk_active(index, id, values, opt.labels)) j.ids.push_back(id);
        if (j.ids.empty()) continue;
        j.k0 = Extractor::layer_samples(h.dims, index.chunk_size(), l0)[0];
        j.k1 = Extractor::layer_samples(h.dims, index.chunk_size(), l1)[1];
        s.job_of[i] = s.jobs.size();
        s.jobs.push_back(std::move(j));
    }
    return s;
}

SlabSteps::SlabSteps(VolumeStream& src, MeshSink& sink, std::shared_ptr<const ChunkIndex> index,
                     const StreamOptions& opt, const std::vector<double>& values, MemoryMeter& meter)
    : src_(src), sink_(sink), index_(std::move(index)), opt_(opt), values_(values), meter_(meter), eo_(opt.extract),
      threads_(effective_threads(opt.extract.threads)) {
    eo_.chunk_size = index_->chunk_size();
    eo_.memory_budget = opt.memory_budget;
    // Extraction and welding take the caller's thread count also when they
    // overlap with each other and the reader: giving the writer a core of its
    // own (the extraction one thread fewer) measured no different for .pvtp
    // and makes the extraction the longer step for .ply (docs/isosurface.md).
    eo_.threads = threads_;
    eo_.keep_keys = false;
    sink_bytes_ = sink_.memory_bytes();
    meter_.add(sink_bytes_);
}

Slab SlabSteps::read(const SlabJob& j) {
    const auto t = Clock::now();
    Slab s;
    // (with what the reader holds meanwhile: OpenVDB's child and its leaves)
    const VolumeHeader& h = src_.header();
    const std::size_t expected = src_.streaming() ? std::size_t(h.slab_memory_bytes(j.k1 - j.k0 + 1)) : 0;
    meter_.add(expected);
    try {
        s.samples = src_.read_slab(j.k0, j.k1);
    } catch (...) {
        meter_.sub(expected);
        throw;
    }
    s.bytes = s.samples.memory_bytes();
    meter_.change(expected, s.bytes);
    seconds.read += seconds_since(t);
    return s;
}

SlabOutput SlabSteps::extract(const SlabJob& j, Slab&& slab, const std::atomic<bool>* failed) {
    const auto t = Clock::now();
    const VolumeHeader& h = src_.header();
    const VolumeWindow w{&slab.samples, h.dims, j.k0, h.index_to_lps};
    const ProgressFn part = progress_part(opt_.progress, j.f0, j.f0 + 0.8 * (j.f1 - j.f0));
    eo_.progress = [failed, part](double f, std::string_view what) {
        return !(failed && failed->load(std::memory_order_relaxed)) && (!part || part(f, what));
    };
    SlabOutput out;
    out.job = &j;
    ExtractStats es;
    if (opt_.labels) {
        out.surfaces = extract_label_chunks(w, *index_, values_, j.ids, eo_);
    } else {
        Extractor x(w, eo_, index_);
        out.surfaces = x.extract_chunks(values_, j.ids, &es);
    }
    for (const auto& s : out.surfaces) out.bytes += s.memory_bytes();
    meter_.add(out.bytes + es.peak_scratch_bytes);
    meter_.sub(es.peak_scratch_bytes);
    slab.samples = Volume{}; // the samples are no longer needed
    meter_.sub(slab.bytes);
    seconds.extract += seconds_since(t);
    return out;
}

void SlabSteps::write(SlabOutput&& out, const std::atomic<bool>* stop) {
    for (std::size_t s = 0; s < values_.size(); ++s) {
        if (stop && stop->load()) return;
        write_surface(out, s);
    }
    meter_.sub(out.bytes);
}

void SlabSteps::write_surface(SlabOutput& out, std::size_t s) {
    auto t = Clock::now();
    Piece piece = take_piece(out, s);
    MeshPiece mp = weld_piece(piece, *out.job, s);
    piece.surface = ChunkedSurface{};
    meter_.sub(piece.bytes);
    seconds.weld += seconds_since(t);
    t = Clock::now();
    const double analysed = sink_.analysis_seconds();
    sink_.piece(std::move(mp));
    const double analysis = sink_.analysis_seconds() - analysed; // the sink's summaries, not its writing
    seconds.analysis += analysis;
    seconds.write += seconds_since(t) - analysis;
    // The sink's seam maps (read here only: piece() and memory_bytes() stay on one thread).
    const std::size_t now = sink_.memory_bytes();
    meter_.change(sink_bytes_, now);
    sink_bytes_ = now;
}

SlabSteps::Piece SlabSteps::take_piece(SlabOutput& out, std::size_t s) {
    Piece piece;
    piece.surface.iso = out.surfaces[s].iso;
    const std::size_t surface_bytes = out.surfaces[s].memory_bytes();
    for (auto id : out.job->ids)
        if (!out.surfaces[s].chunks[id].positions.empty()) {
            piece.surface.chunks.push_back(std::move(out.surfaces[s].chunks[id]));
            piece.ids.push_back(id);
        }
    piece.bytes = piece.surface.memory_bytes();
    meter_.add(piece.bytes);
    meter_.sub(surface_bytes);
    out.bytes -= surface_bytes;
    out.surfaces[s] = ChunkedSurface{};
    return piece;
}

MeshPiece SlabSteps::weld_piece(const Piece& piece, const SlabJob& j, std::size_t s) {
    WeldMap map;
    MeshPiece mp;
    mp.surface = s;
    mp.index = j.piece;
    mp.mesh = weld(piece.surface, threads_, &map);
    add_seams(mp, piece, map, j);
    meter_.transient(mp.memory_bytes() + map.remap.size() * 24 + mp.mesh.positions.size() * sizeof(std::uint32_t));
    return mp;
}

// The seam vertices: the border vertices of chunks with a neighbour outside
// the piece's chunk ids [a, b) (lower: a neighbour id < a, upper: >= b).
void SlabSteps::add_seams(MeshPiece& mp, const Piece& piece, const WeldMap& map, const SlabJob& j) const {
    const auto counts = index_->counts();
    for (std::size_t n = 0; n < piece.ids.size(); ++n) {
        const auto c = index_->coords(piece.ids[n]);
        bool lower = false, upper = false;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                    if (x < 0 || y < 0 || z < 0 || x >= counts[0] || y >= counts[1] || z >= counts[2]) continue;
                    const std::size_t nid =
                        std::size_t(x) +
                        std::size_t(counts[0]) * (std::size_t(y) + std::size_t(counts[1]) * std::size_t(z));
                    lower |= nid < j.a;
                    upper |= nid >= j.b;
                }
        if (!lower && !upper) continue;
        for (const auto& [key, local] : piece.surface.chunks[n].border) {
            if (lower) mp.lower.emplace_back(key, map.remap[n][local]);
            if (upper) mp.upper.emplace_back(key, map.remap[n][local]);
        }
    }
}

} // namespace iso::detail
