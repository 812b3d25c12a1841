// Out-of-core isosurface extraction (docs/isosurface.md, "Out of core").
//
// The volume is read in slabs of whole chunk layers (plus the one-sample
// gradient halo), each slab's chunks are extracted with the in-memory
// extractor working on a window (extract.hpp, VolumeWindow), welded into one
// piece, and handed to a MeshSink (io/mesh_sink.hpp) with the keys of its
// seam vertices. At most `memory_budget` bytes of samples, scratch and output
// are held (the engine's own accounting: StreamStats::peak_bytes).
//
// With StreamOptions::overlap (the default) the three steps run as a pipeline
// of three threads: a reader reads slab i+1 while slab i is extracted and a
// writer welds and hands slab i-1's pieces to the sink; the planner then
// counts two slabs of samples and two slabs of output in flight. The sink
// gets the same pieces in the same order as without overlap (for the same
// plan); its calls all come from one thread at a time (begin() and finish()
// from the caller's, piece() from the writer's).
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

#include "io/mesh_sink.hpp"
#include "io/volume_stream.hpp"
#include "renderer/surface/extract.hpp"

namespace iso {

struct StreamOptions {
    std::vector<double> isos;         // one surface each ...
    bool labels = false;              // ... or label surfaces:
    std::vector<double> label_values; //   these labels (empty: every non-zero value, found in the index pass)
    ExtractOptions extract; // chunk size (shrunk to fit), normals, threads; its memory_budget is set from below
    std::size_t memory_budget = std::size_t(256) << 20;
    // The chunks to extract, [first_chunk, last_chunk) in global ids (MPI
    // ranks pass their own range); the default is the whole volume.
    std::size_t first_chunk = 0, last_chunk = std::numeric_limits<std::size_t>::max();
    // The whole volume's index, when the caller has it (MPI: gathered across
    // ranks); else it is made by a pass over the file (floating-point data,
    // label discovery) or slab by slab while extracting (integer data).
    std::shared_ptr<const ChunkIndex> index;
    ProgressFn progress;
    // Read the next slab and weld/write the last one while a slab is
    // extracted (see above). Off: the steps run one after another, with
    // slabs up to twice as high for the same budget.
    bool overlap = true;
    // At most this many chunk layers per slab (0: as many as the budget
    // allows): more, smaller pieces; tests use it to give both modes one plan.
    int max_layers_per_slab = 0;
};

struct StreamPlan {
    int chunk_size = 0;
    int layers_per_slab = 0;              // chunk layers per slab
    std::size_t slabs = 0;                // pieces per surface
    int first_layer = 0, last_layer = -1; // chunk layers of [first_chunk, last_chunk)
    std::size_t slab_bytes = 0;           // samples of one slab, halo included
    std::size_t fixed_bytes = 0;          // index, scratch, per-chunk tables
    std::size_t output_estimate = 0;      // per slab
    // False when even one chunk layer's estimated output does not fit: the
    // slabs are then one layer each and the output may exceed the budget
    // (StreamStats::warnings says so).
    bool fits = true;
    // Reading, extraction and writing overlap (StreamOptions::overlap, and
    // two slabs and two slabs' output fit the budget with one chunk layer per slab).
    bool overlap = false;
};

struct StreamStats {
    StreamPlan plan;
    bool index_pass = false;
    std::size_t slabs_read = 0, slabs_skipped = 0, chunks_visited = 0;
    // The engine's own accounting of what it held at once: slab samples,
    // extraction scratch and chunk meshes, the welded piece, the index and
    // the sink's seam maps. Peak resident memory adds the program itself
    // (code, libraries, allocator slack): docs/isosurface.md states the constant.
    std::size_t peak_bytes = 0;
    // Seconds each step was busy (read_seconds includes index_seconds, the
    // index pass; extract_seconds excludes weld_seconds, the welding of the
    // pieces; write_seconds excludes analysis_seconds, the sink's summaries
    // of the pieces: MeshSink::analysis_seconds). With overlap the steps run
    // at once and add up to more than the wall time; wait_seconds is how long
    // the extraction waited for the reader or the writer.
    double read_seconds = 0, extract_seconds = 0, write_seconds = 0;
    double index_seconds = 0, weld_seconds = 0, wait_seconds = 0, analysis_seconds = 0;
    std::size_t source_restarts = 0; // gzip streams rewound (VolumeStream::restarts())
    std::vector<double> values;      // the iso values or labels, one per surface
    std::vector<std::string> warnings;
};

// Plans the slabs for a budget (the chunk size halves until one chunk layer
// fits, down to 4; below that iso::Error names the memory budget and the size
// needed; a chunk size below 2 is an iso::Error of the chunk size).
StreamPlan plan_stream(const VolumeHeader& h, const StreamOptions& opt, const ChunkIndex* index = nullptr);

// Builds the whole volume's chunk index in one sequential pass (slabs as
// large as the budget allows). `labels_out` (optional): the distinct
// non-zero values seen (at most 4096, else iso::Error: not a label map).
std::shared_ptr<const ChunkIndex> build_chunk_index(VolumeStream& src, int chunk_size, std::size_t memory_budget,
                                                    const ProgressFn& progress = {},
                                                    std::vector<double>* labels_out = nullptr);

// Streams the extraction into `sink` (begin, pieces, finish). Throws
// iso::Error (bad input, budget too small) or iso::Cancelled; the sink's
// outputs are then never moved into place.
StreamStats stream_extract(VolumeStream& src, const StreamOptions& opt, MeshSink& sink);

// Reader and writer threads of stream_extract() running in this process now
// (0 whenever no stream_extract() is running: every way out joins them; the
// tests check it after errors and cancels).
std::size_t stream_threads_running();

} // namespace iso
