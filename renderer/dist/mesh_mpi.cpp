// The per-rank pipeline of a distributed `isoscope mesh` (mesh_mpi.hpp).
#include "renderer/dist/mesh_mpi.hpp"

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
#include <vtkMPIController.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkFieldData.h>
#include <vtkXMLPPolyDataWriter.h>

#include "io/atomic_file.hpp"
#include "io/mesh_sink.hpp"
#include "io/volume_stream.hpp"
#include "io/volume_io.hpp"
#include "io/vtk_mesh.hpp"
#include "io/vtk_util.hpp"
#include "renderer/iso/partition.hpp"
#include "renderer/iso/stream.hpp"

namespace iso::dist {

namespace fs = std::filesystem;

std::string surface_output_path(const std::string& output, double value, bool labels, std::size_t surfaces) {
    if (surfaces <= 1) return output;
    const fs::path out(output);
    char suffix[64];
    std::snprintf(suffix, sizeof suffix, labels ? "-label%g" : "-iso%g", value);
    return (out.parent_path() / (out.stem().string() + suffix + out.extension().string())).string();
}

std::size_t default_rank_budget() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
    const std::size_t phys = pages > 0 && page > 0 ? std::size_t(pages) * std::size_t(page) : std::size_t(4) << 30;
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

// Joins the pieces the streaming driver makes of this rank's range (one per
// slab) into one piece per surface: vertices on the seams between its own
// slabs are merged by key; those whose chunks reach outside the rank's range
// are its seam with the other ranks. The rank's output is held until it is
// written (the input is streamed: docs/cluster.md, "Memory per rank").
class RankSink final : public MeshSink {
public:
    RankSink(std::size_t surfaces, ChunkRange range, std::array<std::int64_t, 3> dims, int chunk_size)
        : range_(range), dims_(dims), C_(chunk_size), out_(surfaces), keys_(surfaces) {}
    void begin(std::size_t surfaces, std::size_t, bool normals) override {
        if (surfaces != out_.size()) throw Error("isoscope mesh", "the streaming driver made another number of surfaces");
        normals_ = normals;
    }
    void piece(MeshPiece&& p) override {
        if (p.surface >= out_.size()) throw Error("isoscope mesh", "piece of an unknown surface");
        Mesh& m = out_[p.surface].mesh;
        auto& keys = keys_[p.surface];
        constexpr std::uint32_t kNew = 0xFFFFFFFFu;
        std::vector<std::uint32_t> remap(p.mesh.positions.size(), kNew);
        for (const auto* list : {&p.lower, &p.upper})
            for (const auto& [key, v] : *list)
                if (auto it = keys.find(key); it != keys.end()) remap[v] = it->second;
        for (std::size_t v = 0; v < remap.size(); ++v) {
            if (remap[v] != kNew) continue;
            remap[v] = std::uint32_t(m.positions.size());
            m.positions.push_back(p.mesh.positions[v]);
            if (normals_ && v < p.mesh.normals.size()) m.normals.push_back(p.mesh.normals[v]);
        }
        for (const auto* list : {&p.lower, &p.upper})
            for (const auto& [key, v] : *list) keys.try_emplace(key, remap[v]);
        m.triangles.reserve(m.triangles.size() + p.mesh.triangles.size());
        for (const auto& t : p.mesh.triangles) m.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
    }
    void finish() override {}
    std::vector<MeshStats> stats() const override { return {}; }
    // Surface s's piece, with its seam (keys other ranks can hold), sorted.
    SurfacePiece take(std::size_t s) {
        SurfacePiece p = std::move(out_[s]);
        for (const auto& [key, v] : keys_[s])
            if (key_leaves_range(key, range_, dims_, C_)) p.seam.emplace_back(key, v);
        std::sort(p.seam.begin(), p.seam.end());
        keys_[s] = {};
        return p;
    }

private:
    ChunkRange range_;
    std::array<std::int64_t, 3> dims_;
    int C_;
    bool normals_ = true;
    std::vector<SurfacePiece> out_;
    std::vector<std::unordered_map<std::uint64_t, std::uint32_t>> keys_;
};

// A piece as VTK's parallel writer wants it: every piece with the same
// arrays, even an empty one (rank 0's piece, empty or not, describes the
// arrays in the .pvtp summary).
vtkSmartPointer<vtkPolyData> piece_polydata(const Mesh& m, bool normals) {
    auto pd = to_polydata(m, false);
    if (normals && !pd->GetPointData()->GetNormals()) {
        vtkNew<vtkFloatArray> n;
        n->SetName("Normals");
        n->SetNumberOfComponents(3);
        pd->GetPointData()->SetNormals(n);
    }
    vtkNew<vtkStringArray> space;
    space->SetName("SPACE");
    space->InsertNextValue("LPS");
    pd->GetFieldData()->AddArray(space);
    return pd;
}

// Is `dir` absent, or a piece folder an earlier run wrote (only
// <stem>_<N>.vtp files)? Anything else is the user's and is not replaced.
bool replaceable_piece_dir(const fs::path& dir, const std::string& stem) {
    std::error_code ec;
    if (!fs::exists(dir, ec)) return true;
    if (!fs::is_directory(dir, ec)) return false;
    const std::regex piece(std::regex_replace(stem, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") + R"(_[0-9]+\.vtp)");
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (!e.is_regular_file() || !std::regex_match(e.path().filename().string(), piece)) return false;
    return !ec;
}

// Writes this rank's piece of `path` (collective). The job writes into a
// staging folder next to the output; rank 0 moves the piece folder and the
// summary into place once every rank has written its piece, so a failed job
// leaves the previous output (or nothing) at `path`, never a mix.
void write_pieces(const Comm& comm, vtkMPIController* ctrl, const Mesh& m, bool normals, const std::string& path) {
    const fs::path out(path);
    const fs::path dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
    const std::string stem = out.stem().string();
    const std::string tag = comm.broadcast(std::to_string(::getpid()));
    const fs::path staging = dir / ("." + stem + ".isoscope-partial-" + tag);
    agreed(comm, [&] {
        if (!comm.root()) return;
        if (!replaceable_piece_dir(dir / stem, stem))
            throw Error(path, "the piece folder " + (dir / stem).string() +
                                  " exists and holds other files; it is not replaced (move it or choose another name)");
        std::error_code ec;
        fs::create_directories(staging / stem, ec);
        if (ec) throw Error(path, "cannot create " + staging.string() + ": " + ec.message());
    });
    const auto cleanup = [&] {
        if (!comm.root()) return;
        std::error_code ec;
        fs::remove_all(staging, ec);
    };
    try {
        agreed(comm, [&] {
            vtkNew<VtkMessages> msgs;
            vtkNew<vtkXMLPPolyDataWriter> w;
            msgs->watch(w);
            const auto pd = piece_polydata(m, normals);
            w->SetInputData(pd);
            w->SetController(ctrl);
            w->SetFileName((staging / (stem + ".pvtp")).string().c_str());
            w->SetNumberOfPieces(comm.size());
            w->SetStartPiece(comm.rank());
            w->SetEndPiece(comm.rank());
            w->SetUseSubdirectory(true); // pieces in <stem>/<stem>_<rank>.vtp
            w->SetDataModeToAppended();
            w->SetCompressorTypeToZLib();
            const int ok = w->Write();
            if (!ok || msgs->has_error() || w->GetErrorCode() != 0)
                throw Error(path, "cannot write piece " + std::to_string(comm.rank()) + ": " +
                                      (msgs->has_error() ? msgs->first_error() : std::string("VTK writer failed")));
        });
        agreed(comm, [&] {
            if (!comm.root()) return;
            std::error_code ec;
            if (!fs::exists(staging / (stem + ".pvtp"), ec)) throw Error(path, "the parallel writer wrote no summary file");
            fs::remove_all(dir / stem, ec);
            fs::rename(staging / stem, dir / stem, ec);
            if (ec) throw Error(path, "cannot move the pieces into place: " + ec.message());
            fs::rename(staging / (stem + ".pvtp"), out, ec);
            if (ec) throw Error(path, "cannot move the summary into place: " + ec.message());
        });
    } catch (...) {
        cleanup();
        throw;
    }
    cleanup();
}

} // namespace

DistMeshResult mesh_distributed(const Comm& comm, const DistMeshRequest& req) {
    quiet_vtk();
    DistMeshResult res;
    res.ranks = comm.size();
    const bool root = comm.root();
    const ProgressFn progress = root ? req.progress : ProgressFn{};

    // 1. The output: a partitioned .pvtp (other formats would need the whole
    // mesh on one rank).
    agreed(comm, [&] {
        if (lower(fs::path(req.output).extension().string()) != ".pvtp")
            throw Error(req.output, "under mpirun the output must be a partitioned .pvtp (each rank writes its piece); "
                                    "convert it afterwards, or run without mpirun for .stl/.ply/.obj/.vtp");
        if (root) check_writable_destination(req.output);
    });

    // 2. The header (every rank; formats that cannot stream are loaded whole
    // when they fit the budget, as in one process).
    std::unique_ptr<VolumeStream> src;
    agreed(comm, [&] {
        LoadOptions lo;
        lo.series = req.series;
        src = open_volume_stream(req.input, req.memory_budget, lo);
    });
    const VolumeHeader& h = src->header();
    if (root) res.warnings = h.meta.warnings;

    // 3. The chunk size (rank 0's plan, broadcast: it depends on the thread
    // count, which may differ between nodes) and the index, built in
    // parallel: each rank summarizes an equal share of the chunk layers, then
    // the per-chunk arrays are reduced (MIN, MAX, OR) on every rank.
    StreamOptions so;
    so.isos = req.labels ? std::vector<double>{} : req.isos;
    so.labels = req.labels;
    so.label_values = req.labels ? req.isos : std::vector<double>{};
    so.extract = req.extract;
    so.memory_budget = req.memory_budget;
    int C = 0;
    {
        std::string mine;
        agreed(comm, [&] {
            if (root) mine = std::to_string(plan_stream(h, so, nullptr).chunk_size);
        });
        C = std::stoi(comm.broadcast(mine));
    }
    std::vector<double> values = req.labels ? so.label_values : so.isos;
    std::shared_ptr<const ChunkIndex> index;
    {
        ChunkSummaries sum(h.dims, C, h.type);
        const int layers = sum.counts[2];
        const int L0 = int(std::int64_t(layers) * comm.rank() / comm.size());
        const int L1 = int(std::int64_t(layers) * (comm.rank() + 1) / comm.size());
        // Disjoint k-slices: chunk layer l starts at sample l*C; the last share
        // runs to the last slice. (ChunkSummaries::add credits each sample to
        // every chunk holding it, so no slice is read twice.)
        const std::int64_t k_begin = std::int64_t(L0) * C;
        const std::int64_t k_end = comm.rank() + 1 == comm.size() ? h.dims[2] : std::int64_t(L1) * C;
        const std::size_t slice = std::size_t(h.dims[0] * h.dims[1]) * voxel_size(h.type);
        const std::size_t fixed = 3 * sum.finite_min.size() * (2 * sizeof(double) + 1);
        const std::int64_t per =
            std::max<std::int64_t>(1, req.memory_budget > fixed ? std::int64_t((req.memory_budget - fixed) / slice) : 1);
        const bool find_labels = req.labels && values.empty();
        std::set<double> labels;
        agreed(comm, [&] {
            for (std::int64_t k0 = k_begin; k0 < k_end; k0 += per) {
                const std::int64_t k1 = std::min(k0 + per - 1, k_end - 1);
                report(progress, double(k0 - k_begin) / double(std::max<std::int64_t>(k_end - k_begin, 1)), "indexing volume",
                       "isoscope mesh");
                const Volume slab = src->read_slab(k0, k1);
                sum.add({&slab, h.dims, k0, h.index_to_lps});
                if (find_labels) {
                    for (double v : distinct_labels(slab)) labels.insert(v);
                    if (labels.size() > 4096)
                        throw Error(h.path, "has more than 4096 distinct values: it does not look like a label map");
                }
            }
        });
        sum.finite_min = comm.allreduce_min(sum.finite_min);
        sum.finite_max = comm.allreduce_max(sum.finite_max);
        sum.flags = comm.allreduce_bor(sum.flags);
        const double range[2] = {-sum.lowest, sum.highest}; // one MAX for both ends
        const auto r = comm.allreduce_max(range);
        sum.lowest = -r[0];
        sum.highest = r[1];
        if (find_labels) {
            const std::vector<double> mine(labels.begin(), labels.end());
            auto all = comm.allgatherv(mine);
            std::sort(all.begin(), all.end());
            all.erase(std::unique(all.begin(), all.end()), all.end());
            values = all;
            so.label_values = all;
        }
        agreed(comm, [&] {
            if (values.size() > 4096) throw Error(h.path, "has more than 4096 distinct values: it does not look like a label map");
            index = std::make_shared<const ChunkIndex>(sum.finish());
        });
    }
    so.index = index;
    const ChunkIndex& idx = *index;
    if (req.labels) {
        std::sort(values.begin(), values.end());
        values.erase(std::unique(values.begin(), values.end()), values.end());
    }

    // 4. The plan, made on rank 0 and broadcast so every rank holds the same.
    {
        std::string bytes;
        if (root) {
            res.plan = partition_chunks(idx, values, comm.size(), req.labels);
            bytes = encode_plan(res.plan);
        }
        res.plan = decode_plan(comm.broadcast(bytes));
        const auto w = chunk_weights(idx, values, req.labels);
        for (const auto& r : res.plan) {
            std::size_t n = 0;
            for (std::size_t id = r.first; id < r.last; ++id) n += w[id] > 0;
            res.rank_active.push_back(n);
        }
    }
    const ChunkRange mine = res.plan[std::size_t(comm.rank())];

    // 5. Streaming extraction of this rank's chunks (only the slabs its
    // active chunks need are read), its slabs' pieces joined into one piece.
    RankSink sink(values.size(), mine, idx.dims(), idx.chunk_size());
    StreamStats st;
    agreed(comm, [&] {
        so.first_chunk = mine.first;
        so.last_chunk = mine.last;
        so.progress = progress;
        st = stream_extract(*src, so, sink);
    });
    src.reset();
    {
        const double mine_stats[2] = {double(st.slabs_read), double(st.peak_bytes)};
        const auto all = comm.allgatherv(mine_stats);
        for (std::size_t r = 0; r + 1 < all.size(); r += 2) {
            res.rank_slabs.push_back(std::size_t(all[r]));
            res.rank_peak_bytes.push_back(std::size_t(all[r + 1]));
        }
    }

    // 6. Per surface: weld the piece, reduce the statistics, write.
    vtkNew<vtkMPIController> ctrl;
    ctrl->Initialize(nullptr, nullptr, 1); // MPI is already initialised (Runtime)
    for (std::size_t i = 0; i < values.size(); ++i) {
        DistSurface out;
        out.value = values[i];
        char name[64];
        std::snprintf(name, sizeof name, req.labels ? "label %g" : "iso %g", values[i]);
        out.name = name;
        out.path = surface_output_path(req.output, values[i], req.labels, values.size());
        SurfacePiece piece = sink.take(i);
        const auto [lo, hi] = piece_bounds(piece.mesh);
        const double lo3[3] = {lo.x, lo.y, lo.z}, hi3[3] = {hi.x, hi.y, hi.z};
        const auto glo = comm.allreduce_min(lo3), ghi = comm.allreduce_max(hi3);
        const glm::dvec3 origin = volume_origin({glo[0], glo[1], glo[2]}, {ghi[0], ghi[1], ghi[2]});
        const auto gathered = comm.gather(serialize(summarize_piece(piece, origin)));
        agreed(comm, [&] {
            if (!root) return;
            std::vector<PieceSummary> pieces;
            for (const auto& g : gathered) {
                pieces.push_back(deserialize_piece_summary(g));
                out.rank_triangles.push_back(pieces.back().triangles);
            }
            out.summary = merge_summaries(pieces);
        });
        agreed(comm, [&] { report(progress, 1.0, "writing pieces", "isoscope mesh"); });
        write_pieces(comm, ctrl, piece.mesh, req.extract.normals, out.path);
        res.surfaces.push_back(std::move(out));
    }
    ctrl->Finalize(1);
    return res;
}

} // namespace iso::dist
