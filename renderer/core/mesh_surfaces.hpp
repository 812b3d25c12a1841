// `isoscope mesh`: surfaces of a volume written to files, by the route the
// volume and the request call for (docs/isosurface.md): in memory through a
// Scene, or streamed slab by slab (stream_mesh) when the volume exceeds the
// memory budget, streaming is asked for or the output is a .pvtp. Every
// route reports the same per-surface summary (MeshedSurface), so that the
// CLI parses, calls and prints only. The MPI route (renderer/dist,
// mesh_distributed) builds on this library; its caller converts the
// reduced statistics with summarized_surface().
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/progress.hpp"
#include "renderer/surface/components.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/postprocess.hpp"
#include "renderer/surface/stream.hpp"

namespace iso::core {

struct MeshRequest {
    std::string input, output; // output: a mesh file, or .pvtp (streamed); several surfaces: surface_output_path
    std::string series;        // DICOM series (in memory only)
    std::vector<double> isos;
    bool labels = false; // a label map: one surface per label (label_values, or every non-zero label)
    std::vector<double> label_values;
    ExtractOptions extract;        // threads, chunk size
    PostProcessOptions post;       // in memory only: it needs the whole mesh
    std::size_t memory_budget = 0; // 0: default_memory_budget(); a volume above it is streamed
    bool stream = false;           // stream even a volume that fits the budget
    bool overlap = true;           // streamed: StreamOptions::overlap
    ProgressFn progress;
};

// One surface written, whatever the route. The volume is given only where it
// means what it says: a closed surface's enclosed volume; for an open surface
// in memory, the lower bound `isoscope measure` gives (measure_surface: the
// boundary loops capped); for an open surface streamed or from MPI ranks,
// none (their statistics are sums over pieces, without caps).
struct MeshedSurface {
    std::string name, path; // "iso 500" / "label 3", the file written
    bool label = false;
    double value = 0; // iso value or label
    std::size_t triangles = 0, vertices = 0;
    double area_mm2 = 0;
    bool closed = true; // no edge used by one triangle
    std::size_t boundary_edges = 0;
    std::optional<double> volume_ml;         // signed (encloses_cavity); read with volume_kind
    std::optional<VolumeKind> volume_kind;   // none where no volume is known
    std::size_t components = 0;              // connected through shared vertices
    ComponentStats largest;                  // by triangles, then area (its volume: see largest_volume_ml)
    std::optional<double> largest_volume_ml; // signed; a closed surface's only (then every component is closed)
    std::size_t pieces = 0;                  // MPI: the .vtp files the .pvtp lists
    std::vector<std::string> warnings;       // of its extraction
};

enum class MeshRoute { InMemory, Streamed, Distributed };

// The streamed route's figures (StreamStats, and the process's memory).
struct StreamedDetails {
    StreamStats stats;
    std::size_t memory_budget = 0, resident_peak_bytes = 0;
    std::size_t reader_peak_bytes = 0; // OpenVDB read slab by slab: the reading child's peak
};

// The in-memory route's figures: the seconds each step was busy, named as the
// streamed route's (StreamStats): reading the volume; its range index
// (per-chunk min/max) and value range; marching cubes; welding the chunks;
// post-processing; writing the files; the analysis behind the summary
// (measure_surface: closed or open, volume, components). A surface's file is
// written on a thread of its own while it is analysed: those two overlap,
// and the seconds add up to more than the wall time.
struct InMemoryDetails {
    double read_seconds = 0, index_seconds = 0, extract_seconds = 0, weld_seconds = 0, postprocess_seconds = 0,
           write_seconds = 0, analysis_seconds = 0;
};

// The MPI route's figures, per rank.
struct RankDetails {
    int ranks = 1;
    std::vector<std::size_t> active_chunks, slabs_read, peak_bytes;
};

struct MeshResult {
    MeshRoute route = MeshRoute::InMemory;
    std::vector<MeshedSurface> surfaces;
    std::vector<std::string> warnings; // of the volume (and of the streaming engine)
    std::optional<InMemoryDetails> in_memory;
    std::optional<StreamedDetails> streamed;
    std::optional<RankDetails> ranks;
};

// Chooses the route and writes every surface. Throws iso::Error (settings,
// input or output; post-processing or a DICOM series on the streamed route)
// or Cancelled; nothing half-written is left in place.
MeshResult mesh_surfaces(const MeshRequest& req);

// The summary of a surface known by its piece statistics (streamed, MPI).
MeshedSurface summarized_surface(const std::string& name, const std::string& path, bool label, double value,
                                 const SurfaceSummary& s);

// JSON of `isoscope mesh --json`: "route", "surfaces" (per surface: name,
// iso or label, path, triangles, vertices, area_mm2, closed, boundary_edges,
// volume_ml, volume_mm3, volume_kind and cavity (null where not known; the
// volume never negative: a cavity's wall gives the cavity's volume and
// cavity true, encloses_cavity), components {count, largest {triangles,
// area_mm2, volume_ml, cavity}}, warnings; pieces under MPI), "warnings",
// "busy_seconds" (each step's, in memory and streamed; null under MPI),
// "streaming" and "mpi" (their figures, or null).
nlohmann::json mesh_json(const MeshResult& r);

} // namespace iso::core
