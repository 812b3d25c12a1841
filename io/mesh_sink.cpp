// Piece-by-piece surface writers (mesh_sink.hpp).
//
// The assembled .ply and .stl files are written piece by piece (no Debian
// package writes these formats incrementally; save_mesh() needs the whole
// mesh), with the records of io/mesh_writers.hpp: binary little-endian PLY
// with x y z (nx ny nz where the pieces have normals) and "vertex_indices"
// as uchar/int lists, without VTK's comment and obj_info lines; binary STL
// as save_mesh() writes it; both tagged SPACE=LPS.
// The pieces of a .pvtp are written with VTK's vtkXMLPPolyDataWriter.
#include "io/mesh_sink.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <unordered_map>

#include <glm/glm.hpp>
#include <tbb/parallel_for.h>
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
#include "io/mesh_writers.hpp"
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
        add_terms(p.mesh);
        triangles += p.mesh.triangles.size();
        return id;
    }
    // The piece's triangle terms about c0, summed in fixed blocks in parallel
    // and added in block order (the same sums whatever the thread count).
    void add_terms(const Mesh& m) {
        constexpr std::size_t kBlock = 16384;
        struct Sum {
            double area = 0, det = 0;
            glm::dvec3 w{0.0};
        };
        std::vector<Sum> sums((m.triangles.size() + kBlock - 1) / kBlock);
        tbb::parallel_for(std::size_t(0), sums.size(), [&](std::size_t blk) {
            Sum& b = sums[blk];
            for (std::size_t i = blk * kBlock, e = std::min(m.triangles.size(), i + kBlock); i < e; ++i) {
                const auto& t = m.triangles[i];
                const TriangleTerms tt = triangle_terms(c0, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]);
                b.area += tt.area;
                b.det += tt.det;
                b.w += tt.moment;
            }
        });
        for (const Sum& b : sums) {
            area += b.area;
            det_sum += b.det;
            w += b.w;
        }
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
//
// Each piece's records are formatted in parallel into 4 MiB blocks and each
// block written with one write(2) (detail::BlockWriter), not a stdio call per
// record. STL facets go straight into the output (the count patched at the
// end). PLY needs the vertex count in its header and all vertices before
// the faces, neither known until the last piece: vertices and faces are
// spilled to two temporaries, and finish() writes the header and appends
// both with copy_file_range(2), in the kernel, instead of reading them back.

