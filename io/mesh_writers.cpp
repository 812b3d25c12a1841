// Binary PLY and STL written by hand (mesh_writers.hpp).
//
// VTK's writers format one record at a time through stdio (vtkSTLWriter: five
// fwrite calls per 50-byte facet; vtkPLYWriter: a call per property) on one
// thread, after to_polydata() has copied the whole mesh into VTK's arrays:
// on the 1024^3 phantom's 32.5 million triangles that was most of `isoscope
// mesh`'s time (issue 39). Here the mesh's own arrays are formatted straight
// into blocks, in parallel, and each block is written with one write(2)
// while the next is formatted. The bytes are VTK 9.1's: the headers as its
// writers put them together for save_mesh(), little-endian records (the
// formats' and this x86-64/aarch64 host's order), the STL facet normal
// computed as vtkTriangle::ComputeNormal computes it.
#include "io/mesh_writers.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "io/error.hpp"

namespace iso::detail {

static_assert(sizeof(float) == 4 && sizeof(glm::vec3) == 12, "float32 records");

void stl_header(unsigned char out[kStlHeaderBytes], std::uint32_t facets) {
    static constexpr char kText[] = "SPACE=LPS isoscope mesh, millimetres";
    std::memset(out, 0, 80);
    std::memcpy(out, kText, sizeof kText - 1);
    std::memcpy(out + 80, &facets, 4);
}

void stl_facet(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, unsigned char* out) {
    // vtkTriangle::ComputeNormal(v1, v2, v3) with v1 = a, v2 = b, v3 = c, in
    // its order of operations (written out, not through glm, so that nothing
    // reorders them).
    const double ax = double(c.x) - double(b.x), ay = double(c.y) - double(b.y), az = double(c.z) - double(b.z);
    const double bx = double(a.x) - double(b.x), by = double(a.y) - double(b.y), bz = double(a.z) - double(b.z);
    double n[3] = {ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx};
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length != 0.0) {
        n[0] /= length;
        n[1] /= length;
        n[2] /= length;
    }
    const float f[12] = {float(n[0]), float(n[1]), float(n[2]), a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
    std::memcpy(out, f, 48);
    out[48] = out[49] = 0;
}

void ply_face(std::uint32_t a, std::uint32_t b, std::uint32_t c, unsigned char* out) {
    const std::int32_t ids[3] = {std::int32_t(a), std::int32_t(b), std::int32_t(c)};
    out[0] = 3;
    std::memcpy(out + 1, ids, 12);
}

std::string ply_header(std::uint64_t vertices, std::uint64_t faces, bool rgba) {
    // vtkPLY's ply_header_complete: the format, the comments in the order
    // added (VTK's own first), the obj_info, then each element.
    std::string h = "ply\nformat binary_little_endian 1.0\n"
                    "comment VTK generated PLY File\n"
                    "comment SPACE=LPS\n"
                    "comment written by isoscope; coordinates in millimetres\n"
                    "obj_info vtkPolyData points and polygons: vtk4.0\n";
    h += "element vertex " + std::to_string(vertices) + "\nproperty float x\nproperty float y\nproperty float z\n";
    if (rgba) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
    h += "element face " + std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
    return h;
}

// ---- OutFile -------------------------------------------------------------------------

OutFile::~OutFile() {
    if (fd_ >= 0) ::close(fd_);
}

void OutFile::fail(const std::string& what) const {
    const int e = errno;
    throw Error(name_, what + ": " + std::strerror(e) + (e == ENOSPC || e == EDQUOT ? " (disk full?)" : ""));
}

void OutFile::open(const std::string& path, const std::string& name) {
    if (fd_ >= 0) ::close(fd_);
    path_ = path;
    name_ = name;
    size_ = 0;
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd_ < 0) fail("cannot create '" + path + "'");
}

void OutFile::write(const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    while (n > 0) {
        const ssize_t k = ::write(fd_, c, std::min<std::size_t>(n, std::size_t(1) << 30));
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) fail("cannot write");
        c += k;
        n -= std::size_t(k);
        size_ += std::uint64_t(k);
    }
}

void OutFile::write_at(std::uint64_t at, const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    for (std::size_t done = 0; done < n;) {
        const ssize_t k = ::pwrite(fd_, c + done, n - done, off_t(at + done));
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) fail("cannot write");
        done += std::size_t(k);
    }
    size_ = std::max<std::uint64_t>(size_, at + n);
}

