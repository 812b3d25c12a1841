// Mesh readers and writers (STL, PLY, OBJ, VTP), in LPS mm.
//
// STL, PLY and OBJ are parsed by io/mesh_parsers.cpp (VTK's readers for them
// crash on malformed input); VTP goes through VTK's XML reader. The coordinate
// system is read from Slicer's "SPACE=RAS|LPS" tag where the format has a
// header or comment, and written as SPACE=LPS. OBJ is written here because
// VTK 9.1's vtkOBJWriter cannot add a comment line; binary STL and PLY by
// io/mesh_writers.cpp (VTK's bytes, formatted in parallel).
#include "io/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <glm/glm.hpp>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLPolyDataWriter.h>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mesh_parsers.hpp"
#include "io/mesh_writers.hpp"
#include "io/vtk_mesh.hpp"
#include "io/vtp_reader.hpp"
#include "io/vtk_util.hpp"

namespace iso {
namespace fs = std::filesystem;

MeshStats mesh_stats(const Mesh& m) {
    MeshStats s;
    s.vertices = m.positions.size();
    s.triangles = m.triangles.size();
    if (!m.positions.empty()) {
        s.bounds_min = s.bounds_max = glm::dvec3(m.positions[0]);
        for (const auto& p : m.positions) {
            s.bounds_min = glm::min(s.bounds_min, glm::dvec3(p));
            s.bounds_max = glm::max(s.bounds_max, glm::dvec3(p));
        }
    }
    // Relative to the bounds' centre, so the signed volume does not lose
    // digits to large coordinates.
    const glm::dvec3 c = 0.5 * (s.bounds_min + s.bounds_max);
    for (const auto& t : m.triangles) {
        const TriangleTerms tt = triangle_terms(c, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]);
        s.area += tt.area;
        s.volume += tt.det / 6.0;
    }
    return s;
}

TriangleTerms triangle_terms(const glm::dvec3& o, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
    const glm::dvec3 a = glm::dvec3(p0) - o, b = glm::dvec3(p1) - o, d = glm::dvec3(p2) - o;
    const glm::dvec3 bd = glm::cross(b, d);
    TriangleTerms t;
    t.area = 0.5 * glm::length(glm::cross(b - a, d - a));
    t.det = glm::dot(a, bd);
    t.moment = glm::cross(a, b) + bd + glm::cross(d, a);
    return t;
}

double volume_moved(double volume, const glm::dvec3& moment, const glm::dvec3& from, const glm::dvec3& to) {
    return volume - glm::dot(to - from, moment) / 6.0;
}

namespace {

// In the order of mesh_extensions().
enum class Fmt { Stl, Ply, Obj, Vtp };

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

Fmt format_of(const std::string& path) {
    const std::string ext = lower_extension(path);
    const auto& all = mesh_extensions();
    for (std::size_t i = 0; i < all.size(); ++i)
        if (ext == all[i]) return Fmt(i);
    throw Error(path, "unsupported mesh format '" + ext + "' (expected " + mesh_extensions_text() + ")");
}

} // namespace