class AssembledSink final : public SinkBase {
public:
    explicit AssembledSink(std::vector<std::string> paths) : SinkBase(std::move(paths)), files_(paths_.size()) {
        for (std::size_t s = 0; s < paths_.size(); ++s) {
            auto& f = files_[s];
            f.stl = lower_ext(paths_[s]) == ".stl";
            const std::string tmp = temp_path_for(paths_[s]);
            f.temporaries.push_back(tmp);
            f.out.open(tmp, paths_[s]);
            if (f.stl) {
                unsigned char header[detail::kStlHeaderBytes];
                detail::stl_header(header, 0);
                f.out.write(header, sizeof header);
            } else {
                f.temporaries.push_back(tmp + ".faces");
                f.faces.open(tmp + ".faces", paths_[s]);
            }
        }
    }
    void piece(MeshPiece&& p) override {
        auto& st = state(p);
        auto& f = files_[p.surface];
        std::vector<std::uint8_t> is_new;
        const std::uint64_t first_new = st.vertices;
        const auto id = st.map(p, is_new);
        if (f.stl) return write_facets(f, p.mesh);
        // PLY: new vertices in global order, faces with global indices (spilled).
        if (!p.mesh.positions.empty()) {
            if (f.vertex_bytes == 0) f.vertex_bytes = p.mesh.normals.empty() ? 12 : 24;
            if ((f.vertex_bytes == 24) != !p.mesh.normals.empty())
                throw Error(paths_[p.surface], "pieces with and without normals");
        }
        write_vertices(f, p.mesh, id, is_new, first_new, st.vertices);
        const auto& T = p.mesh.triangles;
        writer_.write(f.faces, T.size(), detail::kPlyFaceBytes, [&](std::size_t b, std::size_t e, unsigned char* out) {
            for (std::size_t i = b; i < e; ++i, out += detail::kPlyFaceBytes)
                detail::ply_face(id[T[i][0]], id[T[i][1]], id[T[i][2]], out);
        });
    }
    void finish() override {
        for (std::size_t s = 0; s < paths_.size(); ++s) {
            auto& f = files_[s];
            const auto st = states_[s].stats();
            if (f.stl) {
                if (st.triangles > 0xFFFFFFFFull)
                    throw Error(paths_[s], "more than 4 billion triangles do not fit an STL file");
                const std::uint32_t n = std::uint32_t(st.triangles);
                f.out.write_at(80, &n, 4);
                f.out.close();
                rename_into_place(f.out.path(), paths_[s]);
                continue;
            }
            // Header, then the vertices, then the faces, into a third file.
            detail::OutFile whole;
            f.temporaries.push_back(f.out.path() + ".ply");
            whole.open(f.temporaries.back(), paths_[s]);
            const std::string h = ply_header(st.vertices, st.triangles, f.vertex_bytes == 24);
            whole.write(h.data(), h.size());
            whole.append_copy_of(f.out);
            whole.append_copy_of(f.faces);
            whole.close();
            rename_into_place(whole.path(), paths_[s]);
            std::error_code ec;
            fs::remove(f.out.path(), ec);
            fs::remove(f.faces.path(), ec);
        }
    }
    std::size_t memory_bytes() const override {
        // The two blocks being formatted and written, at most 4 MiB each.
        return SinkBase::memory_bytes() + (std::size_t(8) << 20);
    }

private:
    struct Files {
        bool stl = false;
        std::size_t vertex_bytes = 0;
        detail::OutFile out;   // STL: the output itself; PLY: the vertices
        detail::OutFile faces; // PLY: the faces
        std::vector<std::string> temporaries;
        // Removes what is left of the temporaries (all of them before finish(),
        // also when the sink's constructor throws).
        ~Files() {
            std::error_code ec;
            for (const auto& t : temporaries) fs::remove(t, ec);
        }
    };

    // The layout save_mesh() wrote through VTK, with normals where the pieces
    // have them (vtkPLYWriter left them out).
    static std::string ply_header(std::uint64_t vertices, std::uint64_t faces, bool normals) {
        std::string h = "ply\nformat binary_little_endian 1.0\ncomment SPACE=LPS\n"
                        "comment written by isoscope; coordinates in millimetres\n";
        h += "element vertex " + std::to_string(vertices) + "\nproperty float x\nproperty float y\nproperty float z\n";
        if (normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
        h += "element face " + std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
        return h;
    }
    // Facets carry their own coordinates: a seam vertex's position is the
    // same in both pieces, so no welding is needed to write them.
    void write_facets(Files& f, const Mesh& m) {
        const auto& P = m.positions;
        const auto& T = m.triangles;
        writer_.write(f.out, T.size(), detail::kStlFacetBytes, [&](std::size_t b, std::size_t e, unsigned char* out) {
            for (std::size_t i = b; i < e; ++i, out += detail::kStlFacetBytes)
                detail::stl_facet(P[T[i][0]], P[T[i][1]], P[T[i][2]], out);
        });
    }
    // The piece's new vertices, numbered [first, end) by map(), in that order.
    void write_vertices(Files& f, const Mesh& m, const std::vector<std::uint32_t>& id,
                        const std::vector<std::uint8_t>& is_new, std::uint64_t first, std::uint64_t end) {
        std::vector<std::uint32_t> local(std::size_t(end - first));
        for (std::size_t v = 0; v < is_new.size(); ++v)
            if (is_new[v]) local[std::size_t(id[v] - first)] = std::uint32_t(v);
        const std::size_t vb = f.vertex_bytes;
        writer_.write(f.out, local.size(), vb, [&](std::size_t b, std::size_t e, unsigned char* out) {
            for (std::size_t i = b; i < e; ++i, out += vb) {
                std::memcpy(out, &m.positions[local[i]], 12);
                if (vb == 24) std::memcpy(out + 12, &m.normals[local[i]], 12);
            }
        });
    }
    static void rename_into_place(const std::string& tmp, const std::string& path) {
        std::error_code ec;
        fs::rename(tmp, path, ec);
        if (ec) throw Error(path, "cannot move the written file into place: " + ec.message());
    }
    std::vector<Files> files_;
    detail::BlockWriter writer_;
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
