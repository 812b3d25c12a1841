// isoscope command-line interface. Parses arguments, calls the core API,
// prints. No algorithms live here.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include <filesystem>

#include "io/atomic_file.hpp"
#include <QApplication>
#include <QImage>
#include <QSurfaceFormat>
#include <QTimer>

#include "app/gui/main_window.hpp"
#include "app/gui/viewer.hpp"
#include "io/markups.hpp"
#include "io/mesh_sink.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/stream_mesh.hpp"
#ifdef ISOSCOPE_MPI
#include "renderer/dist/mesh_mpi.hpp"
#endif

namespace {

std::string human_bytes(double b) {
    const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int u = 0;
    while (b >= 1024.0 && u < 4) { b /= 1024.0; ++u; }
    std::ostringstream os;
    os << std::fixed << std::setprecision(u ? 1 : 0) << b << ' ' << unit[u];
    return os.str();
}

void print_info(const nlohmann::json& j, std::ostream& os) {
    os << "source:    " << j["source"].get<std::string>() << "\n";
    os << "format:    " << j["format"].get<std::string>() << " (" << j["storage"].get<std::string>() << ")\n";
    os << "dims:      " << j["dims"][0] << " x " << j["dims"][1] << " x " << j["dims"][2] << "\n";
    os << "type:      " << j["type"].get<std::string>() << "\n";
    os << std::setprecision(6);
    os << "spacing:   " << j["spacing"][0].get<double>() << " x " << j["spacing"][1].get<double>() << " x "
       << j["spacing"][2].get<double>() << " mm\n";
    if (j["range"].is_null())
        os << "range:     not read (header only)\n";
    else
        os << "range:     [" << j["range"][0].get<double>() << ", " << j["range"][1].get<double>() << "]\n";
    os << "memory:    " << human_bytes(j["memory_bytes"].get<double>()) << "\n";
    os << "index -> LPS (mm):\n";
    for (const auto& row : j["index_to_lps"]) {
        os << "  ";
        for (const auto& x : row) os << std::setw(12) << std::fixed << std::setprecision(5) << x.get<double>() << ' ';
        os << "\n";
    }
    os << std::defaultfloat;
    const auto& m = j["metadata"];
    for (const char* key : {"modality", "patient_name", "patient_id", "series_uid", "series_description"})
        if (!m[key].get<std::string>().empty()) os << key << ": " << m[key].get<std::string>() << "\n";
    if (j.contains("series")) {
        os << "series in " << j["source"].get<std::string>() << ":\n";
        int i = 0;
        for (const auto& s : j["series"]) {
            os << (i == j["selected_series"].get<int>() ? " *" : "  ") << "[" << i << "] "
               << s["modality"].get<std::string>() << " #" << s["number"] << " " << s["dims"][0] << "x"
               << s["dims"][1] << "x" << s["dims"][2] << " (" << s["files"] << " files) "
               << s["description"].get<std::string>() << "  " << s["uid"].get<std::string>() << "\n";
            for (const auto& w : s["warnings"]) os << "       warning: " << w.get<std::string>() << "\n";
            ++i;
        }
    }
    for (const auto& w : j["warnings"]) os << "warning: " << w.get<std::string>() << "\n";
}

// A progress bar on stderr when it is a terminal; silent otherwise.
iso::ProgressFn progress_bar() {
    if (!isatty(STDERR_FILENO)) return {};
    return [last = -1](double f, std::string_view stage) mutable {
        int pct = static_cast<int>(f * 100.0 + 0.5);
        if (pct == last) return true;
        last = pct;
        const int width = 30, filled = pct * width / 100;
        std::fprintf(stderr, "\r%-24.*s [%.*s%*s] %3d%%", static_cast<int>(stage.size()), stage.data(), filled,
                     "##############################", width - filled, "", pct);
        if (pct >= 100) std::fputc('\n', stderr);
        std::fflush(stderr);
        return true;
    };
}

// The core names operations and settings in its errors; on the command line
// they are flags.
std::string cli_message(const iso::Error& e) {
    static const std::pair<std::string, std::string> flags[] = {
        {"patient view", "--view"},
        {"AOV", "--aov"},
        {"ao AOV", "--aov ao"},
        {"ambient occlusion", "--ao"},
        {"ambient occlusion reference", "--ao reference"},
        {"ambient occlusion frames", "--ao-frames"},
        {"smoothing factor", "--smooth"},
        {"decimation fraction", "--decimate"},
        {"DICOM series", "--series"},
    };
    std::string where = e.where();
    // renderer/render/disk_ao.cpp names its settings "disk AO <setting>".
    static const std::pair<std::string, std::string> disk_flags[] = {
        {"disk AO passes", "--ao-disk-passes"},
        {"disk AO traversal epsilon", "--ao-disk-epsilon"},
        {"disk AO clip epsilon", "--ao-disk-clip-epsilon"},
        {"disk AO distance attenuation", "--ao-disk-distance-k"},
        {"disk AO triangle attenuation", "--ao-disk-triangle-t"},
        {"disk AO blend minimum weight", "--ao-disk-blend"},
        {"disk AO blend maximum weight", "--ao-disk-blend"},
        {"disk AO receiver offset", "--ao-disk-offset"},
    };
    for (const auto& [core, flag] : disk_flags)
        if (where == core) where = flag;
    const std::string cone = "cone AO setting ";
    if (where.rfind(cone, 0) == 0) where = "--ao-" + where.substr(cone.size());
    for (const auto& [core, flag] : flags)
        if (where == core) where = flag;
    return where.empty() ? e.reason() : where + ": " + e.reason();
}

// How the surfaces of `render` and `view` look: per surface in the order of
// --iso (one each for a mesh), and the frame's background and shading.
struct Look {
    std::vector<double> opacity;
    std::vector<std::string> color;
    std::string background, shading = "lit";
};

void add_look_options(CLI::App* cmd, Look& l) {
    cmd->add_option("--opacity", l.opacity, "Surface opacity 0..1, repeatable in the order of --iso (translucent: VOIT)")
        ->check(CLI::Range(0.0, 1.0))
        ->allow_extra_args(false);
    cmd->add_option("--color", l.color, "Surface colour '#rrggbb' (sRGB), repeatable in the order of --iso")->allow_extra_args(false);
    cmd->add_option("--background", l.background, "Background colour '#rrggbb' (sRGB)");
    cmd->add_option("--shading", l.shading, "lit, or flat (each surface its colour: no lighting, no AO)")->check(CLI::IsMember({"lit", "flat"}));
}

glm::vec3 hex_option(const std::string& flag, const std::string& text) {
    try {
        return iso::core::linear_from_hex(text);
    } catch (const iso::Error& e) {
        throw iso::Error(flag, e.reason());
    }
}

// Opens the input of `render` and `view`: a mesh, or a volume and its
// isosurfaces (--iso required), and gives the surfaces their look.
void open_input(iso::core::Scene& scene, const std::string& input, const std::string& series, const std::vector<double>& isos,
                const Look& look, const std::string& command) {
    iso::LoadOptions lo;
    lo.series = series;
    lo.progress = progress_bar();
    scene.open(input, lo);
    std::vector<iso::core::SurfaceId> in_order; // as the user gave them
    if (scene.has_volume()) {
        for (const auto& w : scene.volume().meta.warnings) std::cerr << "warning: " << w << "\n";
        if (isos.empty()) throw iso::Error("isoscope " + command, input + " is a volume: give --iso V (repeatable)");
        const auto ids = scene.add_isosurfaces(isos, {}, {}, progress_bar());
        for (const auto id : ids)
            for (const auto& w : scene.mesh(id).warnings) std::cerr << "warning: " << scene.info(id).name << ": " << w << "\n";
        for (const double v : isos)
            for (const auto id : ids)
                if (scene.info(id).value == v) in_order.push_back(id);
    } else {
        in_order = scene.surfaces();
    }
    const auto per_surface = [&](const char* flag, std::size_t n) {
        if (n > in_order.size())
            throw iso::Error(flag, std::to_string(n) + " given for " + std::to_string(in_order.size()) + " surface(s)");
    };
    per_surface("--opacity", look.opacity.size());
    per_surface("--color", look.color.size());
    for (std::size_t i = 0; i < look.opacity.size(); ++i) scene.info(in_order[i]).opacity = float(look.opacity[i]);
    for (std::size_t i = 0; i < look.color.size(); ++i) scene.info(in_order[i]).color = hex_option("--color", look.color[i]);
}

// Cone-AO tunables, shared by `render` and `view`.
void add_cone_options(CLI::App* cmd, iso::ConeAoSettings& c) {
    cmd->add_option("--ao-cones", c.cones, "Cones over the hemisphere (cone AO)")->check(CLI::Range(1, 64));
    cmd->add_option("--ao-spheres", c.spheres, "Spheres per cone (cone AO)")->check(CLI::Range(1, 32));
    cmd->add_option("--ao-samples", c.samples, "Poisson-disk columns per sphere (cone AO)")->check(CLI::Range(1, 64));
    cmd->add_option("--ao-strength", c.strength, "AO = 1 - strength * occlusion (cone AO)")->check(CLI::Range(0.0, 4.0));
    cmd->add_option("--ao-layers", c.layers, "Slicemap depth: 128 z-voxels per layer, 1..8 (cone AO)")->check(CLI::Range(1, 8));
    cmd->add_option("--ao-grid", c.grid_scale, "Slicemap texels per image pixel, 0.125..2 (cone AO)")->check(CLI::Range(0.125, 2.0));
    cmd->add_option("--ao-jitter", c.jitter_sets, "Jitter distributions chosen per pixel by a screen hash (cone AO)")->check(CLI::Range(1, 64));
    cmd->add_option("--ao-persistence", c.persistence, "Sphere combination along a cone: 0 independent absorbers, 1 one solid (cone AO)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--ao-ray-weight", c.ray_weight,
                    "Sphere occlusion: 0 occupied volume fraction, 1 blocked-ray fraction of a cutting plane (cone AO)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--ao-axis-weight", c.axis_weight,
                    "Also march each cone's axis as a ray; a cone whose axis is blocked counts as at least this blocked, 0 off, default 1 (cone AO)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--ao-surface-voxels", c.surface_voxels,
                    "Also set the voxels next to every surface, so walls thinner than a voxel occlude; slower voxelization (cone AO)");
    cmd->add_option("--ao-resolution", c.resolution, "Cone-pass pixels per image pixel, 0.25..1; below 1 a bilateral upsampling follows (cone AO)")
        ->check(CLI::Range(0.25, 1.0));
    cmd->add_option("--ao-guard", c.guard,
                    "Largest guard band around the view, fraction of the viewport per side, for occluders just off screen; 0 none (cone AO)")
        ->check(CLI::Range(0.0, 0.5));
}

// Disk-AO tunables (docs/ao.md, "Disk AO on the GPU"), defaults
// DiskAoSettings' (measured against Embree by the CPU benchmark). --ao-disk-blend takes "MIN,MAX" (the weights
// of the convergence blend), parsed by disk_request().
void add_disk_options(CLI::App* cmd, iso::DiskAoSettings& d, std::string& blend) {
    cmd->add_option("--ao-disk-passes", d.passes, "Element passes before the gather, 0..16; 0: none, unmodulated form factors (disk AO; default 0)")
        ->check(CLI::Range(0, 16));
    cmd->add_option("--ao-disk-epsilon", d.traversal_epsilon,
                    "Traversal: open an element while distance^2 < epsilon x area, 0..10000 (disk AO; default 16)")
        ->check(CLI::Range(0.0, 1e4));
    cmd->add_option("--ao-disk-clip-epsilon", d.clip_epsilon, "Tangent-plane snap in mm, 0..0.1 (disk AO; default 1e-6)")
        ->check(CLI::Range(0.0, 0.1));
    cmd->add_option("--ao-disk-distance-k", d.distance_attenuation, "Distance attenuation 1/(1 + k d^2), k 0..100 (disk AO; default 0)")
        ->check(CLI::Range(0.0, 100.0));
    cmd->add_option("--ao-disk-triangle-t", d.triangle_attenuation,
                    "Triangle attenuation: emitter term^t, t 0..16 (disk AO; default 1)")
        ->check(CLI::Range(0.0, 16.0));
    cmd->add_option("--ao-disk-offset", d.receiver_offset,
                    "Receiver raised along its normal by this x R against self-occlusion, 0..0.1 (disk AO; default 0.001)")
        ->check(CLI::Range(0.0, 0.1));
    cmd->add_option("--ao-disk-blend", blend, "Convergence blend weights MIN,MAX of the last two passes (disk AO; default 0.7,0.3)");
}

// "MIN,MAX" of --ao-disk-blend into the settings (empty: unchanged).
void parse_disk_blend(const std::string& text, iso::DiskAoSettings& d) {
    if (text.empty()) return;
    double lo = 0, hi = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%lf,%lf%c", &lo, &hi, &tail) != 2)
        throw iso::Error("--ao-disk-blend", "expected MIN,MAX weights, e.g. 0.7,0.3, got '" + text + "'");
    if (!(lo >= 0 && lo <= 1 && hi >= 0 && hi <= 1))
        throw iso::Error("--ao-disk-blend", "weights must be in 0..1, got '" + text + "'");
    d.min_scale = lo;
    d.max_scale = hi;
}

// ---- isoscope info ---------------------------------------------------------

struct InfoArgs {
    std::string path, series;
    bool json = false, header_only = false;
    double memory_mib = 0;
};

// --memory MiB -> bytes (0: the core's default, a quarter of physical memory).
std::size_t memory_bytes_option(double mib) {
    return mib > 0 ? std::size_t(mib * 1048576.0) : iso::core::default_memory_budget();
}

CLI::App* add_info(CLI::App& app, InfoArgs& a) {
    auto* c = app.add_subcommand("info", "Describe a volume: dimensions, type, spacing, range, index->LPS affine");
    c->add_option("path", a.path, "Volume file or DICOM folder")->required();
    c->add_option("--series", a.series, "DICOM series to load: index in the listing or SeriesInstanceUID");
    c->add_flag("--json", a.json, "Print one JSON object");
    c->add_flag("--header-only", a.header_only, "Read only the header (NIfTI, NRRD, MetaImage; OpenVDB: metadata and topology): no value range");
    c->add_option("--memory", a.memory_mib, "Volumes larger than this (MiB) are described from their header only "
                                            "(default: a quarter of physical memory)")->check(CLI::PositiveNumber);
    return c;
}

int run_info(const InfoArgs& a) {
    if (a.header_only || iso::core::exceeds_budget(a.path, memory_bytes_option(a.memory_mib))) {
        const auto j = iso::core::describe_header(a.path);
        if (a.json)
            std::cout << j.dump(2) << "\n";
        else
            print_info(j, std::cout);
        return 0;
    }
    iso::LoadOptions opt;
    opt.series = a.series;
    opt.progress = progress_bar();
    const auto j = iso::core::describe(iso::core::open_volume(a.path, opt));
    if (a.json)
        std::cout << j.dump(2) << "\n";
    else
        print_info(j, std::cout);
    return 0;
}

// ---- isoscope mesh ---------------------------------------------------------

struct MeshArgs {
    std::string in, out, series;
    std::vector<double> isos, label_values;
    bool labels = false, stream = false, no_overlap = false;
    iso::PostProcessOptions post;
    int threads = 0, chunk = 32;
    double memory_mib = 0; // per rank under mpirun (0: default_rank_budget())
};

CLI::App* add_mesh(CLI::App& app, MeshArgs& a) {
    auto* c = app.add_subcommand("mesh", "Extract isosurfaces (or label surfaces) and write them in LPS mm");
    c->add_option("input", a.in, "Volume file or DICOM folder")->required();
    c->add_option("--iso", a.isos, "Iso value (repeat for several surfaces, e.g. --iso -500 --iso 300)")->allow_extra_args(false);
    c->add_flag("--labels", a.labels, "Label map: one surface per label");
    c->add_option("--label", a.label_values, "With --labels: only these labels (repeatable)")->allow_extra_args(false);
    c->add_option("--smooth", a.post.smooth, "Windowed-sinc smoothing factor, 0..1 (Slicer's scale)")->check(CLI::Range(0.0, 1.0));
    c->add_option("--decimate", a.post.decimate, "Fraction of triangles to remove, 0..<1")->check(CLI::Range(0.0, 0.999));
    c->add_flag("--largest", a.post.keep_largest, "Keep only the largest connected component");
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--threads", a.threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
    c->add_option("--chunk", a.chunk, "Chunk size in cells per side")->check(CLI::Range(2, 1024));
    c->add_option("-o,--output", a.out, "Output " + iso::mesh_extensions_text() + ", or .pvtp when streaming (several surfaces: NAME-iso<V>.ext)")->required();
    c->add_option("--memory", a.memory_mib, "Memory budget in MiB for samples and output; larger volumes are streamed "
                                            "(default: a quarter of physical memory; under mpirun: per rank, a quarter of "
                                            "the node's memory shared by its ranks)")->check(CLI::PositiveNumber);
    c->add_flag("--stream", a.stream, "Stream slabs of the volume from the file even if it fits the budget");
    c->add_flag("--no-overlap", a.no_overlap, "When streaming: read, extract and write each slab one after another "
                                              "(default: overlapped, with slabs sized so that two fit the budget)");
    return c;
}

// The summary line of one written surface (the same in memory and streaming).
void print_surface_line(const std::string& name, const iso::MeshStats& st, const std::string& path) {
    std::cout << name << ": " << st.triangles << " triangles, " << st.vertices << " vertices, area " << st.area << " mm^2, volume "
              << st.volume << " mm^3 -> " << path << "\n";
}

// Out of core: slabs streamed from the file, the surface written as it goes.
int run_mesh_streaming(const MeshArgs& a, std::size_t budget) {
    if (a.post.smooth > 0) throw iso::Error("--smooth", "needs the whole mesh in memory: not available when streaming (--stream, or a volume larger than --memory)");
    if (a.post.decimate > 0) throw iso::Error("--decimate", "needs the whole mesh in memory: not available when streaming (--stream, or a volume larger than --memory)");
    if (a.post.keep_largest) throw iso::Error("--largest", "needs the whole mesh in memory: not available when streaming (--stream, or a volume larger than --memory)");
    if (!a.series.empty()) throw iso::Error("--series", "DICOM series are not streamed");
    iso::core::StreamMeshRequest req;
    req.input = a.in;
    req.output = a.out;
    req.isos = a.isos;
    req.labels = a.labels;
    req.label_values = a.label_values;
    req.extract.threads = a.threads;
    req.extract.chunk_size = a.chunk;
    req.memory_budget = budget;
    req.overlap = !a.no_overlap;
    req.progress = progress_bar();
    const auto r = iso::core::stream_mesh(req);
    for (const auto& w : r.warnings) std::cerr << "warning: " << w << "\n";
    for (const auto& w : r.stream.warnings) std::cerr << "warning: " << w << "\n";
    for (std::size_t i = 0; i < r.paths.size(); ++i) print_surface_line(r.names[i], r.stats[i], r.paths[i]);
    for (std::size_t i = 0; i < r.summaries.size() && i < r.names.size(); ++i) {
        const auto& c = r.summaries[i];
        std::cout << r.names[i] << ": " << c.components << " components (largest: " << c.largest.triangles << " triangles, area "
                  << c.largest.area << " mm^2, volume " << c.largest.volume << " mm^3)\n";
    }
    const auto& s = r.stream;
    std::cout << "streamed: " << s.plan.slabs << " slabs of " << s.plan.layers_per_slab << " chunk layers (chunk " << s.plan.chunk_size
              << "), " << s.slabs_read << " read, " << s.slabs_skipped << " skipped" << (s.index_pass ? ", after an index pass" : "")
              << "; peak memory " << human_bytes(double(s.peak_bytes)) << " (engine) of " << human_bytes(double(r.memory_budget))
              << ", " << human_bytes(double(iso::core::peak_resident_bytes())) << " resident (VmHWM)";
    if (r.reader_peak_bytes) std::cout << "; OpenVDB reader process peak " << human_bytes(double(r.reader_peak_bytes));
    std::cout << "\n";
    char steps[256];
    std::snprintf(steps, sizeof steps, "index %.2f, read %.2f, extract %.2f, weld %.2f, write %.2f, extraction waited %.2f",
                  s.index_seconds, s.read_seconds - s.index_seconds, s.extract_seconds, s.weld_seconds, s.write_seconds, s.wait_seconds);
    std::cout << "streaming steps (busy seconds" << (s.plan.overlap ? ", overlapped" : "") << "): " << steps << "\n";
    return 0;
}

#ifdef ISOSCOPE_MPI
// `mpirun -np N isoscope mesh ... -o OUT.pvtp` (docs/cluster.md): every rank
// runs this; rank 0 alone prints. An error agreed by all ranks is printed
// once (by rank 0) and every rank exits 1; anything else (a bug outside an
// agreement point) aborts the job rather than leave the others waiting.
int run_mesh_mpi(const MeshArgs& a) {
    if (a.post.smooth > 0 || a.post.decimate > 0 || a.post.keep_largest)
        throw iso::Error("isoscope mesh", "--smooth, --decimate and --largest need the whole mesh in one process; "
                                          "they are not available under mpirun");
    iso::dist::Runtime runtime(nullptr, nullptr);
    const iso::dist::Comm comm;
    iso::dist::DistMeshRequest r;
    r.input = a.in;
    r.output = a.out;
    r.series = a.series;
    r.labels = a.labels;
    r.isos = a.labels ? a.label_values : a.isos;
    r.extract.threads = a.threads;
    r.extract.chunk_size = a.chunk;
    r.memory_budget = a.memory_mib > 0 ? std::size_t(a.memory_mib * 1048576.0) : iso::dist::default_rank_budget();
    r.overlap = !a.no_overlap;
    if (comm.root()) {
        r.progress = progress_bar();
        r.extract.progress = progress_bar();
    }
    try {
        const auto res = iso::dist::mesh_distributed(comm, r);
        if (!comm.root()) return 0;
        for (const auto& w : res.warnings) std::cerr << "warning: " << w << "\n";
        std::cout << res.ranks << " ranks, active chunks per rank:";
        for (auto n : res.rank_active) std::cout << ' ' << n;
        std::cout << ", slabs read:";
        for (auto n : res.rank_slabs) std::cout << ' ' << n;
        std::cout << ", engine peak per rank:";
        for (auto n : res.rank_peak_bytes) std::cout << ' ' << human_bytes(double(n));
        std::cout << "\n";
        for (const auto& s : res.surfaces) {
            const auto& m = s.summary;
            std::cout << s.name << ": " << m.triangles << " triangles, " << m.vertices << " vertices, area " << m.area
                      << " mm^2, volume " << m.volume << " mm^3, " << m.components << " components (largest: "
                      << m.largest.triangles << " triangles, area " << m.largest.area << " mm^2, volume "
                      << m.largest.volume << " mm^3) -> " << s.path << " (" << s.pieces << " pieces from " << res.ranks << " ranks)\n";
        }
        return 0;
    } catch (const iso::dist::AgreedError& e) {
        if (comm.root()) std::cerr << "isoscope: error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        iso::dist::Runtime::abort_job(e.what());
    }
}
#endif

int run_mesh(const MeshArgs& a) {
    if (a.isos.empty() && !a.labels) throw iso::Error("isoscope mesh", "give --iso V (repeatable) or --labels");
    if (!a.isos.empty() && a.labels) throw iso::Error("isoscope mesh", "--iso and --labels exclude each other");
#ifdef ISOSCOPE_MPI
    if (iso::dist::launched_by_mpirun()) return run_mesh_mpi(a);
#endif
    const std::size_t budget = memory_bytes_option(a.memory_mib);
    const bool pieces = iso::is_streamable_mesh_path(a.out) && !iso::is_mesh_path(a.out); // .pvtp: written by the streaming path
    if (a.stream || pieces || iso::core::exceeds_budget(a.in, budget)) return run_mesh_streaming(a, budget);
    if (!iso::is_mesh_path(a.out)) throw iso::Error(a.out, "unsupported mesh format (write " + iso::mesh_extensions_text() + ")");
    iso::check_writable_destination(a.out); // fail before the long part
    iso::LoadOptions lo;
    lo.series = a.series;
    lo.progress = progress_bar();
    iso::core::Scene scene;
    if (scene.open(a.in, lo) != 0) throw iso::Error(a.in, "is a mesh; isoscope mesh extracts surfaces from volumes");
    for (const auto& w : scene.volume().meta.warnings) std::cerr << "warning: " << w << "\n";
    iso::ExtractOptions eo;
    eo.threads = a.threads;
    eo.chunk_size = a.chunk;
    const auto ids = a.labels ? scene.add_label_surfaces(a.label_values, eo, a.post, progress_bar())
                              : scene.add_isosurfaces(a.isos, eo, a.post, progress_bar());
    for (const auto id : ids) {
        const auto& s = scene.info(id);
        const std::string path = iso::core::surface_output_path(a.out, s.value, a.labels, ids.size());
        const auto& m = scene.mesh(id);
        for (const auto& w : m.warnings) std::cerr << "warning: " << s.name << ": " << w << "\n";
        scene.export_mesh(id, path);
        print_surface_line(s.name, iso::mesh_stats(m), path);
    }
    return 0;
}

// ---- isoscope render -------------------------------------------------------

// What fixes a frame, shared by `render` and `pick`: a pick's pixel is a
// pixel of the image `render` writes with the same options.
struct FrameArgs {
    std::string in, view = "anterior", size = "1024x1024", series, ao = "off";
    std::vector<double> isos;
    double ao_radius = 10.0;
    int ao_frames = 1;
    iso::ConeAoSettings cone;
    iso::DiskAoSettings disk;
    std::string disk_blend;
    Look look;
    float oit_epsilon = 1.0f / 512.0f;
    double oit_memory = 256;
};

void add_frame_options(CLI::App* c, FrameArgs& a, bool input_required = true) {
    auto* in = c->add_option("input", a.in, "Volume file, DICOM folder, or mesh (" + iso::mesh_extensions_text() + ")");
    if (input_required) in->required();
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--view", a.view, "anterior, posterior, left, right, superior or inferior");
    c->add_option("--size", a.size, "Image size WxH (default 1024x1024)");
    c->add_option("--ao", a.ao,
                  "Ambient occlusion: off, cone (cone tracing), disk (disk hierarchy, high quality for stills), or reference (Embree ray "
                  "tracing; with --aov ao)");
    c->add_option("--ao-radius", a.ao_radius, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    add_cone_options(c, a.cone);
    add_disk_options(c, a.disk, a.disk_blend);
    c->add_option("--ao-frames", a.ao_frames, "Still frames accumulated with new jitter sets (cone AO)")->check(CLI::Range(1, 4096));
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    add_look_options(c, a.look);
    c->add_option("--oit-epsilon", a.oit_epsilon, "Translucent surfaces: stop compositing a pixel below this transmittance (default 1/512)")
        ->check(CLI::Range(0.0, 0.999));
    c->add_option("--oit-memory", a.oit_memory, "Translucent surfaces: fragment pool cap in MiB (default 256)")->check(CLI::Range(1.0, 65536.0));
}

iso::core::RenderRequest frame_request(const FrameArgs& a) {
    iso::core::RenderRequest req;
    req.view = a.view;
    if (std::sscanf(a.size.c_str(), "%dx%d", &req.width, &req.height) != 2 || req.width < 1 || req.height < 1)
        throw iso::Error("--size", "expected WxH, e.g. 1920x1080, got '" + a.size + "'");
    req.ao = a.ao;
    req.ao_radius_mm = a.ao_radius;
    req.cone = a.cone;
    req.disk = a.disk;
    parse_disk_blend(a.disk_blend, req.disk);
    req.ao_frames = a.ao_frames;
    req.progress = progress_bar();
    if (!a.look.background.empty()) req.background = hex_option("--background", a.look.background);
    req.flat_shading = a.look.shading == "flat";
    req.oit_epsilon = a.oit_epsilon;
    req.oit_memory_mib = a.oit_memory;
    return req;
}

struct RenderArgs {
    FrameArgs frame;
    std::string out, aov, cache, session;
    std::vector<std::string> markups;
    float scale = 1.0f;
    bool stats = false, no_annotations = false, transparent = false, no_markups = false;
    bool view_given = false, ao_given = false; // with --session: replace the session's camera / view option
    int ao_rays = 1024;
};

CLI::App* add_render(CLI::App& app, RenderArgs& a) {
    auto* c = app.add_subcommand("render", "Render surfaces of a volume (or a mesh) to an annotated image");
    add_frame_options(c, a.frame, false);
    c->add_option("--session", a.session, "Render a session file of the desktop app (its input, surfaces, camera, markups, AO) "
                                          "instead of INPUT; --view replaces its camera, --ao its AO setting");
    c->add_flag("--no-markups", a.no_markups, "With --session: leave out the session's markups");
    c->add_option("--scale", a.scale, "Scale of text, lines and glyphs (e.g. 2 for a 2x export)")->check(CLI::Range(0.1, 20.0));
    c->add_option("--aov", a.aov, "Write a buffer instead of the colour image: depth, normal, id or ao (EXR)");
    c->add_option("--ao-rays", a.ao_rays, "Rays per pixel for --ao reference")->check(CLI::Range(1, 1 << 20));
    c->add_option("--ao-cache", a.cache, "Folder caching AO references ('-': none; default ~/.cache/isoscope)");
    c->add_flag("--no-annotations", a.no_annotations, "No scale bar, orientation letters or labels (--markups are still drawn)");
    c->add_option("--markups", a.markups, "3D Slicer markups file (.mrk.json) to draw: points, lines with their length, angles "
                                          "(repeatable; dimmed where a surface hides them)")
        ->allow_extra_args(false);
    c->add_flag("--transparent", a.transparent, "Transparent background");
    c->add_flag("--stats", a.stats, "Print per-pass statistics");
    c->add_option("-o,--output", a.out, "Output .png, .tif or .exr")->required();
    return c;
}

void print_stats(const iso::graph::FrameStats& stats, const iso::OitStats& oit) {
    std::cout << std::left << std::setw(14) << "pass" << std::setw(8) << "ran" << std::setw(12) << "ms" << "created\n";
    double total = 0;
    for (const auto& p : stats.passes) {
        std::cout << std::setw(14) << p.name << std::setw(8) << (p.ran ? "yes" : "culled") << std::setw(12) << std::fixed << std::setprecision(2)
                  << p.ms << human_bytes(double(p.bytes_created)) << "\n";
        total += p.ms;
    }
    std::cout << "total " << total << " ms; " << stats.physical_resources << " resources created, " << stats.reused_resources
              << " reused; peak " << human_bytes(double(stats.peak_bytes)) << "\n";
    if (oit.fragments > 0)
        std::cout << "transparency: " << oit.fragments << " fragments in " << oit.lists << " pixel lists (longest " << oit.max_list << "), "
                  << oit.shaded << " shaded, " << oit.merged << " merged past the cap; pool " << oit.capacity << " nodes, " << oit.redraws
                  << " redraw(s)\n";
    if (oit.merged > 0)
        std::cout << "transparency: merged fragments in " << oit.merged_pixels << " pixels, error at most " << std::setprecision(4)
                  << oit.merge_error_max << " (linear colour, per channel)\n";
}

// `isoscope render --session`: the request comes from core::session_request,
// as the desktop app's File > Export image builds it; the frame's other
// options (size, background, AO tunables, ...) apply on top.
iso::core::RenderRequest session_render_request(const RenderArgs& a, iso::core::OpenedSession& opened) {
    const auto& f = a.frame;
    if (!f.in.empty()) throw iso::Error("--session", "the session names its input: give INPUT or --session, not both");
    for (const auto& [given, flag] : {std::pair{!f.isos.empty(), "--iso"}, {!f.series.empty(), "--series"},
                                     {!f.look.opacity.empty(), "--opacity"}, {!f.look.color.empty(), "--color"}})
        if (given) throw iso::Error(flag, "the session holds the surfaces and the series: not with --session");
    const iso::core::RenderRequest frame = frame_request(f);
    iso::core::SessionRenderOptions o;
    o.width = frame.width;
    o.height = frame.height;
    o.scale = a.scale;
    o.annotations = !a.no_annotations;
    o.transparent = a.transparent;
    o.markups = !a.no_markups;
    if (a.ao_given) o.ao = f.ao;
    iso::core::RenderRequest req = iso::core::session_request(opened.session, a.session, o);
    if (a.view_given) {
        req.camera.reset();
        req.view = f.view;
    }
    req.background = frame.background;
    req.flat_shading = frame.flat_shading;
    req.oit_epsilon = frame.oit_epsilon;
    req.oit_memory_mib = frame.oit_memory_mib;
    req.ao_radius_mm = frame.ao_radius_mm;
    req.cone = frame.cone;
    req.disk = frame.disk;
    req.ao_frames = frame.ao_frames;
    req.progress = frame.progress;
    return req;
}

int run_render(const RenderArgs& a) {
    if (a.session.empty() && a.frame.in.empty()) throw iso::Error("isoscope render", "give an INPUT (or --session FILE)");
    if (a.no_markups && a.session.empty()) throw iso::Error("--no-markups", "only with --session (without it, give no --markups)");
    std::optional<iso::core::OpenedSession> opened;
    iso::core::RenderRequest req;
    if (a.session.empty()) {
        req = frame_request(a.frame);
    } else {
        iso::check_writable_destination(a.out);
        opened = iso::core::open_session(a.session, progress_bar());
        for (const auto& w : opened->session.warnings) std::cerr << "warning: " << a.session << ": " << w << "\n";
        req = session_render_request(a, *opened);
    }
    req.scale = a.scale;
    req.aov_ao = a.aov == "ao";
    req.aov = req.aov_ao ? iso::Aov::None : iso::aov_from_name(a.aov);
    req.ao_rays = a.ao_rays;
    req.cache_dir = a.cache;
    req.annotations = !a.no_annotations;
    req.transparent = a.transparent;
    req.time_passes = a.stats;
    if (!a.markups.empty() && !a.aov.empty()) throw iso::Error("--markups", "markups are drawn on the colour image, not on an AOV (--aov)");
    iso::check_writable_destination(a.out);
    // Markups before the volume: a bad file fails fast, naming itself.
    for (const auto& path : a.markups) {
        auto f = iso::load_markups(path);
        for (const auto& w : f.warnings) std::cerr << "warning: " << path << ": " << w << "\n";
        for (auto& m : f.markups) req.markups.push_back(std::move(m));
        req.markups_files.push_back(path);
    }
    iso::core::Scene local;
    if (!opened) open_input(local, a.frame.in, a.frame.series, a.frame.isos, a.frame.look, "render");
    const auto out = iso::core::render_image(opened ? *opened->scene : local, req);
    iso::core::export_image(out.image, out.meta, a.out);
    std::cout << "rendered " << out.image.width << "x" << out.image.height << " (" << out.gl_renderer << ") -> " << a.out << "\n";
    if (a.stats) print_stats(out.stats, out.oit);
    if (out.oit.merged > 0)
        std::cerr << "warning: " << out.oit.merged << " translucent fragments in " << out.oit.merged_pixels << " pixels did not fit the "
                  << a.frame.oit_memory << " MiB pool (--oit-memory) and were merged, order-independently: error at most " << std::setprecision(3)
                  << out.oit.merge_error_max << " per channel\n";
    return 0;
}

// ---- isoscope pick ---------------------------------------------------------

struct PickArgs {
    FrameArgs frame;
    std::string at, rect;
    double threshold = 0.5;
    bool all_layers = false, json = false;
};

CLI::App* add_pick(CLI::App& app, PickArgs& a) {
    auto* c = app.add_subcommand("pick", "What is seen at a pixel of the image `render` writes with the same options: "
                                         "surface, LPS point, normal, value (HU); every layer through translucent ones");
    add_frame_options(c, a.frame);
    c->add_option("--at", a.at, "Pixel X,Y from the image's top-left")->required();
    c->add_option("--rect", a.rect, "Also list the triangles visible in the rectangle X,Y,W,H");
    c->add_option("--threshold", a.threshold, "The visible layer: the first whose accumulated opacity reaches this (default 0.5)")
        ->check(CLI::Range(0.0, 1.0));
    c->add_flag("--all-layers", a.all_layers, "List every layer down to the first opaque one");
    c->add_flag("--json", a.json, "Print JSON");
    return c;
}

std::vector<int> ints(const std::string& flag, const std::string& text, std::size_t n) {
    std::vector<int> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            std::size_t used = 0;
            v.push_back(std::stoi(item, &used));
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            v.clear();
            break;
        }
    }
    if (v.size() != n) throw iso::Error(flag, "expected " + std::to_string(n) + " integers separated by commas, got '" + text + "'");
    return v;
}