void OutFile::append_copy_of(OutFile& src) {
    loff_t in = 0;
    const loff_t end = loff_t(src.size());
    // In the kernel: no round trip of the bytes through this process (a
    // reflink where the file system shares blocks).
    while (in < end) {
        const ssize_t k = ::copy_file_range(src.fd_, &in, fd_, nullptr, std::size_t(end - in), 0);
        if (k < 0 && errno == EINTR) continue;
        if (k < 0 && (errno == EXDEV || errno == ENOSYS || errno == EINVAL || errno == EOPNOTSUPP) && in == 0) break;
        if (k <= 0) fail("cannot copy '" + src.path() + "' into '" + path_ + "'");
        size_ += std::uint64_t(k);
    }
    if (in == end) return;
    std::vector<char> buf(std::size_t(4) << 20);
    while (in < end) {
        const ssize_t k = ::pread(src.fd_, buf.data(), std::min<std::size_t>(buf.size(), std::size_t(end - in)), in);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) src.fail("cannot read back '" + src.path() + "'");
        write(buf.data(), std::size_t(k));
        in += k;
    }
}

void OutFile::close() {
    if (fd_ < 0) return;
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("cannot write (on closing)");
}

// ---- formatting in parallel, writing in blocks -------------------------------------------

void format_records(std::size_t n, std::size_t bytes, unsigned char* out, const RecordFormatter& fmt) {
    // Grains of at least 64 KiB of output: large enough that a task's
    // overhead does not show, small enough to spread over the threads.
    const std::size_t grain = std::max<std::size_t>(1, (std::size_t(64) << 10) / bytes);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
        fmt(r.begin(), r.end(), out + r.begin() * bytes);
    });
}

void BlockWriter::write(OutFile& f, std::size_t n, std::size_t bytes, const RecordFormatter& fmt) {
    if (n == 0) return;
    const std::size_t per_block = std::max<std::size_t>(1, block_bytes_ / bytes);
    const std::size_t blocks = (n + per_block - 1) / per_block;
    const auto format_block = [&](std::size_t i) {
        const std::size_t b = i * per_block, e = std::min(n, b + per_block);
        auto& buf = buffers_[i % 2];
        buf.resize((e - b) * bytes);
        format_records(e - b, bytes, buf.data(),
                       [&](std::size_t rb, std::size_t re, unsigned char* out) { fmt(b + rb, b + re, out); });
    };
    format_block(0);
    tbb::task_group next;
    for (std::size_t i = 0; i < blocks; ++i) {
        if (i + 1 < blocks) next.run([&, i] { format_block(i + 1); });
        try {
            f.write(buffers_[i % 2].data(), buffers_[i % 2].size());
        } catch (...) {
            next.wait();
            throw;
        }
        next.wait();
    }
}

// ---- save_mesh()'s .ply and .stl ------------------------------------------------------------

void write_ply(const Mesh& m, const std::string& file, const std::string& name) {
    // As to_polydata() + vtkPLYWriter: colours only when every vertex has
    // one; normals are not written (vtkPLYWriter leaves them out).
    const bool rgba = !m.colors.empty() && m.colors.size() == m.positions.size();
    const std::size_t vbytes = rgba ? 16 : 12;
    OutFile f;
    f.open(file, name);
    const std::string h = ply_header(m.positions.size(), m.triangles.size(), rgba);
    f.write(h.data(), h.size());
    BlockWriter w;
    w.write(f, m.positions.size(), vbytes, [&](std::size_t b, std::size_t e, unsigned char* out) {
        for (std::size_t i = b; i < e; ++i, out += vbytes) {
            std::memcpy(out, &m.positions[i], 12);
            if (rgba) std::memcpy(out + 12, &m.colors[i], 4);
        }
    });
    w.write(f, m.triangles.size(), kPlyFaceBytes, [&](std::size_t b, std::size_t e, unsigned char* out) {
        for (std::size_t i = b; i < e; ++i, out += kPlyFaceBytes)
            ply_face(m.triangles[i][0], m.triangles[i][1], m.triangles[i][2], out);
    });
    f.close();
}

void write_stl(const Mesh& m, const std::string& file, const std::string& name) {
    if (m.triangles.size() > 0xFFFFFFFFull) throw Error(name, "more than 4 billion triangles do not fit an STL file");
    OutFile f;
    f.open(file, name);
    unsigned char header[kStlHeaderBytes];
    stl_header(header, std::uint32_t(m.triangles.size()));
    f.write(header, sizeof header);
    BlockWriter w;
    w.write(f, m.triangles.size(), kStlFacetBytes, [&](std::size_t b, std::size_t e, unsigned char* out) {
        const auto& P = m.positions;
        for (std::size_t i = b; i < e; ++i, out += kStlFacetBytes) {
            const auto& t = m.triangles[i];
            stl_facet(P[t[0]], P[t[1]], P[t[2]], out);
        }
    });
    f.close();
}

} // namespace iso::detail
