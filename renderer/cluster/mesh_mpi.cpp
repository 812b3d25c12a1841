// The per-rank pipeline of a distributed `isoscope mesh` (mesh_mpi.hpp).
#include "renderer/cluster/mesh_mpi.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <regex>
#include <set>
#include <unordered_map>

#include <unistd.h>

#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkFieldData.h>
#include <vtkXMLPPolyDataWriter.h>
#include <vtkXMLPolyDataWriter.h>

#include "io/atomic_file.hpp"
#include "io/mesh_sink.hpp"
#include "io/process.hpp"
#include "io/volume_stream.hpp"
#include "io/volume_io.hpp"
#include "io/vtk_mesh.hpp"
#include "io/vtk_util.hpp"
#include "renderer/core/stream_mesh.hpp"
#include "renderer/surface/partition.hpp"
#include "renderer/surface/stream.hpp"
#include "renderer/core/surface_name.hpp"

namespace iso::cluster {

namespace fs = std::filesystem;

std::size_t default_rank_budget() {
    const std::size_t known = physical_memory_bytes();
    const std::size_t phys = known ? known : std::size_t(4) << 30;
    int local = 1;
    if (const char* e = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE")) local = std::max(1, std::atoi(e));
    return std::max<std::size_t>(phys / 4 / std::size_t(local), std::size_t(64) << 20);
}

namespace {

std::string lower(std::string s) {
    for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// The plan as bytes for the broadcast: 2 x uint64 per rank.
std::string encode_plan(const std::vector<ChunkRange>& plan) {
    std::string out;
    for (const auto& r : plan) {
        const std::uint64_t v[2] = {r.first, r.last};
        out.append(reinterpret_cast<const char*>(v), sizeof v);
    }
    return out;
}
std::vector<ChunkRange> decode_plan(const std::string& bytes) {
    std::vector<ChunkRange> plan(bytes.size() / 16);
    for (std::size_t i = 0; i < plan.size(); ++i) {
        std::uint64_t v[2];
        std::memcpy(v, bytes.data() + 16 * i, sizeof v);
        plan[i] = {std::size_t(v[0]), std::size_t(v[1])};
    }
    return plan;
}

// Is `dir` absent, or a piece folder an earlier run wrote (only
// <stem>_<N>.vtp files)? Anything else is the user's and is not replaced.
bool replaceable_piece_dir(const fs::path& dir, const std::string& stem) {
    std::error_code ec;
    if (!fs::exists(dir, ec)) return true;
    if (!fs::is_directory(dir, ec)) return false;
    const std::regex piece(std::regex_replace(stem, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") +
                           R"(_[0-9]+\.vtp)");
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (!e.is_regular_file() || !std::regex_match(e.path().filename().string(), piece)) return false;
    return !ec;
}

// Receives the pieces the streaming driver makes of this rank's range (one
// per slab and surface) and writes each at once as a .vtp into the job's
// staging folder under a rank-local name (renamed to its global piece
// number once every rank's count is known), keeping only its summary: the
// rank's output is never held whole, so a rank stays within its memory
// budget plus one slab's piece (docs/cluster.md, "Memory per rank").
class RankSink final : public MeshSink {
public:
    RankSink(std::vector<fs::path> piece_dirs, std::vector<std::string> stems, int rank, const glm::dvec3& origin)
        : dirs_(std::move(piece_dirs)), stems_(std::move(stems)), rank_(rank), origin_(origin), sums_(dirs_.size()),
          files_(dirs_.size()) {}
    void begin(std::size_t surfaces, std::size_t, bool normals) override {
        if (surfaces != dirs_.size())
            throw Error("isoscope mesh", "the streaming driver made another number of surfaces");
        normals_ = normals;
    }
    void piece(MeshPiece&& p) override {
        if (p.surface >= dirs_.size()) throw Error("isoscope mesh", "piece of an unknown surface");
        SurfacePiece sp;
        sp.mesh = std::move(p.mesh);
        // Its seam: every vertex another piece can hold (the driver's lower
        // and upper lists; keys repeated in both are one vertex).
        sp.seam = std::move(p.lower);
        sp.seam.insert(sp.seam.end(), p.upper.begin(), p.upper.end());
        std::sort(sp.seam.begin(), sp.seam.end());
        sp.seam.erase(std::unique(sp.seam.begin(), sp.seam.end()), sp.seam.end());
        sums_[p.surface].push_back(summarize_piece(sp, origin_));
        if (sp.mesh.triangles.empty()) return; // nothing to read: not written, not listed
        const std::string stem = stems_[p.surface];
        const fs::path file = dirs_[p.surface] / (stem + "_r" + std::to_string(rank_) + "_" +
                                                  std::to_string(files_[p.surface].size()) + ".vtp");
        write_vtp_piece(sp.mesh, normals_, file.string(), "the piece");
        files_[p.surface].push_back(file);
    }
    void finish() override {}
    std::vector<MeshStats> stats() const override { return {}; }
    bool normals() const { return normals_; }
    const std::vector<PieceSummary>& summaries(std::size_t s) const { return sums_[s]; }
    const std::vector<fs::path>& files(std::size_t s) const { return files_[s]; }

private:
    std::vector<fs::path> dirs_;
    std::vector<std::string> stems_;
    int rank_;
    glm::dvec3 origin_;
    bool normals_ = true;
    std::vector<std::vector<PieceSummary>> sums_;
    std::vector<std::vector<fs::path>> files_;
};

// The job writes into a staging folder next to the output
// (.<stem>.isoscope-partial-<rank 0's pid>/<stem_s>/ for each surface's
// pieces); rank 0 moves each piece folder and then its summary into place
// once every rank has written and agreed, so a failed job leaves the
// previous output (or nothing) at the output paths, never a mix.
struct Staging {
    fs::path dir;                                // the staging folder
    std::vector<fs::path> dests, finals, pieces; // per surface: the .pvtp, its piece folder, the staged piece folder
    std::vector<std::string> stems;
};

Staging prepare_staging(const Comm& comm, const std::vector<std::string>& paths) {
    Staging st;
    const fs::path first(paths.front());
    const fs::path dir = first.parent_path().empty() ? fs::path(".") : first.parent_path();
    st.dir = dir / ("." + first.stem().string() + ".isoscope-partial-" + comm.broadcast(std::to_string(::getpid())));
    for (const auto& p : paths) {
        const fs::path out(p);
        const fs::path d = out.parent_path().empty() ? fs::path(".") : out.parent_path();
        st.dests.push_back(out);
        st.stems.push_back(out.stem().string());
        st.finals.push_back(d / st.stems.back());
        st.pieces.push_back(st.dir / st.stems.back());
    }
    agreed(comm, [&] {
        if (!comm.root()) return;
        for (std::size_t s = 0; s < paths.size(); ++s)
            if (!replaceable_piece_dir(st.finals[s], st.stems[s]))
                throw Error(paths[s],
                            "the piece folder " + st.finals[s].string() +
                                " exists and holds other files; it is not replaced (move it or choose another name)");
        for (const auto& d : st.pieces) {
            std::error_code ec;
            fs::create_directories(d, ec);
            if (ec) throw Error(paths.front(), "cannot create " + d.string() + ": " + ec.message());
        }
    });
    return st;
}

// Surface s: every rank's pieces get their global numbers (rank order, then
// slab order), rank 0 writes the summary through vtkXMLPPolyDataWriter and
// moves pieces and summary into place. Collective.
std::size_t finish_surface(const Comm& comm, const Staging& st, const RankSink& sink, std::size_t s) {
    const auto& mine = sink.files(s);
    const double n = double(mine.size());
    const auto counts = comm.allgatherv(std::span<const double>(&n, 1));
    std::size_t offset = 0, total = 0;
    for (int r = 0; r < comm.size(); ++r) {
        if (r < comm.rank()) offset += std::size_t(counts[std::size_t(r)]);
        total += std::size_t(counts[std::size_t(r)]);
    }
    const std::string& stem = st.stems[s];
    agreed(comm, [&] {
        for (std::size_t j = 0; j < mine.size(); ++j) {
            std::error_code ec;
            fs::rename(mine[j], st.pieces[s] / (stem + "_" + std::to_string(offset + j) + ".vtp"), ec);
            if (ec) throw Error(mine[j].string(), "cannot rename the piece: " + ec.message());
        }
    });
    agreed(comm, [&] {
        if (!comm.root()) return;
        const bool normals = sink.normals();
        // No triangle anywhere: one empty piece, so that the summary is a valid file.
        if (total == 0) {
            write_vtp_piece(Mesh{}, normals, (st.pieces[s] / (stem + "_0.vtp")).string(), "an empty piece");
            total = 1;
        }
        // Pieces listed as <stem>/<stem>_<i>.vtp.
        const fs::path summary = write_pvtp_summary(st.dir / ("summary-" + std::to_string(s)), stem, total, normals,
                                                    true, st.dests[s].string());
        std::error_code ec;
        fs::remove_all(st.finals[s], ec);
        fs::rename(st.pieces[s], st.finals[s], ec);
        if (ec) throw Error(st.dests[s].string(), "cannot move the pieces into place: " + ec.message());
        fs::rename(summary, st.dests[s], ec);
        if (ec) throw Error(st.dests[s].string(), "cannot move the summary into place: " + ec.message());
    });
    return total;
}

// 1. The output: a partitioned .pvtp (other formats would need the whole
// mesh on one rank).
void check_output(const Comm& comm, const DistMeshRequest& req) {
    agreed(comm, [&] {
        if (lower(fs::path(req.output).extension().string()) != ".pvtp")
            throw Error(req.output, "under mpirun the output must be a partitioned .pvtp (each rank writes its piece); "
                                    "convert it afterwards, or run without mpirun for .stl/.ply/.obj/.vtp");
        if (comm.root()) check_writable_destination(req.output);
    });
}

// 2. The header (every rank; formats that cannot stream are loaded whole
// when they fit the budget, as in one process).
std::unique_ptr<VolumeStream> open_source(const Comm& comm, const DistMeshRequest& req) {
    std::unique_ptr<VolumeStream> src;
    agreed(comm, [&] {
        LoadOptions lo;
        lo.series = req.series;
        src = open_volume_stream(req.input, req.memory_budget, lo);
    });
    return src;
}

StreamOptions stream_options(const DistMeshRequest& req) {
    StreamOptions so;
    so.isos = req.labels ? std::vector<double>{} : req.isos;
    so.labels = req.labels;
    so.label_values = req.labels ? req.isos : std::vector<double>{};
    so.extract = req.extract;
    so.memory_budget = req.memory_budget;
    so.overlap = req.overlap;
    return so;
}

// 3a. The chunk size: rank 0's plan, broadcast (it depends on the thread
// count, which may differ between nodes).
int agreed_chunk_size(const Comm& comm, const VolumeHeader& h, const StreamOptions& so) {
    std::string mine;
    agreed(comm, [&] {
        if (comm.root()) mine = std::to_string(plan_stream(h, so, nullptr).chunk_size);
    });
    return std::stoi(comm.broadcast(mine));
}

// 3b. This rank's share of the index pass: an equal share of the chunk
// layers, read in slabs as large as the budget allows. `labels` (optional):
// the distinct non-zero values seen.
void summarize_share(const Comm& comm, VolumeStream& src, ChunkSummaries& sum, std::size_t memory_budget,
                     const ProgressFn& progress, std::set<double>* labels) {
    const VolumeHeader& h = src.header();
    const int C = sum.chunk_size;
    const int layers = sum.counts[2];
    const int L0 = int(std::int64_t(layers) * comm.rank() / comm.size());
    const int L1 = int(std::int64_t(layers) * (comm.rank() + 1) / comm.size());
    // Disjoint k-slices: chunk layer l starts at sample l*C; the last share
    // runs to the last slice. (ChunkSummaries::add credits each sample to
    // every chunk holding it, so no slice is read twice.)
    const std::int64_t k_begin = std::int64_t(L0) * C;
    const std::int64_t k_end = comm.rank() + 1 == comm.size() ? h.dims[2] : std::int64_t(L1) * C;
    const std::size_t slice = std::size_t(h.slab_memory_bytes(1) - h.slab_memory_bytes(0));
    const std::size_t fixed =
        3 * sum.finite_min.size() * (2 * sizeof(double) + 1) + std::size_t(h.slab_memory_bytes(0));
    const std::int64_t per =
        std::max<std::int64_t>(1, memory_budget > fixed ? std::int64_t((memory_budget - fixed) / slice) : 1);
    agreed(comm, [&] {
        for (std::int64_t k0 = k_begin; k0 < k_end; k0 += per) {
            const std::int64_t k1 = std::min(k0 + per - 1, k_end - 1);
            report(progress, double(k0 - k_begin) / double(std::max<std::int64_t>(k_end - k_begin, 1)),
                   "indexing volume", "isoscope mesh");
            const Volume slab = src.read_slab(k0, k1);
            sum.add({&slab, h.dims, k0, h.index_to_lps});
            if (labels) {
                for (double v : distinct_labels(slab)) labels->insert(v);
                if (labels->size() > 4096)
                    throw Error(h.path, "has more than 4096 distinct values: it does not look like a label map");
            }
        }
    });
}

// 3c. The per-chunk arrays reduced on every rank (MIN, MAX, OR).
void reduce_summaries(const Comm& comm, ChunkSummaries& sum) {
    sum.finite_min = comm.allreduce_min(sum.finite_min);
    sum.finite_max = comm.allreduce_max(sum.finite_max);
    sum.flags = comm.allreduce_bor(sum.flags);
    const double range[2] = {-sum.lowest, sum.highest}; // one MAX for both ends
    const auto r = comm.allreduce_max(range);
    sum.lowest = -r[0];
    sum.highest = r[1];
}

// 3. The index, built in parallel with chunk size C. Labels: when none are
// given, every rank's labels found, gathered into `values` and `so`.
std::shared_ptr<const ChunkIndex> parallel_index(const Comm& comm, VolumeStream& src, int C, const DistMeshRequest& req,
                                                 const ProgressFn& progress, StreamOptions& so,
                                                 std::vector<double>& values) {
    const VolumeHeader& h = src.header();
    ChunkSummaries sum(h.dims, C, h.type);
    const bool find_labels = req.labels && values.empty();
    std::set<double> labels;
    summarize_share(comm, src, sum, req.memory_budget, progress, find_labels ? &labels : nullptr);
    reduce_summaries(comm, sum);
    if (find_labels) {
        const std::vector<double> mine(labels.begin(), labels.end());
        auto all = comm.allgatherv(mine);
        std::sort(all.begin(), all.end());
        all.erase(std::unique(all.begin(), all.end()), all.end());
        values = all;
        so.label_values = all;
    }
    std::shared_ptr<const ChunkIndex> index;
    agreed(comm, [&] {
        if (values.size() > 4096)
            throw Error(h.path, "has more than 4096 distinct values: it does not look like a label map");
        if (values.empty()) throw Error(h.path, req.labels ? "has no non-zero label" : "no iso value given");
        index = std::make_shared<const ChunkIndex>(sum.finish());
    });
    return index;
}

// 4. The plan, made on rank 0 and broadcast so every rank holds the same,
// and each rank's active chunks.
void plan_ranks(const Comm& comm, const ChunkIndex& idx, const std::vector<double>& values, bool labels,
                DistMeshResult& res) {
    std::string bytes;
    if (comm.root()) {
        res.plan = partition_chunks(idx, values, comm.size(), labels);
        bytes = encode_plan(res.plan);
    }
    res.plan = decode_plan(comm.broadcast(bytes));
    const auto w = chunk_weights(idx, values, labels);
    for (const auto& r : res.plan) {
        std::size_t n = 0;
        for (std::size_t id = r.first; id < r.last; ++id) n += w[id] > 0;
        res.rank_active.push_back(n);
    }
}

// 5. Streaming extraction of this rank's chunks (only the slabs its active
// chunks need are read); each slab's piece is summarized and written at
// once. The source is closed after it; every rank's slabs and peak are gathered.
void extract_share(const Comm& comm, std::unique_ptr<VolumeStream>& src, StreamOptions& so, const ProgressFn& progress,
                   RankSink& sink, DistMeshResult& res) {
    const ChunkRange mine = res.plan[std::size_t(comm.rank())];
    StreamStats st;
    agreed(comm, [&] {
        so.first_chunk = mine.first;
        so.last_chunk = mine.last;
        so.progress = progress;
        st = stream_extract(*src, so, sink);
    });
    src.reset();
    const double mine_stats[2] = {double(st.slabs_read), double(st.peak_bytes)};
    const auto all = comm.allgatherv(mine_stats);
    for (std::size_t r = 0; r + 1 < all.size(); r += 2) {
        res.rank_slabs.push_back(std::size_t(all[r]));
        res.rank_peak_bytes.push_back(std::size_t(all[r + 1]));
    }
}

// 6a. Surface s's statistics reduced on rank 0 (collective).
void reduce_surface(const Comm& comm, const RankSink& sink, std::size_t s, DistSurface& out) {
    const auto gathered = comm.gather(serialize(std::span<const PieceSummary>(sink.summaries(s))));
    agreed(comm, [&] {
        if (!comm.root()) return;
        std::vector<PieceSummary> pieces;
        for (const auto& g : gathered) {
            auto rank_pieces = deserialize_piece_summaries(g);
            std::size_t t = 0;
            for (auto& p : rank_pieces) {
                t += p.triangles;
                pieces.push_back(std::move(p));
            }
            out.rank_triangles.push_back(t);
        }
        out.summary = merge_summaries(pieces);
    });
}

} // namespace

DistMeshResult mesh_distributed(const Comm& comm, const DistMeshRequest& req) {
    quiet_vtk();
    DistMeshResult res;
    res.ranks = comm.size();
    const bool root = comm.root();
    const ProgressFn progress = root ? req.progress : ProgressFn{};
    check_output(comm, req);
    std::unique_ptr<VolumeStream> src = open_source(comm, req);
    const VolumeHeader& h = src->header();
    if (root) res.warnings = h.meta.warnings;
    StreamOptions so = stream_options(req);
    std::vector<double> values = req.labels ? so.label_values : so.isos;
    const int C = agreed_chunk_size(comm, h, so);
    so.index = parallel_index(comm, *src, C, req, progress, so, values);
    if (req.labels) {
        std::sort(values.begin(), values.end());
        values.erase(std::unique(values.begin(), values.end()), values.end());
    }
    plan_ranks(comm, *so.index, values, req.labels, res);

    std::vector<std::string> paths;
    for (double v : values) paths.push_back(core::surface_output_path(req.output, v, req.labels, values.size()));
    const Staging staging = prepare_staging(comm, paths);
    const auto remove_staging = [&] {
        if (!root) return;
        std::error_code ec;
        fs::remove_all(staging.dir, ec);
    };
    try {
        // Every piece's volume about one point near the data (the volume's
        // centre); merge_summaries() moves them to the surface's bounds centre.
        const glm::dvec3 centre =
            glm::dvec3(h.index_to_lps * glm::dvec4(0.5 * glm::dvec3(h.dims[0] - 1, h.dims[1] - 1, h.dims[2] - 1), 1.0));
        RankSink sink(staging.pieces, staging.stems, comm.rank(), centre);
        extract_share(comm, src, so, progress, sink, res);

        // 6. Per surface: reduce the statistics on rank 0, then number the
        // pieces, write the summary and move everything into place.
        for (std::size_t i = 0; i < values.size(); ++i) {
            DistSurface out;
            out.value = values[i];
            out.name = core::surface_name(req.labels, values[i]);
            out.path = paths[i];
            reduce_surface(comm, sink, i, out);
            agreed(comm, [&] { report(progress, 1.0, "writing pieces", "isoscope mesh"); });
            out.pieces = finish_surface(comm, staging, sink, i);
            res.surfaces.push_back(std::move(out));
        }
    } catch (...) {
        remove_staging();
        throw;
    }
    remove_staging();
    return res;
}

} // namespace iso::cluster
