// `isoscope mesh`: parses, calls the core's mesh route (core::mesh_surfaces:
// in memory or streamed) or, under mpirun, renderer/dist's per-rank pipeline,
// and prints the one per-surface summary of every route (text or --json).
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/cli/commands.hpp"
#include "app/cli/common.hpp"
#include "io/mesh.hpp"
#include "renderer/core/mesh_surfaces.hpp"
#include "renderer/core/stream_mesh.hpp"
#ifdef ISOSCOPE_MPI
#include "renderer/cluster/mesh_mpi.hpp"
#endif

namespace iso::cli {

namespace {

struct MeshArgs {
    std::string in, out, series;
    std::vector<double> isos, label_values;
    bool labels = false, stream = false, no_overlap = false, json = false;
    iso::PostProcessOptions post;
    int threads = 0, chunk = 32;
    double memory_mib = 0; // per rank under mpirun (0: default_rank_budget())
};

// A signed volume as what it is: never negative, a cavity's wall says so
// (iso::encloses_cavity).
std::string volume_text(double ml, bool lower_bound) {
    std::ostringstream o;
    const char* const at_least = lower_bound ? ">= " : "";
    if (iso::encloses_cavity(ml))
        o << "encloses a cavity of " << at_least << -ml << " mL (" << -ml * 1000.0 << " mm^3)";
    else
        o << "volume " << at_least << ml * 1000.0 << " mm^3";
    return o.str();
}

// The volume part of a surface's line: only a volume that means what it says.
void print_volume(const iso::core::MeshedSurface& s) {
    using iso::VolumeKind;
    std::cout << (s.closed ? "closed" : "open");
    if (!s.volume_kind)
        std::cout << ", volume not known (the statistics of an open surface held as pieces have no caps)";
    else if (*s.volume_kind == VolumeKind::Undefined)
        std::cout << ", volume undefined (misoriented triangles)";
    else if (*s.volume_kind == VolumeKind::LowerBound)
        std::cout << ", " << volume_text(*s.volume_ml, true) << " (lower bound: the boundary loops capped)";
    else
        std::cout << ", " << volume_text(*s.volume_ml, false);
}

// The summary line of one written surface (the same for every route).
void print_surface(const iso::core::MeshedSurface& s, const iso::core::MeshResult& r) {
    std::cout << s.name << ": " << s.triangles << " triangles, " << s.vertices << " vertices, area " << s.area_mm2
              << " mm^2, ";
    print_volume(s);
    std::cout << ", " << s.components << " components (largest: " << s.largest.triangles << " triangles, area "
              << s.largest.area << " mm^2";
    if (s.largest_volume_ml) std::cout << ", " << volume_text(*s.largest_volume_ml, false);
    std::cout << ") -> " << s.path;
    if (r.ranks) std::cout << " (" << s.pieces << " pieces from " << r.ranks->ranks << " ranks)";
    std::cout << "\n";
}

void print_streamed(const iso::core::StreamedDetails& d) {
    const auto& s = d.stats;
    std::cout << "streamed: " << s.plan.slabs << " slabs of " << s.plan.layers_per_slab << " chunk layers (chunk "
              << s.plan.chunk_size << "), " << s.slabs_read << " read, " << s.slabs_skipped << " skipped"
              << (s.index_pass ? ", after an index pass" : "") << "; peak memory " << human_bytes(double(s.peak_bytes))
              << " (engine) of " << human_bytes(double(d.memory_budget)) << ", "
              << human_bytes(double(d.resident_peak_bytes)) << " resident (VmHWM)";
    if (d.reader_peak_bytes) std::cout << "; OpenVDB reader process peak " << human_bytes(double(d.reader_peak_bytes));
    std::cout << "\n";
    char steps[256];
    std::snprintf(steps, sizeof steps,
                  "index %.2f, read %.2f, extract %.2f, weld %.2f, write %.2f, analysis %.2f, extraction waited %.2f",
                  s.index_seconds, s.read_seconds - s.index_seconds, s.extract_seconds, s.weld_seconds, s.write_seconds,
                  s.analysis_seconds, s.wait_seconds);
    std::cout << "streaming steps (busy seconds" << (s.plan.overlap ? ", overlapped" : "") << "): " << steps << "\n";
}

void print_in_memory(const iso::core::InMemoryDetails& d) {
    char post[64] = "";
    if (d.postprocess_seconds > 0) std::snprintf(post, sizeof post, "post-processing %.2f, ", d.postprocess_seconds);
    char steps[256];
    std::snprintf(steps, sizeof steps, "read %.2f, index %.2f, extract %.2f, weld %.2f, %swrite %.2f, analysis %.2f",
                  d.read_seconds, d.index_seconds, d.extract_seconds, d.weld_seconds, post, d.write_seconds,
                  d.analysis_seconds);
    std::cout << "steps (busy seconds): " << steps << "\n";
}

void print_ranks(const iso::core::RankDetails& d) {
    std::cout << d.ranks << " ranks, active chunks per rank:";
    for (auto n : d.active_chunks) std::cout << ' ' << n;
    std::cout << ", slabs read:";
    for (auto n : d.slabs_read) std::cout << ' ' << n;
    std::cout << ", engine peak per rank:";
    for (auto n : d.peak_bytes) std::cout << ' ' << human_bytes(double(n));
    std::cout << "\n";
}

// Warnings on stderr; the summary (or the JSON) on stdout.
void print_result(const iso::core::MeshResult& r, bool json) {
    print_warnings(r.warnings);
    for (const auto& s : r.surfaces) print_warnings(s.warnings, s.name);
    if (json) {
        std::cout << iso::core::mesh_json(r).dump(2) << "\n";
        return;
    }
    if (r.ranks) print_ranks(*r.ranks);
    for (const auto& s : r.surfaces) print_surface(s, r);
    if (r.streamed) print_streamed(*r.streamed);
    if (r.in_memory) print_in_memory(*r.in_memory);
}

#ifdef ISOSCOPE_MPI
// The ranks' reduced statistics as the summary every route gives.
iso::core::MeshResult distributed_result(const iso::cluster::DistMeshResult& res, bool labels) {
    iso::core::MeshResult m;
    m.route = iso::core::MeshRoute::Distributed;
    m.warnings = res.warnings;
    m.ranks = iso::core::RankDetails{res.ranks, res.rank_active, res.rank_slabs, res.rank_peak_bytes};
    for (const auto& s : res.surfaces) {
        auto ms = iso::core::summarized_surface(s.name, s.path, labels, s.value, s.summary);
        ms.pieces = s.pieces;
        m.surfaces.push_back(std::move(ms));
    }
    return m;
}

// `mpirun -np N isoscope mesh ... -o OUT.pvtp` (docs/cluster.md): every rank
// runs this; rank 0 alone prints. An error agreed by all ranks is printed
// once (by rank 0) and every rank exits 1; anything else (a bug outside an
// agreement point) aborts the job rather than leave the others waiting.
int run_mesh_mpi(const MeshArgs& a) {
    if (a.post.smooth > 0 || a.post.decimate > 0 || a.post.keep_largest)
        throw iso::Error("isoscope mesh", "--smooth, --decimate and --largest need the whole mesh in one process; "
                                          "they are not available under mpirun");
    iso::cluster::Runtime runtime(nullptr, nullptr);
    const iso::cluster::Comm comm;
    iso::cluster::DistMeshRequest r;
    r.input = a.in;
    r.output = a.out;
    r.series = a.series;
    r.labels = a.labels;
    r.isos = a.labels ? a.label_values : a.isos;
    r.extract.threads = a.threads;
    r.extract.chunk_size = a.chunk;
    r.memory_budget = a.memory_mib > 0 ? std::size_t(a.memory_mib * 1048576.0) : iso::cluster::default_rank_budget();
    r.overlap = !a.no_overlap;
    if (comm.root()) {
        r.progress = progress_bar();
        r.extract.progress = progress_bar();
    }
    try {
        const auto res = iso::cluster::mesh_distributed(comm, r);
        if (comm.root()) print_result(distributed_result(res, a.labels), a.json);
        return 0;
    } catch (const iso::cluster::AgreedError& e) {
        if (comm.root()) std::cerr << "isoscope: error: " << e.where() << ": " << cli_text(e.reason()) << "\n";
        return 1;
    } catch (const std::exception& e) {
        iso::cluster::Runtime::abort_job(e.what());
    }
}
#endif

int run_mesh(const MeshArgs& a) {
    if (a.isos.empty() && !a.labels) throw iso::Error("isoscope mesh", "give --iso V (repeatable) or --labels");
    if (!a.isos.empty() && a.labels) throw iso::Error("isoscope mesh", "--iso and --labels exclude each other");
#ifdef ISOSCOPE_MPI
    if (iso::cluster::launched_by_mpirun()) return run_mesh_mpi(a);
#endif
    iso::core::MeshRequest req;
    req.input = a.in;
    req.output = a.out;
    req.series = a.series;
    req.isos = a.isos;
    req.labels = a.labels;
    req.label_values = a.label_values;
    req.extract.threads = a.threads;
    req.extract.chunk_size = a.chunk;
    req.post = a.post;
    req.memory_budget = memory_bytes_option(a.memory_mib);
    req.stream = a.stream;
    req.overlap = !a.no_overlap;
    req.progress = progress_bar();
    print_result(iso::core::mesh_surfaces(req), a.json);
    return 0;
}

} // namespace

RunFn add_mesh(CLI::App& cmd, char*) {
    const auto args = std::make_shared<MeshArgs>();
    MeshArgs& a = *args;
    CLI::App* c = &cmd;
    c->add_option("input", a.in, "Volume file or DICOM folder")->required();
    c->add_option("--iso", a.isos, "Iso value (repeat for several surfaces, e.g. --iso -500 --iso 300)")
        ->allow_extra_args(false);
    c->add_flag("--labels", a.labels, "Label map: one surface per label");
    c->add_option("--label", a.label_values, "With --labels: only these labels (repeatable)")->allow_extra_args(false);
    c->add_option("--smooth", a.post.smooth, "Windowed-sinc smoothing factor, 0..1 (Slicer's scale)")
        ->check(CLI::Range(0.0, 1.0));
    c->add_option("--decimate", a.post.decimate, "Fraction of triangles to remove, 0..<1")
        ->check(CLI::Range(0.0, 0.999));
    c->add_flag("--largest", a.post.keep_largest, "Keep only the largest connected component");
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--threads", a.threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
    c->add_option("--chunk", a.chunk, "Chunk size in cells per side")->check(CLI::Range(2, 1024));
    c->add_option("-o,--output", a.out,
                  "Output " + iso::mesh_extensions_text() +
                      ", or .pvtp when streaming (several surfaces: NAME-iso<V>.ext)")
        ->required();
    c->add_option("--memory", a.memory_mib,
                  "Memory budget in MiB for samples and output; larger volumes are streamed "
                  "(default: a quarter of physical memory; under mpirun: per rank, a quarter of "
                  "the node's memory shared by its ranks)")
        ->check(CLI::PositiveNumber);
    c->add_flag("--stream", a.stream, "Stream slabs of the volume from the file even if it fits the budget");
    c->add_flag("--json", a.json,
                "Print one JSON object: per surface its counts, area, closed or open, a volume only where it "
                "means what it says, components; the streaming or MPI figures");
    c->add_flag("--no-overlap", a.no_overlap,
                "When streaming: read, extract and write each slab one after another "
                "(default: overlapped, with slabs sized so that two fit the budget)");
    return [args] { return run_mesh(*args); };
}

} // namespace iso::cli
