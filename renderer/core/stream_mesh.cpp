#include "renderer/core/stream_mesh.hpp"

#include <algorithm>

#include <glm/glm.hpp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "io/atomic_file.hpp"
#include "io/mesh_sink.hpp"
#include "io/process.hpp"
#include "io/volume_io.hpp"
#include "io/volume_stream.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/surface_name.hpp"

namespace iso::core {

std::size_t default_memory_budget() {
    const std::size_t phys = physical_memory_bytes();
    return phys ? phys / 4 : std::size_t(1) << 30;
}

std::size_t peak_resident_bytes() { return process_status_bytes("VmHWM:"); }

bool exceeds_budget(const std::string& path, std::size_t budget) {
    const VolumeFormat f = volume_format_of(path);
    if (f == VolumeFormat::Vdb) return 2 * read_vdb_header(path).grid_bytes > budget;
    if (f != VolumeFormat::Nifti && f != VolumeFormat::Nrrd && f != VolumeFormat::MetaImage) return false;
    return read_volume_header(path).memory_bytes() > budget;
}

nlohmann::json describe_header(const std::string& path) {
    const bool vdb = volume_format_of(path) == VolumeFormat::Vdb;
    VdbHeader vh;
    if (vdb) vh = read_vdb_header(path);
    const VolumeHeader h = vdb ? vh.header : read_volume_header(path);
    // describe() of a volume without samples: the geometry and metadata the
    // same way, then what the samples would have told replaced.
    Volume v;
    v.dims = h.dims;
    v.type = h.type;
    v.index_to_lps = h.index_to_lps;
    v.meta = h.meta;
    nlohmann::json j = describe(v);
    j["range"] = nullptr;
    j["range_read"] = false;
    j.erase("nan_count");
    j.erase("inf_count");
    j["memory_bytes"] = vdb ? vh.grid_bytes : h.memory_bytes();
    if (vdb) {
        // Sparse: what the grid takes loaded whole, and its tree without leaf values.
        j["grid"] = vh.grid;
        j["topology_bytes"] = vh.topology_bytes;
    }
    j["data_file"] = h.data_file;
    j["encoding"] = h.encoding == DataEncoding::Raw ? "raw" : h.encoding == DataEncoding::Gzip ? "gzip" : "other";
    return j;
}

std::string surface_output_path(const std::string& out, double value, bool label, std::size_t surfaces) {
    if (surfaces <= 1) return out;
    namespace fs = std::filesystem;
    const fs::path p(out);
    return (p.parent_path() / (p.stem().string() + surface_file_suffix(label, value) + p.extension().string()))
        .string();
}

namespace {
// Streams into the output sink through a SummarizingSink, so that the result
// also carries the components (as the MPI path reports them). Volumes are
// summarized about the volume's centre and merged about the surface's bounds
// centre, as mesh_stats() takes them.
StreamStats extract_summarized(VolumeStream& src, const StreamOptions& so, StreamMeshResult& r) {
    auto sink = make_mesh_sink(r.paths);
    const VolumeHeader& h = src.header();
    const glm::dvec3 centre(h.index_to_lps *
                            glm::dvec4(0.5 * glm::dvec3(h.dims[0] - 1, h.dims[1] - 1, h.dims[2] - 1), 1.0));
    SummarizingSink summing(*sink, centre);
    StreamStats st = stream_extract(src, so, summing);
    r.stats = sink->stats();
    r.summaries = summing.summaries();
    return st;
}
} // namespace

StreamMeshResult stream_mesh(const StreamMeshRequest& req) {
    StreamMeshResult r;
    r.memory_budget = req.memory_budget ? req.memory_budget : default_memory_budget();
    if (!is_streamable_mesh_path(req.output))
        throw Error(req.output, "streamed output must be .pvtp (pieces), .ply or .stl (a single .vtp or .obj needs the "
                                "whole mesh in memory)");
    check_writable_destination(req.output); // before the long part
    // A format that cannot stream is loaded whole if it takes at most half the budget.
    auto src = open_volume_stream(req.input, r.memory_budget / 2);
    r.warnings = src->header().meta.warnings;
    StreamOptions so;
    so.isos = req.isos;
    so.labels = req.labels;
    so.label_values = req.label_values;
    so.extract = req.extract;
    so.memory_budget = r.memory_budget;
    so.overlap = req.overlap;
    so.progress = req.progress;
    if (!req.labels) {
        for (std::size_t i = 0; i < req.isos.size(); ++i) {
            r.names.push_back(surface_name(false, req.isos[i]));
            r.paths.push_back(surface_output_path(req.output, req.isos[i], false, req.isos.size()));
        }
        r.stream = extract_summarized(*src, so, r);
        r.reader_peak_bytes = src->reader_peak_bytes();
        return r;
    }
    // Labels: the label list is known after the index pass when not given.
    if (so.label_values.empty()) {
        const StreamPlan pre = plan_stream(src->header(), so, nullptr);
        std::vector<double> found;
        so.index = build_chunk_index(*src, pre.chunk_size, r.memory_budget, {}, &found);
        so.label_values = found;
    }
    std::sort(so.label_values.begin(), so.label_values.end());
    so.label_values.erase(std::unique(so.label_values.begin(), so.label_values.end()), so.label_values.end());
    for (double v : so.label_values) {
        r.names.push_back(surface_name(true, v));
        r.paths.push_back(surface_output_path(req.output, v, true, so.label_values.size()));
    }
    if (r.paths.empty()) throw Error(req.input, "has no non-zero label");
    r.stream = extract_summarized(*src, so, r);
    r.reader_peak_bytes = src->reader_peak_bytes();
    return r;
}

} // namespace iso::core
