// Binary PLY and STL written by hand (mesh_writers.cpp, docs/isosurface.md
// "Writing"): the records formatted in parallel (TBB) into blocks of a few
// MiB, each block written with one write(2) while the next is formatted.
// save_mesh() writes .ply and .stl through write_ply()/write_stl(), byte for
// byte what VTK 9.1's vtkPLYWriter and vtkSTLWriter wrote for the same mesh
// (tests/unit/mesh_writers_test.cpp compares them); the streamed sink
// (mesh_sink.cpp) formats its pieces with the same record functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"

namespace iso::detail {

inline constexpr std::size_t kStlHeaderBytes = 84; // 80 bytes of text, then the uint32 facet count
inline constexpr std::size_t kStlFacetBytes = 50;  // normal, three corners (float32), uint16 attribute 0
inline constexpr std::size_t kPlyFaceBytes = 13;   // uchar 3, three int32 vertex indices

// The STL header save_mesh() and the streamed sink write: "SPACE=LPS isoscope
// mesh, millimetres" padded with zero bytes to 80, then `facets` (LE).
void stl_header(unsigned char out[kStlHeaderBytes], std::uint32_t facets);
// One binary STL facet of the triangle (a, b, c): its normal as vtkSTLWriter
// takes it from vtkTriangle::ComputeNormal ((c - b) x (a - b) in double,
// divided by its length unless that is 0, then rounded to float), the
// corners, attribute 0.
void stl_facet(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, unsigned char* out);
// One binary PLY face: the count 3 (uchar), then the three indices (int32 LE).
void ply_face(std::uint32_t a, std::uint32_t b, std::uint32_t c, unsigned char* out);

// The header vtkPLYWriter wrote for save_mesh(): binary little endian, VTK's
// comment, isoscope's two (SPACE=LPS), VTK's obj_info, float x y z (and
// uchar red green blue alpha with `rgba`), faces as uchar/int lists.
std::string ply_header(std::uint64_t vertices, std::uint64_t faces, bool rgba);

// An output file written with write(2)/pwrite(2); errors name `name` (the
// user's path) and the system's reason. Closed (not removed) on destruction.
class OutFile {
public:
    OutFile() = default;
    OutFile(const OutFile&) = delete;
    OutFile& operator=(const OutFile&) = delete;
    ~OutFile();
    // Creates (or truncates) `path` for reading and writing.
    void open(const std::string& path, const std::string& name);
    void write(const void* p, std::size_t n);
    void write_at(std::uint64_t at, const void* p, std::size_t n);
    // Appends the whole of `src` (written through its own OutFile): in the
    // kernel with copy_file_range(2) where the file system allows it, else
    // through a buffer.
    void append_copy_of(OutFile& src);
    // Closes, reporting a failed close (a delayed write error) as an error.
    void close();
    bool is_open() const { return fd_ >= 0; }
    const std::string& path() const { return path_; }
    std::uint64_t size() const { return size_; }

private:
    [[noreturn]] void fail(const std::string& what) const;
    int fd_ = -1;
    std::string path_, name_;
    std::uint64_t size_ = 0;
};

// Formats records [begin, end) into `out` (record `begin` first).
using RecordFormatter = std::function<void(std::size_t begin, std::size_t end, unsigned char* out)>;

// Writes `n` records of `bytes` bytes each, formatted by `fmt` in parallel
// into blocks of about `block_bytes`: block i + 1 is formatted (on TBB's
// threads) while block i is written with one write(2). The two block buffers
// are kept between calls (the streamed sink writes each piece through one).
class BlockWriter {
public:
    explicit BlockWriter(std::size_t block_bytes = std::size_t(4) << 20) : block_bytes_(block_bytes) {}
    void write(OutFile& f, std::size_t n, std::size_t bytes, const RecordFormatter& fmt);
    std::size_t memory_bytes() const { return buffers_[0].capacity() + buffers_[1].capacity(); }

private:
    std::size_t block_bytes_;
    std::vector<unsigned char> buffers_[2];
};

// Formats `n` records of `bytes` bytes into `out` (n * bytes of it) in parallel.
void format_records(std::size_t n, std::size_t bytes, unsigned char* out, const RecordFormatter& fmt);

// save_mesh()'s .ply and .stl (indices already checked): write `file`,
// errors naming `name`.
void write_ply(const Mesh& m, const std::string& file, const std::string& name);
void write_stl(const Mesh& m, const std::string& file, const std::string& name);

} // namespace iso::detail
