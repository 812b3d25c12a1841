// Statistics of a surface that exists only as pieces (docs/cluster.md,
// "Statistics"): each MPI rank, or each slab of the single-process streaming
// path, holds one welded piece of the surface made of a contiguous range of
// chunk ids; no process ever holds the whole mesh. A piece is summarized on
// its own (triangles, vertices, area, signed volume, and its connected
// components with their size) together with the global keys of its vertices
// that other pieces can also hold (its seam). Merging the summaries gives the
// whole surface's statistics: vertices shared by several pieces are counted
// once, components that meet on a seam are joined.
//
// Written here (no Debian package merges connected components across
// partitions of a mesh: VTK's vtkPConnectivityFilter needs the unstructured
// pieces and an MPI controller, and moves cells between ranks; we only need the
// counts, from a few bytes per seam vertex).
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/mesh_sink.hpp"
#include "renderer/surface/extract.hpp"

namespace iso {

// A contiguous range of global chunk ids, [first, last).
struct ChunkRange {
    std::size_t first = 0, last = 0;
    bool empty() const { return last <= first; }
    bool operator==(const ChunkRange&) const = default;
};

// One welded piece of a surface: the mesh, and for each of its vertices that
// may also belong to another piece, (global key, index into mesh.positions),
// sorted by key. Keys are those of ChunkMesh::border.
struct SurfacePiece {
    Mesh mesh;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> seam;
};

// Welds the chunks [range.first, range.last) of `s` into one piece (as
// weld() does for the whole surface: duplicates by key merged, the first
// kept; zero normals replaced by the piece's area-weighted face normal) and
// lists the vertices lying on a chunk face shared with a chunk outside the
// range. `dims` and `chunk_size` are the whole volume's (ChunkIndex).
SurfacePiece weld_piece(const ChunkedSurface& s, ChunkRange range, const std::array<std::int64_t, 3>& dims,
                        int chunk_size);

// Does the vertex of global key `key` belong to a chunk outside `range`?
// (The chunks of a sample are those whose inclusive sample box holds it; a
// vertex on an edge belongs to the chunks holding the whole edge.)
bool key_leaves_range(std::uint64_t key, ChunkRange range, const std::array<std::int64_t, 3>& dims, int chunk_size);

struct ComponentStats {
    std::size_t triangles = 0;
    double area = 0;   // mm^2
    double volume = 0; // signed, mm^3, about the piece's origin (merged: about the whole's, as mesh_stats)
    // Sum over the triangles (a, b, c) of a x b + b x c + c x a, about the
    // piece's origin (twice the vector area): the signed volume about
    // another origin o' is volume - (o' - origin) . moment / 6, so pieces
    // summarized before the whole surface's bounds are known still add up.
    glm::dvec3 moment{0.0};
};

// A piece's summary: a few numbers per component, 12 bytes per seam vertex.
struct PieceSummary {
    std::size_t triangles = 0, vertices = 0;
    double area = 0, volume = 0;
    glm::dvec3 origin{0.0};                                 // of `volume` and the components' volumes
    glm::dvec3 bounds_min{INFINITY}, bounds_max{-INFINITY}; // of the piece's vertices
    std::vector<ComponentStats> components;
    // (global key, component index) of every seam vertex, sorted by key.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> seam;
    // Edges used by one triangle of the piece: those with a vertex off the
    // seam are counted (no other piece has them); those between two seam
    // vertices are listed as (smaller key, larger key), sorted, since another
    // piece may hold the other side of the edge.
    std::size_t boundary_edges = 0;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> seam_boundary;
};

// The bounds of a piece's vertices (inverted, min > max, when it has none).
std::pair<glm::dvec3, glm::dvec3> piece_bounds(const Mesh& m);
// The origin mesh_stats() uses for the signed volume: the centre of the
// whole surface's bounds. Every piece must use the same one for the volumes
// to add up to the whole's.
glm::dvec3 volume_origin(const glm::dvec3& bounds_min, const glm::dvec3& bounds_max);

// Summarizes a piece: components by shared vertices (union-find over the
// triangles), area and signed volume about `origin` in double precision
// (any origin near the data: merge_summaries() moves every volume to the
// centre of the whole's bounds).
PieceSummary summarize_piece(const SurfacePiece& p, const glm::dvec3& origin);

struct SurfaceSummary {
    std::size_t triangles = 0, vertices = 0, components = 0;
    double area = 0, volume = 0;
    ComponentStats largest; // by triangles, then area; of a tie, the first in piece order
    // Edges used by one triangle of the whole surface: 0 for a closed
    // surface (then `volume` is the enclosed volume; otherwise it means
    // nothing on its own).
    std::size_t boundary_edges = 0;
};

// Merges the summaries of all the pieces of one surface: vertices whose key
// occurs in k pieces count once (k - 1 subtracted), components sharing a
// seam key are one; volumes are taken about the centre of the merged bounds
// (volume_origin), as mesh_stats() takes the whole mesh's.
SurfaceSummary merge_summaries(std::span<const PieceSummary> pieces);

// The summary of a whole mesh (one piece, no seam): what merge_summaries()
// must equal.
SurfaceSummary summarize_mesh(const Mesh& m);

// The single-process streaming path's statistics: summarizes every piece
// (its seam: the driver's lower and upper key lists) about `origin` before
// passing it on to `next`, and merges the summaries of each surface when asked.
class SummarizingSink final : public MeshSink {
public:
    SummarizingSink(MeshSink& next, const glm::dvec3& origin) : next_(next), origin_(origin) {}
    void begin(std::size_t surfaces, std::size_t pieces, bool normals) override;
    void piece(MeshPiece&& p) override;
    void finish() override { next_.finish(); }
    std::size_t memory_bytes() const override;
    std::vector<MeshStats> stats() const override { return next_.stats(); }
    // The summaries' seconds (summarize_piece), and the next sink's own.
    double analysis_seconds() const override { return seconds_ + next_.analysis_seconds(); }
    // Per surface: triangles, welded vertices, area, volume, components, the largest.
    std::vector<SurfaceSummary> summaries() const;

private:
    MeshSink& next_;
    glm::dvec3 origin_;
    std::vector<std::vector<PieceSummary>> pieces_;
    double seconds_ = 0;
};

// A byte string for sending a summary between processes, and back.
std::string serialize(const PieceSummary& s);
PieceSummary deserialize_piece_summary(std::string_view bytes);
// Several summaries in one byte string (a rank's pieces, for one gather).
std::string serialize(std::span<const PieceSummary> s);
std::vector<PieceSummary> deserialize_piece_summaries(std::string_view bytes);

} // namespace iso
