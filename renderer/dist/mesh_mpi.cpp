// The per-rank pipeline of a distributed `isoscope mesh` (mesh_mpi.hpp).
#include "renderer/dist/mesh_mpi.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <regex>

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
#include "io/volume_io.hpp"
#include "io/vtk_mesh.hpp"
#include "io/vtk_util.hpp"
#include "renderer/iso/partition.hpp"

namespace iso::dist {

namespace fs = std::filesystem;

std::string surface_output_path(const std::string& output, double value, bool labels, std::size_t surfaces) {
    if (surfaces <= 1) return output;
    const fs::path out(output);
    char suffix[64];
    std::snprintf(suffix, sizeof suffix, labels ? "-label%g" : "-iso%g", value);
    return (out.parent_path() / (out.stem().string() + suffix + out.extension().string())).string();
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

// The sample box whose chunks' extraction gives every chunk of `r` (the
// chunk layers it spans).
IndexBox range_box(const ChunkIndex& idx, ChunkRange r) {
    IndexBox box;
    if (r.empty()) return box;
    const auto n = idx.counts();
    const std::size_t layer = std::size_t(n[0]) * n[1];
    const std::int64_t C = idx.chunk_size(), z0 = std::int64_t(r.first / layer), z1 = std::int64_t((r.last - 1) / layer);
    const auto d = idx.dims();
    box.lo = {0, 0, z0 * C};
    box.hi = {d[0] - 1, d[1] - 1, std::min((z1 + 1) * C, d[2] - 1)};
    return box;
}

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

    // 2. The volume. Every rank reads the whole volume for now (in-memory
    // readers); the chunk ranges below decide what each rank extracts.
    Volume v;
    agreed(comm, [&] {
        LoadOptions lo;
        lo.series = req.series;
        lo.progress = progress;
        v = load_volume(req.input, lo);
    });
    if (root) res.warnings = v.meta.warnings;

    // 3. The surfaces' values and the index.
    std::vector<double> values = req.isos;
    std::unique_ptr<Extractor> x;
    agreed(comm, [&] {
        if (req.labels && values.empty()) values = distinct_labels(v);
        std::sort(values.begin(), values.end());
        values.erase(std::unique(values.begin(), values.end()), values.end());
        if (!req.labels) values = req.isos; // iso values keep the user's order, as the in-memory path does
        if (req.labels) throw Error("isoscope mesh", "--labels under mpirun is not available yet");
        for (double iso : values)
            if (!std::isfinite(iso)) throw Error("extract", "iso value is not a finite number");
        x = std::make_unique<Extractor>(v, req.extract);
    });
    // Held: update() below replaces the extractor's index with a refreshed copy.
    const std::shared_ptr<const ChunkIndex> index = x->shared_index();
    const ChunkIndex& idx = *index;

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

    // 5. Extraction of this rank's chunks.
    std::vector<ChunkedSurface> surfaces(values.size());
    agreed(comm, [&] {
        for (std::size_t i = 0; i < values.size(); ++i) {
            surfaces[i].iso = values[i];
            surfaces[i].chunks.resize(idx.chunk_count());
        }
        if (!mine.empty()) x->update(range_box(idx, mine), surfaces);
    });

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
        SurfacePiece piece;
        agreed(comm, [&] {
            piece = weld_piece(surfaces[i], mine, idx.dims(), idx.chunk_size());
            surfaces[i] = ChunkedSurface{};
        });
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