int run_pick(const PickArgs& a) {
    const iso::core::RenderRequest req = frame_request(a.frame);
    iso::core::PickRequest p;
    const auto at = ints("--at", a.at, 2);
    p.x = at[0];
    p.y = at[1];
    if (!a.rect.empty()) {
        const auto r = ints("--rect", a.rect, 4);
        if (r[2] < 1 || r[3] < 1) throw iso::Error("--rect", "width and height must be at least 1, got '" + a.rect + "'");
        p.rect = {r[0], r[1], r[2], r[3]};
    }
    p.threshold = a.threshold;
    p.all_layers = a.all_layers;
    iso::core::Scene scene;
    open_input(scene, a.frame.in, a.frame.series, a.frame.isos, a.frame.look, "pick");
    const auto r = iso::core::pick(scene, req, p);
    if (!r.complete) std::cerr << "warning: the pick's lists overflowed: some layers are missing\n";
    if (a.json) {
        std::cout << iso::core::pick_json(r).dump(2) << "\n";
        return 0;
    }
    std::cout << "pixel " << r.x << "," << r.y << " of " << r.width << "x" << r.height << ": ";
    if (r.layers.empty()) std::cout << "background\n";
    else if (!r.visible) std::cout << "nothing opaque enough (threshold " << a.threshold << ")\n";
    else std::cout << r.layers[*r.visible].name << "\n";
    std::cout << std::fixed;
    for (std::size_t i = 0; i < r.layers.size(); ++i) {
        const auto& l = r.layers[i];
        std::cout << (r.visible && *r.visible == i ? "* " : "  ") << std::setw(10) << std::left << l.name << std::right << std::setprecision(2)
                  << " LPS (" << l.lps.x << ", " << l.lps.y << ", " << l.lps.z << ") mm, depth " << l.depth_mm << " mm, alpha "
                  << std::setprecision(3) << l.alpha << ", share " << l.share;
        if (l.hu) std::cout << ", value " << std::setprecision(1) << *l.hu;
        if (l.voxel) std::cout << ", voxel (" << (*l.voxel)[0] << ", " << (*l.voxel)[1] << ", " << (*l.voxel)[2] << ")";
        std::cout << ", triangle " << l.triangle << "\n";
    }
    if (r.rect.width > 0) std::cout << r.triangles.size() << " triangles visible in the rectangle\n";
    return 0;
}

