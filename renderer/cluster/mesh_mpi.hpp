// `mpirun -np N isoscope mesh IN --iso V -o OUT.pvtp` (docs/cluster.md): every
// rank reads and extracts its own contiguous range of chunk ids, writes its
// piece of a partitioned .pvtp through VTK's parallel XML writer, and the
// statistics (triangles, welded vertices, area, signed volume, connected
// components) are reduced on rank 0. Collective: every rank of the job calls
// it with the same request.
#pragma once

#include <string>
#include <vector>

#include "io/progress.hpp"
#include "renderer/cluster/mpi.hpp"
#include "renderer/surface/components.hpp"
#include "renderer/surface/extract.hpp"

namespace iso::cluster {

struct DistMeshRequest {
    std::string input, output; // output: a .pvtp (several surfaces: core::surface_output_path)
    std::string series;        // DICOM series (every rank loads the same)
    std::vector<double> isos;  // iso values, or with `labels` the labels (empty: every label)
    bool labels = false;
    ExtractOptions extract; // chunk size, threads, normals
    // Per rank: samples read at once, extraction scratch and the slab's
    // output (the streaming driver's budget); the rank's whole output comes on top.
    std::size_t memory_budget = std::size_t(1) << 30;
    bool overlap = true; // StreamOptions::overlap (each rank's reading, extraction and writing)
    ProgressFn progress; // rank 0's progress (other ranks: none)
};

struct DistSurface {
    std::string name; // "iso 500", "label 3"
    double value = 0;
    std::string path;                        // the .pvtp written
    std::size_t pieces = 0;                  // .vtp files it lists (non-empty slab pieces of every rank)
    SurfaceSummary summary;                  // reduced over every piece (valid on rank 0)
    std::vector<std::size_t> rank_triangles; // per piece (rank 0)
};

struct DistMeshResult {
    int ranks = 1;
    std::vector<ChunkRange> plan;             // each rank's chunk ids
    std::vector<std::size_t> rank_active;     // active chunks per rank
    std::vector<std::size_t> rank_slabs;      // slabs each rank read for extraction (the streaming driver's count)
    std::vector<std::size_t> rank_peak_bytes; // the streaming engine's own peak accounting per rank
    std::vector<DistSurface> surfaces;
    std::vector<std::string> warnings; // the volume's (rank 0)
};

// Throws iso::Error on every rank when any rank fails (Comm::agree).
DistMeshResult mesh_distributed(const Comm& comm, const DistMeshRequest& req);

// The default per-rank budget: a quarter of this node's physical memory
// shared by the ranks on this node (OMPI_COMM_WORLD_LOCAL_SIZE), at least 64 MiB.
std::size_t default_rank_budget();

} // namespace iso::cluster
