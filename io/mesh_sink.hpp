// Writing a surface piece by piece, as out-of-core extraction makes it
// (renderer/surface/stream.hpp; docs/isosurface.md, "Out of core").
//
// A piece is one slab's share of one surface, welded: its vertices, its
// triangles, and the global keys of its vertices that other pieces may hold
// too (on its boundary with the chunks before and after it). Nothing is
// written where the user's output goes until finish(): a sink destroyed
// before finish() (an error, a cancel) removes its temporaries and leaves
// the output path as it was.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "io/mesh.hpp"

namespace iso {

struct MeshPiece {
    std::size_t surface = 0; // which surface (index of its iso value or label)
    std::size_t index = 0;   // piece number, increasing with k
    Mesh mesh;
    // (global key, vertex) for vertices shared with pieces before (lower) and
    // after (upper) this one: only these are kept to weld across seams.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> lower, upper;
    std::size_t memory_bytes() const;
};

class MeshSink {
public:
    virtual ~MeshSink() = default;
    // Called once before the first piece: how many pieces each surface gets,
    // and whether vertices carry normals.
    virtual void begin(std::size_t surfaces, std::size_t pieces_per_surface, bool normals) {}
    // Pieces of one surface come in increasing index; surfaces may interleave.
    virtual void piece(MeshPiece&& p) = 0;
    // Writes what is left and moves the output(s) into place.
    virtual void finish() = 0;
    // Bytes the sink holds (the seam's key map, a buffered piece).
    virtual std::size_t memory_bytes() const { return 0; }
    // Statistics of what was written, per surface (vertices after welding).
    virtual std::vector<MeshStats> stats() const = 0;
    // Of the time piece() took so far, the seconds spent analysing the pieces
    // rather than writing them (a summarizing sink's components and volumes):
    // the streaming driver reports them as their own step.
    virtual double analysis_seconds() const { return 0; }
};

// `paths[s]` is surface s's output: .pvtp (one .vtp per piece, written with
// VTK's vtkXMLPPolyDataWriter beside it as NAME_<i>.vtp), or .ply / .stl /
// .vtp assembled into one file on disk (vertices welded across seams by key,
// triangles spilled to a temporary file next to the output and appended;
// binary, LPS-tagged as save_mesh() tags them). .obj: iso::Error.
std::unique_ptr<MeshSink> make_mesh_sink(const std::vector<std::string>& paths);
// Can make_mesh_sink() write this path? (".pvtp", ".ply", ".stl", ".vtp")
bool is_streamable_mesh_path(const std::string& path);

// Writes one piece of a .pvtp as a .vtp (appended, LZ4) straight from the
// mesh's buffers (no copy into VTK's cell arrays), with the arrays every
// piece declares (an empty "Normals" when `normals` and the piece is empty)
// and SPACE=LPS. Throws iso::Error naming `file` and `what`.
void write_vtp_piece(const Mesh& m, bool normals, const std::string& file, const std::string& what);
// Writes the .pvtp summary of `pieces` pieces named <stem>_<i>.vtp (in a
// <stem>/ folder beside it with `subdirectory`) into the folder `scratch`
// (created; VTK writes stand-in pieces there too) and returns its path, to be
// renamed into place by the caller. Errors name `what`.
std::string write_pvtp_summary(const std::filesystem::path& scratch, const std::string& stem, std::size_t pieces,
                               bool normals, bool subdirectory, const std::string& what);

} // namespace iso