// ---- isoscope measure ------------------------------------------------------

struct MeasureArgs {
    std::string in, series, out;
    std::vector<double> isos;
    std::vector<std::string> distance, angle, hu;
    bool json = false;
};

CLI::App* add_measure(CLI::App& app, MeasureArgs& a) {
    auto* c = app.add_subcommand("measure", "Measure surfaces (area, volume, closed/open, components, uncertainty) and points "
                                            "(distance, angle, value) in LPS mm");
    c->add_option("input", a.in, "Volume file, DICOM folder, or mesh (" + iso::mesh_extensions_text() + ")")->required();
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--distance", a.distance, "Distance between two points: --distance X,Y,Z X,Y,Z (LPS mm; repeatable)")->expected(2)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    c->add_option("--angle", a.angle, "Angle at the middle of three points: --angle P1 P2 P3 (repeatable)")->expected(3)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    c->add_option("--hu", a.hu, "The volume's value (HU for CT) at a point X,Y,Z (repeatable)")->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    c->add_flag("--json", a.json, "Print JSON");
    c->add_option("-o,--output", a.out, "Write the points, distances and angles as 3D Slicer markups (.mrk.json, LPS)");
    return c;
}

int run_measure(const MeasureArgs& a) {
    iso::core::PointMeasurements points;
    for (std::size_t i = 0; i + 1 < a.distance.size(); i += 2)
        points.distances.push_back({iso::core::parse_point("--distance", a.distance[i]), iso::core::parse_point("--distance", a.distance[i + 1])});
    for (std::size_t i = 0; i + 2 < a.angle.size(); i += 3)
        points.angles.push_back({iso::core::parse_point("--angle", a.angle[i]), iso::core::parse_point("--angle", a.angle[i + 1]),
                                 iso::core::parse_point("--angle", a.angle[i + 2])});
    for (const auto& t : a.hu) points.values.push_back(iso::core::parse_point("--hu", t));
    if (!a.out.empty()) {
        const std::string suffix = ".mrk.json";
        if (a.out.size() < suffix.size() || a.out.compare(a.out.size() - suffix.size(), suffix.size(), suffix) != 0)
            throw iso::Error("--output", "markups are written as .mrk.json, got '" + a.out + "'");
        iso::check_writable_destination(a.out);
    }
    iso::core::Scene scene;
    open_input(scene, a.in, a.series, a.isos, {}, "measure");
    const auto surfaces = iso::core::measure_surfaces(scene);
    const auto j = iso::core::measure_json(scene, surfaces, points);
    if (!a.out.empty()) iso::save_markups(iso::core::point_markups(scene, points), a.out);
    if (a.json) {
        std::cout << j.dump(2) << "\n";
    } else {
        std::cout << std::fixed;
        for (const auto& s : j["surfaces"]) {
            std::cout << s["surface"].get<std::string>() << ": area " << std::setprecision(1) << s["area_mm2"].get<double>() << " mm2";
            if (!s["area_uncertainty_mm2"].is_null()) std::cout << " +- " << s["area_uncertainty_mm2"].get<double>();
            const std::string kind = s["volume_kind"].get<std::string>();
            if (s["volume_ml"].is_null())
                std::cout << ", volume undefined (" << kind << ")";
            else
                std::cout << ", volume " << (kind == "lower bound" ? ">= " : "") << std::setprecision(3) << s["volume_ml"].get<double>() << " mL";
            if (!s["volume_uncertainty_ml"].is_null()) std::cout << " +- " << s["volume_uncertainty_ml"].get<double>();
            if (!s["volume_extrapolated_ml"].is_null() && kind == "enclosed")
                std::cout << " (extrapolated to zero voxel size: " << s["volume_extrapolated_ml"].get<double>() << ")";
            if (s["closed"].get<bool>())
                std::cout << ", closed";
            else
                std::cout << ", open (boundary " << std::setprecision(1) << s["boundary"]["length_mm"].get<double>() << " mm)";
            std::cout << ", " << s["components"].size() << " component(s)\n";
            for (const auto& w : s["warnings"]) std::cout << "  note: " << w.get<std::string>() << "\n";
        }
        for (const auto& d : j["distances"]) std::cout << "distance " << std::setprecision(3) << d["distance_mm"].get<double>() << " mm\n";
        for (const auto& an : j["angles"]) std::cout << "angle " << std::setprecision(3) << an["angle_deg"].get<double>() << " deg\n";
        for (const auto& v : j["values"]) {
            if (v["value"].is_null())
                std::cout << "value: outside the volume\n";
            else
                std::cout << "value " << std::setprecision(2) << v["value"].get<double>() << "\n";
        }
    }
    if (!a.out.empty()) std::cerr << "markups -> " << a.out << "\n";
    return 0;
}