Mesh from_polydata(vtkPolyData* in, const std::string& path) {
    vtkSmartPointer<vtkPolyData> pd = in;
    // Polygons and strips become triangles; lines and vertices are dropped.
    bool all_triangles = pd->GetNumberOfStrips() == 0;
    if (all_triangles) {
        auto* polys = pd->GetPolys();
        vtkIdType npts;
        const vtkIdType* ids;
        for (polys->InitTraversal(); polys->GetNextCell(npts, ids);)
            if (npts != 3) {
                all_triangles = false;
                break;
            }
    }
    if (!all_triangles) {
        vtkNew<vtkTriangleFilter> tf;
        tf->SetInputData(pd);
        tf->PassLinesOff();
        tf->PassVertsOff();
        tf->Update();
        pd = tf->GetOutput();
    }
    Mesh m;
    const vtkIdType np = pd->GetNumberOfPoints();
    m.positions.resize(std::size_t(np));
    std::size_t bad = 0;
    for (vtkIdType i = 0; i < np; ++i) {
        double p[3];
        pd->GetPoint(i, p);
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) ++bad;
        m.positions[std::size_t(i)] = glm::vec3(float(p[0]), float(p[1]), float(p[2]));
    }
    if (bad)
        throw Error(path,
                    std::to_string(bad) + " of " + std::to_string(np) + " vertices have NaN or infinite coordinates");
    auto* polys = pd->GetPolys();
    m.triangles.reserve(std::size_t(polys->GetNumberOfCells()));
    vtkIdType npts;
    const vtkIdType* ids;
    for (polys->InitTraversal(); polys->GetNextCell(npts, ids);) {
        if (npts != 3) continue;
        for (int k = 0; k < 3; ++k)
            if (ids[k] < 0 || ids[k] >= np)
                throw Error(path,
                            "a triangle refers to vertex " + std::to_string(ids[k]) + " of " + std::to_string(np));
        m.triangles.push_back({std::uint32_t(ids[0]), std::uint32_t(ids[1]), std::uint32_t(ids[2])});
    }
    if (auto* n = pd->GetPointData()->GetNormals();
        n && n->GetNumberOfComponents() == 3 && n->GetNumberOfTuples() == np) {
        m.normals.resize(std::size_t(np));
        for (vtkIdType i = 0; i < np; ++i) {
            double v[3];
            n->GetTuple(i, v);
            m.normals[std::size_t(i)] = glm::vec3(float(v[0]), float(v[1]), float(v[2]));
        }
    }
    // Colours: an unsigned char array of 3 or 4 components on the points.
    vtkDataArray* c = pd->GetPointData()->GetScalars();
    if (!c) c = pd->GetPointData()->GetArray("RGB");
    if (!c) c = pd->GetPointData()->GetArray("RGBA");
    if (c && c->GetDataType() == VTK_UNSIGNED_CHAR &&
        (c->GetNumberOfComponents() == 3 || c->GetNumberOfComponents() == 4) && c->GetNumberOfTuples() == np) {
        m.colors.resize(std::size_t(np));
        for (vtkIdType i = 0; i < np; ++i) {
            double v[4] = {0, 0, 0, 255};
            c->GetTuple(i, v);
            m.colors[std::size_t(i)] = glm::u8vec4(std::uint8_t(v[0]), std::uint8_t(v[1]), std::uint8_t(v[2]),
                                                   std::uint8_t(c->GetNumberOfComponents() == 4 ? v[3] : 255));
        }
    }
    std::size_t degenerate = 0;
    for (const auto& t : m.triangles)
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) ++degenerate;
    if (degenerate)
        m.warnings.push_back(std::to_string(degenerate) + " degenerate triangles (repeated vertices) kept as read");
    return m;
}

vtkSmartPointer<vtkPolyData> to_polydata(const Mesh& m, bool with_colors) {
    auto pd = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToFloat();
    pts->SetNumberOfPoints(vtkIdType(m.positions.size()));
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        pts->SetPoint(vtkIdType(i), m.positions[i].x, m.positions[i].y, m.positions[i].z);
    pd->SetPoints(pts);
    vtkNew<vtkCellArray> polys;
    polys->AllocateExact(vtkIdType(m.triangles.size()), vtkIdType(3 * m.triangles.size()));
    for (const auto& t : m.triangles) {
        const vtkIdType ids[3] = {t[0], t[1], t[2]};
        polys->InsertNextCell(3, ids);
    }
    pd->SetPolys(polys);
    if (m.normals.size() == m.positions.size() && !m.normals.empty()) {
        vtkNew<vtkFloatArray> n;
        n->SetName("Normals");
        n->SetNumberOfComponents(3);
        n->SetNumberOfTuples(vtkIdType(m.normals.size()));
        for (std::size_t i = 0; i < m.normals.size(); ++i) n->SetTypedTuple(vtkIdType(i), &m.normals[i].x);
        pd->GetPointData()->SetNormals(n);
    }
    if (with_colors && m.colors.size() == m.positions.size() && !m.colors.empty()) {
        vtkNew<vtkUnsignedCharArray> c;
        c->SetName("RGBA");
        c->SetNumberOfComponents(4);
        c->SetNumberOfTuples(vtkIdType(m.colors.size()));
        for (std::size_t i = 0; i < m.colors.size(); ++i) c->SetTypedTuple(vtkIdType(i), &m.colors[i].x);
        pd->GetPointData()->SetScalars(c);
    }
    return pd;
}

namespace {

void write_obj(const Mesh& m, const std::string& path) {
    std::ofstream f(path, std::ios::binary);
    if (!f) throw Error(path, "cannot open for writing");
    f << "# SPACE=LPS (coordinates in millimetres)\n# written by isoscope\n";
    f.precision(9);
    const bool normals = m.normals.size() == m.positions.size() && !m.normals.empty();
    for (const auto& p : m.positions) f << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    if (normals)
        for (const auto& n : m.normals) f << "vn " << n.x << ' ' << n.y << ' ' << n.z << '\n';
    for (const auto& t : m.triangles) {
        if (normals)
            f << "f " << t[0] + 1 << "//" << t[0] + 1 << ' ' << t[1] + 1 << "//" << t[1] + 1 << ' ' << t[2] + 1 << "//"
              << t[2] + 1 << '\n';
        else
            f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    }
    f.flush();
    if (!f) throw Error(path, "write failed (disk full?)");
}

} // namespace

