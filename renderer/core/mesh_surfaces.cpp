// The route of `isoscope mesh` and its per-surface summary (mesh_surfaces.hpp).
#include "renderer/core/mesh_surfaces.hpp"

#include <chrono>
#include <cmath>
#include <exception>
#include <thread>

#include "io/atomic_file.hpp"
#include "io/mesh.hpp"
#include "io/mesh_sink.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/stream_mesh.hpp"

namespace iso::core {

MeshedSurface summarized_surface(const std::string& name, const std::string& path, bool label, double value,
                                 const SurfaceSummary& s) {
    MeshedSurface m;
    m.name = name;
    m.path = path;
    m.label = label;
    m.value = value;
    m.triangles = s.triangles;
    m.vertices = s.vertices;
    m.area_mm2 = s.area;
    m.boundary_edges = s.boundary_edges;
    m.closed = s.boundary_edges == 0;
    m.components = s.components;
    m.largest = s.largest;
    if (m.closed) {
        m.volume_ml = s.volume / 1000.0;
        m.volume_kind = VolumeKind::Enclosed;
        m.largest_volume_ml = s.largest.volume / 1000.0;
    }
    return m;
}

namespace {

// Streaming keeps one slab's piece of the mesh in memory at a time: what
// needs the whole mesh is refused, naming the setting.
void check_streamable(const MeshRequest& req) {
    const std::string whole = "needs the whole mesh in memory: not available when streaming "
                              "(asked for, or a volume larger than the memory budget)";
    if (req.post.smooth > 0) throw Error("smoothing factor", whole);
    if (req.post.decimate > 0) throw Error("decimation fraction", whole);
    if (req.post.keep_largest) throw Error("largest component", whole);
    if (req.post.keep_at) throw Error("component point", whole);
    if (!req.series.empty()) throw Error("DICOM series", "DICOM series are not streamed");
}

MeshResult mesh_streamed(const MeshRequest& req, std::size_t budget) {
    check_streamable(req);
    StreamMeshRequest sr;
    sr.input = req.input;
    sr.output = req.output;
    sr.isos = req.isos;
    sr.labels = req.labels;
    sr.label_values = req.label_values;
    sr.extract = req.extract;
    sr.memory_budget = budget;
    sr.overlap = req.overlap;
    sr.progress = req.progress;
    const StreamMeshResult s = stream_mesh(sr);
    MeshResult r;
    r.route = MeshRoute::Streamed;
    r.warnings = s.warnings;
    r.warnings.insert(r.warnings.end(), s.stream.warnings.begin(), s.stream.warnings.end());
    for (std::size_t i = 0; i < s.summaries.size() && i < s.paths.size(); ++i)
        r.surfaces.push_back(
            summarized_surface(s.names[i], s.paths[i], req.labels, s.stream.values.at(i), s.summaries[i]));
    r.streamed = StreamedDetails{s.stream, s.memory_budget, peak_resident_bytes(), s.reader_peak_bytes};
    return r;
}

// The in-memory summary, all of it from measure_surface (as `isoscope
// measure`: an open surface's volume is its lower bound): counts, closed or
// open, the volume, and the components (joined where they share a vertex
// position; an extracted surface's vertices are distinct, so these are the
// streamed route's components); the largest picked as the streamed route
// picks it: by triangles, then area.
MeshedSurface measured_surface(const SurfaceInfo& info, const std::string& path, const Mesh& m) {
    const SurfaceMeasures ms = measure_surface(m);
    MeshedSurface s;
    s.name = info.name;
    s.path = path;
    s.label = info.kind == SurfaceInfo::Kind::Label;
    s.value = info.value;
    s.triangles = m.triangles.size();
    s.vertices = m.positions.size();
    s.area_mm2 = ms.area_mm2;
    s.closed = ms.closed;
    s.boundary_edges = ms.boundary_edges;
    s.volume_kind = ms.volume_kind;
    if (ms.volume_kind != VolumeKind::Undefined) s.volume_ml = ms.volume_ml;
    s.components = ms.components.size();
    const SurfacePart* largest = nullptr;
    for (const auto& c : ms.components)
        if (!largest || c.triangles > largest->triangles ||
            (c.triangles == largest->triangles && c.area_mm2 > largest->area_mm2))
            largest = &c;
    if (largest) {
        s.largest.triangles = largest->triangles;
        s.largest.area = largest->area_mm2;
        s.largest.volume = largest->volume_ml * 1000.0;
        if (ms.closed) s.largest_volume_ml = largest->volume_ml;
    }
    s.warnings = m.warnings;
    return s;
}

double seconds_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

MeshResult mesh_in_memory(const MeshRequest& req) {
    if (!is_mesh_path(req.output))
        throw Error(req.output, "unsupported mesh format (write " + mesh_extensions_text() + ")");
    check_writable_destination(req.output); // fail before the long part
    LoadOptions lo;
    lo.series = req.series;
    lo.progress = req.progress;
    Scene scene;
    InMemoryDetails d;
    auto t = std::chrono::steady_clock::now();
    if (scene.open(req.input, lo) != 0)
        throw Error(req.input, "is a mesh; isoscope mesh extracts surfaces from volumes");
    d.read_seconds = seconds_since(t);
    MeshResult r;
    r.warnings = scene.volume().meta.warnings;
    ExtractSeconds xs;
    const auto ids = req.labels ? scene.add_label_surfaces(req.label_values, req.extract, req.post, req.progress, &xs)
                                : scene.add_isosurfaces(req.isos, req.extract, req.post, req.progress, &xs);
    for (const auto id : ids) {
        const SurfaceInfo& info = scene.info(id);
        const std::string path = surface_output_path(req.output, info.value, req.labels, ids.size());
        // The file is written on a thread of its own while the surface is
        // analysed: writing waits on the kernel and the disk, the analysis
        // on the cores, and both only read the mesh.
        std::exception_ptr failed;
        std::thread writer([&] {
            const auto tw = std::chrono::steady_clock::now();
            try {
                scene.export_mesh(id, path);
            } catch (...) {
                failed = std::current_exception();
            }
            d.write_seconds += seconds_since(tw);
        });
        t = std::chrono::steady_clock::now();
        try {
            r.surfaces.push_back(measured_surface(info, path, scene.mesh(id)));
        } catch (...) {
            writer.join();
            throw;
        }
        d.analysis_seconds += seconds_since(t);
        writer.join();
        if (failed) std::rethrow_exception(failed);
    }
    d.index_seconds = xs.index;
    d.extract_seconds = xs.extract;
    d.weld_seconds = xs.weld;
    d.postprocess_seconds = xs.postprocess;
    r.in_memory = d;
    return r;
}

nlohmann::json number_or_null(const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

// A signed volume as shown: its size (a cavity's wall: the cavity's), or null.
std::optional<double> shown(const std::optional<double>& signed_volume, double scale = 1.0) {
    if (!signed_volume) return std::nullopt;
    return std::abs(*signed_volume) * scale;
}

nlohmann::json cavity_or_null(const std::optional<double>& signed_volume) {
    return signed_volume ? nlohmann::json(encloses_cavity(*signed_volume)) : nlohmann::json(nullptr);
}

nlohmann::json surface_json(const MeshedSurface& s) {
    nlohmann::json j;
    j["name"] = s.name;
    j[s.label ? "label" : "iso"] = s.value;
    j["path"] = s.path;
    j["triangles"] = s.triangles;
    j["vertices"] = s.vertices;
    j["area_mm2"] = s.area_mm2;
    j["closed"] = s.closed;
    j["boundary_edges"] = s.boundary_edges;
    j["volume_ml"] = number_or_null(shown(s.volume_ml));
    j["volume_mm3"] = number_or_null(shown(s.volume_ml, 1000.0));
    j["volume_kind"] = s.volume_kind ? nlohmann::json(volume_kind_name(*s.volume_kind)) : nlohmann::json(nullptr);
    j["cavity"] = cavity_or_null(s.volume_ml);
    j["components"] = {{"count", s.components},
                       {"largest",
                        {{"triangles", s.largest.triangles},
                         {"area_mm2", s.largest.area},
                         {"volume_ml", number_or_null(shown(s.largest_volume_ml))},
                         {"cavity", cavity_or_null(s.largest_volume_ml)}}}};
    if (s.pieces) j["pieces"] = s.pieces;
    j["warnings"] = s.warnings;
    return j;
}

nlohmann::json streamed_busy_json(const StreamStats& s) {
    return {{"index", s.index_seconds},           {"read", s.read_seconds - s.index_seconds},
            {"extract", s.extract_seconds},       {"weld", s.weld_seconds},
            {"write", s.write_seconds},           {"analysis", s.analysis_seconds},
            {"extraction_waited", s.wait_seconds}};
}

nlohmann::json in_memory_busy_json(const InMemoryDetails& d) {
    return {{"read", d.read_seconds},
            {"index", d.index_seconds},
            {"extract", d.extract_seconds},
            {"weld", d.weld_seconds},
            {"postprocess", d.postprocess_seconds},
            {"write", d.write_seconds},
            {"analysis", d.analysis_seconds}};
}

nlohmann::json streamed_json(const StreamedDetails& d) {
    const StreamStats& s = d.stats;
    return {{"slabs", s.plan.slabs},
            {"chunk_layers_per_slab", s.plan.layers_per_slab},
            {"chunk_size", s.plan.chunk_size},
            {"slabs_read", s.slabs_read},
            {"slabs_skipped", s.slabs_skipped},
            {"index_pass", s.index_pass},
            {"overlapped", s.plan.overlap},
            {"memory_budget_bytes", d.memory_budget},
            {"engine_peak_bytes", s.peak_bytes},
            {"resident_peak_bytes", d.resident_peak_bytes},
            {"reader_peak_bytes", d.reader_peak_bytes},
            {"busy_seconds", streamed_busy_json(s)}};
}

} // namespace

MeshResult mesh_surfaces(const MeshRequest& req) {
    const std::size_t budget = req.memory_budget ? req.memory_budget : default_memory_budget();
    const bool pieces = is_streamable_mesh_path(req.output) && !is_mesh_path(req.output); // .pvtp: written by streaming
    if (req.stream || pieces || exceeds_budget(req.input, budget)) return mesh_streamed(req, budget);
    return mesh_in_memory(req);
}

nlohmann::json mesh_json(const MeshResult& r) {
    static const char* const routes[] = {"in memory", "streamed", "mpi"};
    nlohmann::json j;
    j["route"] = routes[int(r.route)];
    j["surfaces"] = nlohmann::json::array();
    for (const auto& s : r.surfaces) j["surfaces"].push_back(surface_json(s));
    j["warnings"] = r.warnings;
    j["busy_seconds"] = r.streamed    ? streamed_busy_json(r.streamed->stats)
                        : r.in_memory ? in_memory_busy_json(*r.in_memory)
                                      : nlohmann::json(nullptr);
    j["streaming"] = r.streamed ? streamed_json(*r.streamed) : nlohmann::json(nullptr);
    if (r.ranks)
        j["mpi"] = {{"ranks", r.ranks->ranks},
                    {"active_chunks", r.ranks->active_chunks},
                    {"slabs_read", r.ranks->slabs_read},
                    {"engine_peak_bytes", r.ranks->peak_bytes}};
    else
        j["mpi"] = nullptr;
    return j;
}

} // namespace iso::core