// ---- isoscope view ---------------------------------------------------------

// Qt's windows get a GL 4.5 core context with a depth buffer (before the
// QApplication is made), as the renderer needs.
void use_gl45_surfaces() {
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
}

struct ViewArgs {
    std::string in, view = "anterior", screenshot, series, ao = "cone";
    std::vector<double> isos;
    iso::gui::ViewerOptions opt;
    Look look;
};

CLI::App* add_view(CLI::App& app, ViewArgs& a) {
    auto* c = app.add_subcommand("view", "Open a window showing the surfaces (mouse: orbit, pan, zoom; keys a p l r s i: views)");
    c->add_option("input", a.in, "Volume file, DICOM folder, or mesh")->required();
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--view", a.view, "Initial view: anterior, posterior, left, right, superior or inferior");
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--screenshot", a.screenshot, "Save the first converged frame to this PNG and quit (tests)");
    c->add_option("--ao", a.ao, "Ambient occlusion: cone (default) or off; key O toggles it")->check(CLI::IsMember({"cone", "off"}));
    c->add_option("--ao-radius", a.opt.cone.radius_mm, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    add_cone_options(c, a.opt.cone);
    c->add_option("--ao-frames", a.opt.still_frames, "Still frames accumulated with new jitter sets while nothing moves")
        ->check(CLI::Range(1, 4096));
    add_look_options(c, a.look);
    return c;
}

int run_view(ViewArgs a, char* argv0) {
    const auto initial = iso::patient_view_from_name(a.view);
    iso::validate(a.opt.cone); // before the long part
    iso::core::Scene scene;
    open_input(scene, a.in, a.series, a.isos, a.look, "view");
    if (!a.look.background.empty()) a.opt.background = hex_option("--background", a.look.background);
    a.opt.flat_shading = a.look.shading == "flat";
    use_gl45_surfaces();
    int qargc = 1;
    char* qargv[] = {argv0, nullptr};
    QApplication qapp(qargc, qargv);
    a.opt.ao = a.ao == "cone";
    iso::gui::Viewer w(scene, initial, a.opt);
    w.setWindowTitle(QString::fromStdString("isoscope - " + a.in));
    w.resize(800, 600);
    w.show();
    QTimer poll;
    if (!a.screenshot.empty()) {
        // Grab once the picture has converged (the first frame without AO;
        // all still frames with it), then quit.
        QObject::connect(&poll, &QTimer::timeout, [&] {
            if (!w.converged() && w.error().empty()) return;
            poll.stop();
            if (!w.error().empty()) {
                qapp.exit(1);
                return;
            }
            if (!w.grabFramebuffer().save(QString::fromStdString(a.screenshot))) {
                std::cerr << "isoscope: error: " << a.screenshot << ": cannot save the screenshot\n";
                qapp.exit(1);
                return;
            }
            std::cout << "view: " << w.frames() << " frames; " << w.gl_objects_since_first_frame()
                      << " GL objects created after the first -> " << a.screenshot << "\n";
            qapp.exit(0);
        });
        poll.start(50);
    }
    return qapp.exec();
}

// ---- isoscope gui -----------------------------------------------------------

// The desktop app (docs/gui.md); also what `isoscope` with no arguments
// starts where there is a display.
int run_gui(const std::string& in, char* argv0) {
    use_gl45_surfaces();
    int qargc = 1;
    char* qargv[] = {argv0, nullptr};
    QApplication qapp(qargc, qargv);
    QApplication::setOrganizationName("isoscope");
    QApplication::setApplicationName("isoscope");
    iso::gui::MainWindow w;
    w.show();
    // A session (.json: no volume or mesh format uses it) restores what it saved.
    const std::string json = ".json";
    const bool session = in.size() > json.size() && in.compare(in.size() - json.size(), json.size(), json) == 0;
    if (session) w.open_session(QString::fromStdString(in));
    else if (!in.empty()) w.open_path(QString::fromStdString(in));
    return qapp.exec();
}

} // namespace