const std::vector<std::string>& mesh_extensions() {
    static const std::vector<std::string> all = {".stl", ".ply", ".obj", ".vtp"};
    return all;
}

bool is_mesh_path(const std::string& path) {
    const std::string ext = lower_extension(path);
    const auto& all = mesh_extensions();
    return std::find(all.begin(), all.end(), ext) != all.end();
}

std::string mesh_extensions_text() {
    std::string s;
    const auto& all = mesh_extensions();
    for (std::size_t i = 0; i < all.size(); ++i) s += (i == 0 ? "" : i + 1 == all.size() ? " or " : ", ") + all[i];
    return s;
}

Mesh load_mesh(const std::string& path) {
    quiet_vtk();
    const Fmt fmt = format_of(path);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path, fs::exists(path, ec) ? "not a regular file" : "no such file");
    const auto size = fs::file_size(path, ec);
    if (size == 0) throw Error(path, "file is empty");
    std::string space;
    Mesh m;
    try {
        switch (fmt) {
        case Fmt::Stl: m = detail::parse_stl(path, space); break;
        case Fmt::Ply: m = detail::parse_ply(path, space); break;
        case Fmt::Obj: m = detail::parse_obj(path, space); break;
        case Fmt::Vtp: m = detail::read_vtp(path, space, size); break;
        }
    } catch (const std::bad_alloc&) {
        throw Error(path, "not enough memory to read this file (a corrupt header announcing a huge size?)");
    }
    const std::uint32_t n = std::uint32_t(m.positions.size());
    for (const auto& t : m.triangles)
        if (t[0] >= n || t[1] >= n || t[2] >= n)
            throw Error(path, "a triangle refers to a vertex that does not exist (" +
                                  std::to_string(std::max({t[0], t[1], t[2]})) + " of " + std::to_string(n) + ")");
    if (!m.normals.empty() && m.normals.size() != m.positions.size()) m.normals.clear();
    if (!m.colors.empty() && m.colors.size() != m.positions.size()) m.colors.clear();
    std::size_t degenerate = 0;
    for (const auto& t : m.triangles)
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) ++degenerate;
    if (degenerate && fmt != Fmt::Vtp)
        m.warnings.push_back(std::to_string(degenerate) + " degenerate triangles (repeated vertices) kept as read");
    if (space == "RAS") {
        // A 180-degree turn about z: determinant +1, so winding and outward normals stay.
        for (auto& p : m.positions) p = glm::vec3(-p.x, -p.y, p.z);
        for (auto& nn : m.normals) nn = glm::vec3(-nn.x, -nn.y, nn.z);
        m.warnings.push_back("coordinates converted from RAS (SPACE=RAS in the file) to LPS");
    } else if (!space.empty() && space != "LPS") {
        m.warnings.push_back("unknown SPACE=" + space + " tag; coordinates taken as LPS");
    }
    return m;
}

void save_mesh(const Mesh& m, const std::string& path) {
    quiet_vtk();
    const Fmt fmt = format_of(path);
    check_writable_destination(path);
    const std::uint32_t n = std::uint32_t(m.positions.size());
    for (const auto& t : m.triangles)
        if (t[0] >= n || t[1] >= n || t[2] >= n) throw Error(path, "mesh has a triangle index out of range");
    write_atomically(path, [&](const std::string& tmp) {
        // .stl and .ply by hand (mesh_writers.cpp): the bytes VTK's writers
        // wrote, formatted in parallel and written in blocks.
        if (fmt == Fmt::Obj) return write_obj(m, tmp);
        if (fmt == Fmt::Stl) return detail::write_stl(m, tmp, path);
        if (fmt == Fmt::Ply) return detail::write_ply(m, tmp, path);
        auto pd = to_polydata(m, true);
        vtkNew<vtkStringArray> space;
        space->SetName("SPACE");
        space->InsertNextValue("LPS");
        pd->GetFieldData()->AddArray(space);
        vtkNew<VtkMessages> msgs;
        vtkNew<vtkXMLPolyDataWriter> w;
        msgs->watch(w);
        w->SetInputData(pd);
        w->SetFileName(tmp.c_str());
        w->SetDataModeToAppended();
        w->SetCompressorTypeToZLib();
        const int ok = w->Write();
        if (!ok || msgs->has_error()) throw Error(path, "cannot write: " + msgs->first_error());
    });
}

} // namespace iso
