// `isoscope mesh` and `isoscope info` on volumes larger than memory: the
// out-of-core path of the core (renderer/surface/stream.hpp; docs/isosurface.md,
// "Out of core"). The CLI only parses flags and prints.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/mesh.hpp"
#include "io/progress.hpp"
#include "renderer/surface/components.hpp"
#include "renderer/surface/stream.hpp"

namespace iso::core {

// The default memory budget: a quarter of physical memory (sysconf), so that
// the page cache that feeds the reads, the output's write-back and other
// programs keep the rest.
std::size_t default_memory_budget();

// Peak resident memory of this process so far (VmHWM of /proc/self/status), bytes; 0 if unknown.
std::size_t peak_resident_bytes();

// Does the volume at `path` need more than `budget` bytes in memory? From its
// header alone (NIfTI, NRRD, MetaImage; OpenVDB: twice its grid, which the
// reading child and this process hold for a moment); false for formats whose
// header cannot be read alone (they are loaded whole).
bool exceeds_budget(const std::string& path, std::size_t budget);

// `isoscope info` without reading the samples: what describe() gives, with
// "range" null and "range_read" false.
nlohmann::json describe_header(const std::string& path);

// The output file of surface `value` when several are written: NAME-iso<V>.ext
// or NAME-label<V>.ext beside `out` (the in-memory path names them alike).
std::string surface_output_path(const std::string& out, double value, bool label, std::size_t surfaces);

struct StreamMeshRequest {
    std::string input, output; // output: .pvtp, .ply or .stl
    std::vector<double> isos;
    bool labels = false;
    std::vector<double> label_values;
    ExtractOptions extract;
    std::size_t memory_budget = 0; // 0: default_memory_budget()
    bool overlap = true;           // StreamOptions::overlap
    ProgressFn progress;
};

struct StreamMeshResult {
    std::vector<std::string> names, paths; // per surface: "iso 500" / "label 3", file written
    std::vector<MeshStats> stats;
    std::vector<SurfaceSummary>
        summaries; // per surface: connected components and the largest (renderer/surface/components.hpp)
    StreamStats stream;
    std::size_t memory_budget = 0;
    std::vector<std::string> warnings; // of the volume's header
    std::size_t reader_peak_bytes = 0; // OpenVDB read slab by slab: the reading child's peak resident memory
};

// Streams the extraction to the output file(s). Throws iso::Error (or Cancelled);
// no output is then moved into place.
StreamMeshResult stream_mesh(const StreamMeshRequest& req);

} // namespace iso::core
