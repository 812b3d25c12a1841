// Piece-by-piece surface writers (mesh_sink.hpp).
//
// The assembled .ply and .stl files are written here by hand: VTK's writers
// (vtkPLYWriter, vtkSTLWriter) take a whole vtkPolyData, i.e. the whole mesh
// in memory, which is what out-of-core extraction must avoid, and no Debian
// package writes these formats incrementally. The layouts are the ones
// save_mesh() writes through VTK (binary little-endian PLY with x y z nx ny nz
// and "vertex_indices" as uchar/int lists; binary STL with facet normals as
// vtkTriangle::ComputeNormal gives them), tagged SPACE=LPS the same way.
// The pieces of a .pvtp are written with VTK's vtkXMLPPolyDataWriter.
#include "io/mesh_sink.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <unordered_map>

#include <glm/glm.hpp>
#include <vtkFieldData.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkPoints.h>
#include <vtkTypeInt32Array.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkXMLPPolyDataWriter.h>
#include <vtkXMLPolyDataWriter.h>

#include "io/atomic_file.hpp"
#include "io/vtk_mesh.hpp"
#include "io/vtk_util.hpp"

namespace iso {
namespace fs = std::filesystem;

std::size_t MeshPiece::memory_bytes() const {
    return mesh.positions.capacity() * sizeof(glm::vec3) + mesh.normals.capacity() * sizeof(glm::vec3) +
           mesh.triangles.capacity() * sizeof(mesh.triangles[0]) +
           (lower.capacity() + upper.capacity()) * sizeof(lower[0]);
}

namespace {

std::string lower_ext(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

// Welds one surface's pieces across seams by key and keeps mesh_stats()'s
// figures without the mesh: the signed volume is summed about a provisional
// centre and moved to the final bounds' centre at the end (det(a-c, b-c, d-c)
// is linear in c), so that it equals mesh_stats() of the welded mesh.
struct SurfaceState {
    std::unordered_map<std::uint64_t, std::uint32_t> seam; // previous piece's upper keys -> global id
    std::uint64_t vertices = 0, triangles = 0;
    glm::dvec3 lo{0.0}, hi{0.0};
    bool any = false, have_c0 = false;
    glm::dvec3 c0{0.0};
    double area = 0, det_sum = 0;
    glm::dvec3 w{0.0};
    std::size_t next_piece = 0;

    // Global ids of the piece's vertices (new ones numbered from `vertices`).
    std::vector<std::uint32_t> map(const MeshPiece& p, std::vector<std::uint8_t>& is_new) {
        std::vector<std::uint32_t> id(p.mesh.positions.size(), 0xFFFFFFFFu);
        is_new.assign(id.size(), 1);
        for (const auto& [key, v] : p.lower)
            if (auto it = seam.find(key); it != seam.end()) {
                id[v] = it->second;
                is_new[v] = 0;
            }
        for (std::size_t v = 0; v < id.size(); ++v)
            if (is_new[v]) {
                if (vertices >= 0xFFFFFFFFull) throw Error("streaming", "the surface has more than 4 billion vertices");
                id[v] = std::uint32_t(vertices++);
                const glm::dvec3 q(p.mesh.positions[v]);
                if (!any) {
                    lo = hi = q;
                    any = true;
                }
                lo = glm::min(lo, q);
                hi = glm::max(hi, q);
            }
        std::unordered_map<std::uint64_t, std::uint32_t> next;
        next.reserve(p.upper.size());
        for (const auto& [key, v] : p.upper) next.emplace(key, id[v]);
        seam = std::move(next);
        if (!have_c0 && !p.mesh.positions.empty()) {
            c0 = glm::dvec3(p.mesh.positions[0]);
            have_c0 = true;
        }
        for (const auto& t : p.mesh.triangles) {
            const TriangleTerms tt =
                triangle_terms(c0, p.mesh.positions[t[0]], p.mesh.positions[t[1]], p.mesh.positions[t[2]]);
            area += tt.area;
            det_sum += tt.det;
            w += tt.moment;
        }
        triangles += p.mesh.triangles.size();
        return id;
    }
    MeshStats stats() const {
        MeshStats s;
        s.vertices = vertices;
        s.triangles = triangles;
        s.bounds_min = lo;
        s.bounds_max = hi;
        s.area = area;
        s.volume = volume_moved(det_sum / 6.0, w, c0, 0.5 * (lo + hi));
        return s;
    }
    std::size_t bytes() const {
        return seam.size() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 2 * sizeof(void*));
    }
};

class SinkBase : public MeshSink {
public:
    explicit SinkBase(std::vector<std::string> paths) : paths_(std::move(paths)), states_(paths_.size()) {
        for (const auto& p : paths_) check_writable_destination(p);
    }
    std::vector<MeshStats> stats() const override {
        std::vector<MeshStats> out;
        for (const auto& s : states_) out.push_back(s.stats());
        return out;
    }
    std::size_t memory_bytes() const override {
        std::size_t n = 0;
        for (const auto& s : states_) n += s.bytes();
        return n;
    }

protected:
    SurfaceState& state(const MeshPiece& p) {
        if (p.surface >= states_.size()) throw Error("streaming", "piece of an unknown surface");
        auto& s = states_[p.surface];
        if (p.index < s.next_piece) throw Error("streaming", "pieces out of order");
        s.next_piece = p.index + 1;
        return s;
    }
    std::vector<std::string> paths_;
    std::vector<SurfaceState> states_;
};

// ---- .pvtp: one .vtp per piece through VTK's parallel XML writer -----------

} // namespace

// The piece as VTK sees it, without copying it: the points, the normals and
// the triangles' connectivity are VTK arrays over the mesh's own buffers
// (vtkAOSDataArrayTemplate::SetArray with save = 1: VTK never frees them),
// the cells in 32-bit storage with one offsets array (4 bytes per triangle).
// to_polydata() copies into vtkIdType cells instead: ~44 bytes per vertex
// and triangle more, which for a slab of 8 million triangles was ~350 MiB
// beyond the memory budget (docs/scaling.md). Every piece declares the same
// arrays, an empty one too ("Normals" empty), and the SPACE=LPS field.
// `m` must outlive the returned object's use.
vtkSmartPointer<vtkPolyData> piece_polydata_view(const Mesh& m, bool normals) {
    if (m.positions.size() > std::size_t(std::numeric_limits<std::int32_t>::max()) ||
        m.triangles.size() > std::size_t(std::numeric_limits<std::int32_t>::max() / 3))
        throw Error("streaming", "a piece with 2^31 vertices or more: lower the memory budget");
    auto pd = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkFloatArray> xyz;
    xyz->SetNumberOfComponents(3);
    if (!m.positions.empty())
        xyz->SetArray(const_cast<float*>(&m.positions[0].x), vtkIdType(3 * m.positions.size()), 1);
    vtkNew<vtkPoints> pts;
    pts->SetData(xyz);
    pd->SetPoints(pts);
    vtkNew<vtkTypeInt32Array> conn, offsets;
    if (!m.triangles.empty())
        conn->SetArray(reinterpret_cast<std::int32_t*>(const_cast<std::uint32_t*>(m.triangles[0].data())),
                       vtkIdType(3 * m.triangles.size()), 1);
    offsets->SetNumberOfValues(vtkIdType(m.triangles.size() + 1));
    for (std::size_t i = 0; i <= m.triangles.size(); ++i) offsets->SetValue(vtkIdType(i), std::int32_t(3 * i));
    vtkNew<vtkCellArray> polys;
    polys->SetData(offsets, conn);
    pd->SetPolys(polys);
    if (normals) {
        vtkNew<vtkFloatArray> n;
        n->SetName("Normals");
        n->SetNumberOfComponents(3);
        if (m.normals.size() == m.positions.size() && !m.normals.empty())
            n->SetArray(const_cast<float*>(&m.normals[0].x), vtkIdType(3 * m.normals.size()), 1);
        pd->GetPointData()->SetNormals(n);
    }
    vtkNew<vtkStringArray> space;
    space->SetName("SPACE");
    space->InsertNextValue("LPS");
    pd->GetFieldData()->AddArray(space);
    return pd;
}

void write_vtp_piece(const Mesh& m, bool normals, const std::string& file, const std::string& what) {
    vtkNew<vtkXMLPolyDataWriter> w;
    vtkNew<VtkMessages> msgs;
    msgs->watch(w);
    const auto pd = piece_polydata_view(m, normals);
    w->SetInputData(pd);
    w->SetFileName(file.c_str());
    w->SetDataModeToAppended();
    // LZ4: ~4x faster than zlib here for ~1.3x the bytes; the writing of
    // pieces was the serial part of a streamed extraction. VTK >= 8.1 and
    // ParaView >= 5.5 read it.
    w->SetCompressorTypeToLZ4();
    // Raw appended bytes, not base64 (VTK's default): a third smaller and
    // faster to write and read; what ParaView's own writers do.
    w->EncodeAppendedDataOff();
    if (!w->Write() || msgs->has_error())
        throw Error(file,
                    "cannot write " + what + ": " + (msgs->has_error() ? msgs->first_error() : "VTK writer failed"));
}

std::string write_pvtp_summary(const fs::path& scratch, const std::string& stem, std::size_t pieces, bool normals,
                               bool subdirectory, const std::string& what) {
    // vtkXMLPPolyDataWriter writes the summary (piece list, declared arrays)
    // only together with pieces it makes itself; in one process it lists
    // only those. So it is run on a one-point stand-in with the pieces'
    // arrays in a scratch folder, and only its .pvtp is kept.
    fs::create_directories(scratch);
    Mesh one;
    one.positions = {glm::vec3(0.0f)};
    if (normals) one.normals = {glm::vec3(0.0f, 0.0f, 1.0f)};
    const auto pd = piece_polydata_view(one, normals);
    vtkNew<vtkXMLPPolyDataWriter> w;
    vtkNew<VtkMessages> msgs;
    msgs->watch(w);
    const std::string file = (scratch / (stem + ".pvtp")).string();
    w->SetInputData(pd);
    w->SetFileName(file.c_str());
    w->SetNumberOfPieces(int(pieces));
    w->SetStartPiece(0);
    w->SetEndPiece(int(pieces) - 1);
    w->SetUseSubdirectory(subdirectory);
    w->SetDataModeToAppended();
    w->SetCompressorTypeToLZ4();
    w->EncodeAppendedDataOff();
    if (!w->Write() || msgs->has_error()) throw Error(what, "cannot write the summary: " + msgs->first_error());
    return file;
}

namespace {

// Pieces are written as they come with vtkXMLPolyDataWriter under the names
// vtkXMLPPolyDataWriter gives them (NAME_<i>.vtp beside NAME.pvtp); at the end
// vtkXMLPPolyDataWriter writes the summary. In one process it lists only the
// non-empty pieces its own Write() wrote, so it is run on a one-point
// stand-in with the pieces' arrays in a scratch folder, and only its summary
// is kept. (With an MPI controller each rank's writer writes its own pieces
// and rank 0 the summary: the MPI path uses that directly.)
class PvtpSink final : public SinkBase {
public:
    using SinkBase::SinkBase;
    ~PvtpSink() override {
        std::error_code ec;
        for (const auto& d : dirs_) fs::remove_all(d, ec);
    }
    void begin(std::size_t surfaces, std::size_t pieces, bool normals) override {
        pieces_ = std::max<std::size_t>(pieces, 1);
        normals_ = normals;
        dirs_.clear();
        for (const auto& p : paths_) {
            const fs::path dir = fs::path(temp_path_for(p)).replace_extension("");
            fs::create_directory(dir);
            dirs_.push_back(dir);
        }
        written_.assign(paths_.size(), 0);
    }
    void piece(MeshPiece&& p) override {
        if (dirs_.empty()) throw Error("streaming", "piece before begin");
        auto& st = state(p);
        std::vector<std::uint8_t> is_new;
        st.map(p, is_new);
        write(p.surface, p.index, p.mesh);
    }
    void finish() override {
        for (std::size_t s = 0; s < paths_.size(); ++s) {
            if (pieces_ > 0) write(s, pieces_ - 1, Mesh{}, written_[s] == pieces_); // trailing empty pieces
            const fs::path dest(paths_[s]);
            const std::string stem = dest.stem().string();
            const std::string file =
                write_pvtp_summary(dirs_[s] / "summary", stem, pieces_, normals_, false, paths_[s]);
            // Pieces first, the summary last.
            for (std::size_t i = 0; i < pieces_; ++i) {
                const std::string name = stem + "_" + std::to_string(i) + ".vtp";
                fs::rename(dirs_[s] / name, dest.parent_path() / name);
            }
            fs::rename(file, dest);
            fs::remove_all(dirs_[s]);
        }
        dirs_.clear();
    }

private:
    // Writes piece `index` (and empty pieces for the slabs skipped before it).
    void write(std::size_t s, std::size_t index, const Mesh& m, bool skip_self = false) {
        if (index >= pieces_) throw Error(paths_[s], "more pieces than planned");
        for (std::size_t i = written_[s]; i < index; ++i) write_one(s, i, Mesh{});
        if (!skip_self) write_one(s, index, m);
        written_[s] = std::max(written_[s], index + 1);
    }
    void write_one(std::size_t s, std::size_t index, const Mesh& m) {
        const fs::path dest(paths_[s]);
        const std::string file = (dirs_[s] / (dest.stem().string() + "_" + std::to_string(index) + ".vtp")).string();
        write_vtp_piece(m, normals_, file, "piece " + std::to_string(index) + " of " + paths_[s]);
    }
    std::size_t pieces_ = 1;
    std::vector<fs::path> dirs_;
    std::vector<std::size_t> written_;
    bool normals_ = false;
};

// ---- .ply / .stl assembled on disk -------------------------------------------

class SpillFile {
public:
    SpillFile() = default;
    void open(const std::string& path) {
        path_ = path;
        f_ = std::fopen(path.c_str(), "w+b");
        if (!f_) throw Error(path, std::string("cannot create a temporary file: ") + std::strerror(errno));
        std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
    }
    ~SpillFile() { close(true); }
    void put(const void* p, std::size_t n) {
        if (n && std::fwrite(p, 1, n, f_) != n) throw Error(path_, std::string("write error: ") + std::strerror(errno));
        size_ += n;
    }
    // Appends everything written here to `out`.
    void copy_to(SpillFile& out) {
        if (std::fflush(f_) != 0 || std::fseek(f_, 0, SEEK_SET) != 0)
            throw Error(path_, "cannot re-read the temporary file");
        std::vector<char> buf(1 << 20);
        std::size_t n;
        while ((n = std::fread(buf.data(), 1, buf.size(), f_)) > 0) out.put(buf.data(), n);
        if (std::ferror(f_)) throw Error(path_, "read error in the temporary file");
    }
    void seek_put(long at, const void* p, std::size_t n) {
        if (std::fseek(f_, at, SEEK_SET) != 0 || std::fwrite(p, 1, n, f_) != n) throw Error(path_, "write error");
        std::fseek(f_, 0, SEEK_END);
    }
    void close(bool remove) {
        if (f_) {
            const bool bad = std::fclose(f_) != 0;
            f_ = nullptr;
            if (bad && !remove) throw Error(path_, "write error while closing");
        }
        if (remove && !path_.empty()) {
            std::error_code ec;
            fs::remove(path_, ec);
            path_.clear();
        }
    }
    const std::string& path() const { return path_; }
    std::uint64_t size() const { return size_; }

private:
    std::FILE* f_ = nullptr;
    std::string path_;
    std::uint64_t size_ = 0;
};

class AssembledSink final : public SinkBase {
public:
    explicit AssembledSink(std::vector<std::string> paths) : SinkBase(std::move(paths)), files_(paths_.size()) {
        for (std::size_t s = 0; s < paths_.size(); ++s) {
            files_[s].stl = lower_ext(paths_[s]) == ".stl";
            const std::string tmp = temp_path_for(paths_[s]);
            files_[s].out.open(tmp);
            if (files_[s].stl) {
                char header[80] = {};
                std::snprintf(header, sizeof header, "SPACE=LPS isoscope mesh, millimetres");
                files_[s].out.put(header, 80);
                const std::uint32_t zero = 0;
                files_[s].out.put(&zero, 4);
            } else {
                files_[s].faces.open(tmp + ".faces");
            }
        }
    }
    void piece(MeshPiece&& p) override {
        auto& st = state(p);
        auto& f = files_[p.surface];
        std::vector<std::uint8_t> is_new;
        const auto id = st.map(p, is_new);
        if (!p.mesh.normals.empty()) f.normals = true;
        if (f.stl) {
            // Facets carry their own coordinates: a seam vertex's position is
            // the same in both pieces, so no welding is needed to write them.
            std::vector<float> rec;
            for (const auto& t : p.mesh.triangles) {
                float buf[12];
                const glm::vec3 a = p.mesh.positions[t[0]], b = p.mesh.positions[t[1]], c = p.mesh.positions[t[2]];
                // As vtkTriangle::ComputeNormal: (b - a) x (c - a) in double, normalized.
                glm::dvec3 n = glm::cross(glm::dvec3(c) - glm::dvec3(b), glm::dvec3(a) - glm::dvec3(b));
                const double len = glm::length(n);
                if (len != 0.0) n /= len;
                buf[0] = float(n.x), buf[1] = float(n.y), buf[2] = float(n.z);
                std::memcpy(buf + 3, &a, 12);
                std::memcpy(buf + 6, &b, 12);
                std::memcpy(buf + 9, &c, 12);
                f.out.put(buf, 48);
                const std::uint16_t attr = 0;
                f.out.put(&attr, 2);
            }
            return;
        }
        // PLY: new vertices in global order, faces with global indices (spilled).
        if (f.vertex_bytes == 0) f.vertex_bytes = f.normals ? 24 : 12;
        if ((f.vertex_bytes == 24) != !p.mesh.normals.empty() && !p.mesh.positions.empty())
            throw Error(paths_[p.surface], "pieces with and without normals");
        for (std::size_t v = 0; v < p.mesh.positions.size(); ++v) {
            if (!is_new[v]) continue;
            f.verts_spill().put(&p.mesh.positions[v], 12);
            if (f.vertex_bytes == 24) f.verts_spill().put(&p.mesh.normals[v], 12);
        }
        for (const auto& t : p.mesh.triangles) {
            unsigned char rec[13];
            rec[0] = 3;
            const std::int32_t ids[3] = {std::int32_t(id[t[0]]), std::int32_t(id[t[1]]), std::int32_t(id[t[2]])};
            std::memcpy(rec + 1, ids, 12);
            f.faces.put(rec, 13);
        }
    }
    void finish() override {
        for (std::size_t s = 0; s < paths_.size(); ++s) {
            auto& f = files_[s];
            const auto st = states_[s].stats();
            if (f.stl) {
                if (st.triangles > 0xFFFFFFFFull)
                    throw Error(paths_[s], "more than 4 billion triangles do not fit an STL file");
                const std::uint32_t n = std::uint32_t(st.triangles);
                f.out.seek_put(80, &n, 4);
            } else {
                // Header, then the vertices (written to `out` after the
                // header), then the faces.
                SpillFile final_file;
                final_file.open(f.out.path() + ".ply");
                std::string h = "ply\nformat binary_little_endian 1.0\ncomment SPACE=LPS\n"
                                "comment written by isoscope; coordinates in millimetres\n";
                h += "element vertex " + std::to_string(st.vertices) +
                     "\nproperty float x\nproperty float y\nproperty float z\n";
                if (f.vertex_bytes == 24) h += "property float nx\nproperty float ny\nproperty float nz\n";
                h += "element face " + std::to_string(st.triangles) +
                     "\nproperty list uchar int vertex_indices\nend_header\n";
                final_file.put(h.data(), h.size());
                f.out.copy_to(final_file);
                f.faces.copy_to(final_file);
                f.faces.close(true);
                f.out.close(true);
                final_file.close(false);
                rename_into_place(final_file.path(), paths_[s]);
                continue;
            }
            const std::string tmp = f.out.path();
            f.out.close(false);
            rename_into_place(tmp, paths_[s]);
        }
    }
    std::size_t memory_bytes() const override { return SinkBase::memory_bytes() + files_.size() * (3u << 20); }

private:
    static void rename_into_place(const std::string& tmp, const std::string& path) {
        std::error_code ec;
        fs::rename(tmp, path, ec);
        if (ec) {
            fs::remove(tmp, ec);
            throw Error(path, "cannot move the written file into place: " + ec.message());
        }
    }
    struct Files {
        bool stl = false, normals = false;
        std::size_t vertex_bytes = 0;
        SpillFile out;   // STL: the output itself; PLY: the vertices
        SpillFile faces; // PLY: the faces
        SpillFile& verts_spill() { return out; }
    };
    std::vector<Files> files_;
};

} // namespace

bool is_streamable_mesh_path(const std::string& path) {
    const std::string e = lower_ext(path);
    return e == ".pvtp" || e == ".ply" || e == ".stl";
}

std::unique_ptr<MeshSink> make_mesh_sink(const std::vector<std::string>& paths) {
    if (paths.empty()) throw Error("streaming", "no output");
    const std::string e = lower_ext(paths[0]);
    for (const auto& p : paths)
        if (lower_ext(p) != e) throw Error(p, "all outputs of one run must have the same format");
    if (e == ".pvtp") return std::make_unique<PvtpSink>(paths);
    if (e == ".ply" || e == ".stl") return std::make_unique<AssembledSink>(paths);
    if (e == ".vtp")
        throw Error(
            paths[0],
            "a single .vtp cannot be written without holding the whole mesh: write .pvtp (pieces), .ply or .stl");
    throw Error(paths[0], "streamed output must be .pvtp, .ply or .stl");
}

} // namespace iso