int main(int argc, char** argv) {
    // No arguments: the desktop app where there is a display, the help otherwise.
    if (argc == 1 && (std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY"))) return run_gui("", argv[0]);
    CLI::App app{"isoscope: inspect CT volumes, reconstruct and render isosurfaces"};
    app.set_version_flag("--version", std::string("isoscope ") + iso::core::version());
    app.require_subcommand(1);
    InfoArgs info_args;
    MeshArgs mesh_args;
    RenderArgs render_args;
    ViewArgs view_args;
    PickArgs pick_args;
    MeasureArgs measure_args;
    auto* info = add_info(app, info_args);
    auto* mesh = add_mesh(app, mesh_args);
    auto* render = add_render(app, render_args);
    auto* view = add_view(app, view_args);
    auto* pick = add_pick(app, pick_args);
    auto* measure = add_measure(app, measure_args);
    std::string gui_in;
    auto* gui = app.add_subcommand("gui", "Open the desktop app (main window with the 3D and slice views)");
    gui->add_option("input", gui_in, "Volume file, DICOM folder, mesh, or session (.json) to open");
    CLI11_PARSE(app, argc, argv);
    render_args.view_given = render->get_option("--view")->count() > 0;
    render_args.ao_given = render->get_option("--ao")->count() > 0;
    try {
        if (*info) return run_info(info_args);
        if (*mesh) return run_mesh(mesh_args);
        if (*render) return run_render(render_args);
        if (*view) return run_view(view_args, argv[0]);
        if (*pick) return run_pick(pick_args);
        if (*measure) return run_measure(measure_args);
        if (*gui) return run_gui(gui_in, argv[0]);
    } catch (const iso::Error& e) {
        std::cerr << "isoscope: error: " << cli_message(e) << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "isoscope: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
