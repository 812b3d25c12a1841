// Mesh readers and writers through VTK (STL, PLY, OBJ, VTP), in LPS mm.
//
// Files are checked before VTK sees them (existence, size, STL and PLY
// headers against the file size), because VTK's readers report malformed
// input through its output window, and some crash on it. The coordinate
// system is read from Slicer's "SPACE=RAS|LPS" tag where the format has a
// header or comment, and written as SPACE=LPS. OBJ is written here because
// VTK 9.1's vtkOBJWriter cannot add a comment line.
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
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPLYWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkSTLWriter.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
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
        const glm::dvec3 a = glm::dvec3(m.positions[t[0]]) - c, b = glm::dvec3(m.positions[t[1]]) - c,
                         d = glm::dvec3(m.positions[t[2]]) - c;
        s.area += 0.5 * glm::length(glm::cross(b - a, d - a));
        s.volume += glm::dot(a, glm::cross(b, d)) / 6.0;
    }
    return s;
}

namespace {

enum class Fmt { Stl, Ply, Obj, Vtp };

Fmt format_of(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".stl") return Fmt::Stl;
    if (ext == ".ply") return Fmt::Ply;
    if (ext == ".obj") return Fmt::Obj;
    if (ext == ".vtp") return Fmt::Vtp;
    throw Error(path, "unsupported mesh format '" + ext + "' (expected .stl, .ply, .obj or .vtp)");
}

// "RAS", "LPS" or "" from text holding Slicer's "SPACE=..." tag.
std::string space_tag(const std::string& text) {
    const auto p = text.find("SPACE=");
    if (p == std::string::npos) return "";
    return text.substr(p + 6, 3);
}

std::string read_prefix(const std::string& path, std::size_t n) {
    std::ifstream f(path, std::ios::binary);
    std::string s(n, '\0');
    f.read(s.data(), std::streamsize(n));
    s.resize(std::size_t(f.gcount()));
    return s;
}

// Binary STL: 80-byte header, triangle count, 50 bytes per triangle. Checks
// the count against the size before VTK allocates for it.
std::string check_stl(const std::string& path, std::uintmax_t size) {
    const std::string head = read_prefix(path, 84);
    if (size >= 84) {
        std::uint32_t n = 0;
        std::memcpy(&n, head.data() + 80, 4);
        if (84 + 50 * std::uintmax_t(n) == size) return head.substr(0, 80); // binary
    }
    std::string start = head.substr(0, std::min<std::size_t>(head.size(), 80));
    const auto nonspace = start.find_first_not_of(" \t\r\n");
    if (nonspace != std::string::npos && start.compare(nonspace, 5, "solid") == 0) {
        // ASCII, or a binary file whose header starts with "solid" and whose
        // size is wrong: tell them apart by the text.
        const std::string more = read_prefix(path, 4096);
        if (more.find("facet") != std::string::npos || more.find("endsolid") != std::string::npos)
            return start.substr(0, start.find('\n'));
    }
    if (size < 84) throw Error(path, "truncated STL file (" + std::to_string(size) + " bytes)");
    std::uint32_t n = 0;
    std::memcpy(&n, head.data() + 80, 4);
    throw Error(path, "truncated or malformed binary STL: the header announces " + std::to_string(n) +
                          " triangles (" + std::to_string(84 + 50 * std::uintmax_t(n)) + " bytes), the file has " +
                          std::to_string(size) + " bytes");
}

// PLY: the header must be complete and its element counts plausible for the
// file size (VTK's reader trusts them).
std::string check_ply(const std::string& path, std::uintmax_t size) {
    const std::string head = read_prefix(path, 1 << 16);
    if (head.compare(0, 3, "ply") != 0) throw Error(path, "not a PLY file (no 'ply' magic)");
    const auto end = head.find("end_header");
    if (end == std::string::npos) throw Error(path, "PLY header is incomplete (no end_header)");
    std::istringstream in(head.substr(0, end));
    std::string line, comments, format;
    std::uintmax_t elements = 0;
    bool has_vertex = false, has_face = false;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string word;
        ls >> word;
        if (word == "comment" || word == "obj_info") comments += line + "\n";
        else if (word == "format") ls >> format;
        else if (word == "element") {
            std::string name;
            std::uintmax_t count = 0;
            if (!(ls >> name >> count)) throw Error(path, "malformed PLY element line: " + line);
            elements += count;
            has_vertex |= name == "vertex";
            has_face |= name == "face";
        } else if (word == "property") {
            std::string type;
            ls >> type;
            if (type == "list") {
                std::string ct, it;
                ls >> ct >> it;
                static const char* ok[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                           "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
                auto valid = [&](const std::string& t) { return std::find(std::begin(ok), std::end(ok), t) != std::end(ok); };
                if (!valid(ct) || !valid(it)) throw Error(path, "malformed PLY list property: " + line);
            }
        }
    }
    if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        throw Error(path, "unknown PLY format '" + format + "'");
    if (!has_vertex || !has_face) throw Error(path, "PLY file has no vertex or no face element");
    // Every element takes at least one byte (binary) or two characters (ASCII).
    if (elements > size) throw Error(path, "PLY header announces more elements than the file can hold (truncated?)");
    return comments;
}

// OBJ vertex lines must hold finite numbers: vtkOBJReader reads "nan" and
// other unparsable coordinates as 0 without a word.
void check_obj(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::string line;
    std::size_t lineno = 0, bad = 0, first_bad = 0;
    while (std::getline(f, line)) {
        ++lineno;
        if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != '\t')) continue;
        const char* p = line.c_str() + 2;
        for (int k = 0; k < 3; ++k) {
            char* end = nullptr;
            const double x = std::strtod(p, &end);
            if (end == p || !std::isfinite(x)) {
                if (!bad++) first_bad = lineno;
                break;
            }
            p = end;
        }
    }
    if (bad)
        throw Error(path, std::to_string(bad) + " vertex line(s) with NaN, infinite or unreadable coordinates (first at line " +
                              std::to_string(first_bad) + ")");
}

vtkSmartPointer<vtkPolyData> run_reader(vtkAlgorithm* reader, const std::string& path) {
    vtkNew<VtkMessages> msgs;
    msgs->watch(reader);
    reader->Update();
    if (msgs->has_error()) throw Error(path, msgs->first_error());
    auto* pd = vtkPolyData::SafeDownCast(reader->GetOutputDataObject(0));
    if (!pd) throw Error(path, "the reader produced no polygon data");
    return pd;
}

Mesh to_mesh(vtkPolyData* in, const std::string& path) {
    vtkSmartPointer<vtkPolyData> pd = in;
    // Polygons and strips become triangles; lines and vertices are dropped.
    bool all_triangles = pd->GetNumberOfStrips() == 0;
    if (all_triangles) {
        auto* polys = pd->GetPolys();
        vtkIdType npts;
        const vtkIdType* ids;
        for (polys->InitTraversal(); polys->GetNextCell(npts, ids);)
            if (npts != 3) { all_triangles = false; break; }
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
    if (bad) throw Error(path, std::to_string(bad) + " of " + std::to_string(np) + " vertices have NaN or infinite coordinates");
    auto* polys = pd->GetPolys();
    m.triangles.reserve(std::size_t(polys->GetNumberOfCells()));
    vtkIdType npts;
    const vtkIdType* ids;
    for (polys->InitTraversal(); polys->GetNextCell(npts, ids);) {
        if (npts != 3) continue;
        for (int k = 0; k < 3; ++k)
            if (ids[k] < 0 || ids[k] >= np)
                throw Error(path, "a triangle refers to vertex " + std::to_string(ids[k]) + " of " + std::to_string(np));
        m.triangles.push_back({std::uint32_t(ids[0]), std::uint32_t(ids[1]), std::uint32_t(ids[2])});
    }
    if (auto* n = pd->GetPointData()->GetNormals(); n && n->GetNumberOfComponents() == 3 && n->GetNumberOfTuples() == np) {
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
    if (c && c->GetDataType() == VTK_UNSIGNED_CHAR && (c->GetNumberOfComponents() == 3 || c->GetNumberOfComponents() == 4) &&
        c->GetNumberOfTuples() == np) {
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
    if (degenerate) m.warnings.push_back(std::to_string(degenerate) + " degenerate triangles (repeated vertices) kept as read");
    return m;
}

vtkSmartPointer<vtkPolyData> to_polydata(const Mesh& m, bool with_colors = true) {
    auto pd = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToFloat();
    pts->SetNumberOfPoints(vtkIdType(m.positions.size()));
    for (std::size_t i = 0; i < m.positions.size(); ++i) pts->SetPoint(vtkIdType(i), m.positions[i].x, m.positions[i].y, m.positions[i].z);
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
            f << "f " << t[0] + 1 << "//" << t[0] + 1 << ' ' << t[1] + 1 << "//" << t[1] + 1 << ' ' << t[2] + 1 << "//" << t[2] + 1 << '\n';
        else
            f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    }
    f.flush();
    if (!f) throw Error(path, "write failed (disk full?)");
}

} // namespace

Mesh load_mesh(const std::string& path) {
    quiet_vtk();
    const Fmt fmt = format_of(path);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path, fs::exists(path, ec) ? "not a regular file" : "no such file");
    const auto size = fs::file_size(path, ec);
    if (size == 0) throw Error(path, "file is empty");
    std::string space;
    vtkSmartPointer<vtkPolyData> pd;
    switch (fmt) {
    case Fmt::Stl: {
        space = space_tag(check_stl(path, size));
        vtkNew<vtkSTLReader> r;
        r->SetFileName(path.c_str());
        r->MergingOn(); // weld identical positions: STL stores each triangle's corners
        pd = run_reader(r, path);
        break;
    }
    case Fmt::Ply: {
        space = space_tag(check_ply(path, size));
        vtkNew<vtkPLYReader> r;
        r->SetFileName(path.c_str());
        pd = run_reader(r, path);
        break;
    }
    case Fmt::Obj: {
        space = space_tag(read_prefix(path, 4096));
        check_obj(path);
        vtkNew<vtkOBJReader> r;
        r->SetFileName(path.c_str());
        pd = run_reader(r, path);
        break;
    }
    case Fmt::Vtp: {
        vtkNew<vtkXMLPolyDataReader> r;
        r->SetFileName(path.c_str());
        if (!r->CanReadFile(path.c_str())) throw Error(path, "not a VTK XML PolyData file");
        pd = run_reader(r, path);
        if (auto* s = vtkStringArray::SafeDownCast(pd->GetFieldData()->GetAbstractArray("SPACE")); s && s->GetNumberOfValues() > 0)
            space = s->GetValue(0);
        break;
    }
    }
    if (pd->GetNumberOfPoints() == 0 && size > 0 && fmt != Fmt::Vtp)
        throw Error(path, "no vertices could be read (malformed or truncated file)");
    Mesh m = to_mesh(pd, path);
    if (space == "RAS") {
        // A 180-degree turn about z: determinant +1, so winding and outward normals stay.
        for (auto& p : m.positions) p = glm::vec3(-p.x, -p.y, p.z);
        for (auto& n : m.normals) n = glm::vec3(-n.x, -n.y, n.z);
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
        if (fmt == Fmt::Obj) return write_obj(m, tmp);
        auto pd = to_polydata(m, fmt != Fmt::Stl);
        vtkNew<VtkMessages> msgs;
        int ok = 1;
        if (fmt == Fmt::Stl) {
            vtkNew<vtkSTLWriter> w;
            msgs->watch(w);
            w->SetInputData(pd);
            w->SetFileName(tmp.c_str());
            w->SetFileTypeToBinary();
            w->SetHeader("SPACE=LPS isoscope mesh, millimetres");
            ok = w->Write();
        } else if (fmt == Fmt::Ply) {
            vtkNew<vtkPLYWriter> w;
            msgs->watch(w);
            w->SetInputData(pd);
            w->SetFileName(tmp.c_str());
            w->SetFileTypeToBinary();
            w->AddComment("SPACE=LPS");
            w->AddComment("written by isoscope; coordinates in millimetres");
            if (!m.colors.empty()) {
                w->SetArrayName("RGBA");
                w->SetColorModeToDefault();
                w->EnableAlphaOn();
            }
            ok = w->Write();
        } else {
            vtkNew<vtkStringArray> space;
            space->SetName("SPACE");
            space->InsertNextValue("LPS");
            pd->GetFieldData()->AddArray(space);
            vtkNew<vtkXMLPolyDataWriter> w;
            msgs->watch(w);
            w->SetInputData(pd);
            w->SetFileName(tmp.c_str());
            w->SetDataModeToAppended();
            w->SetCompressorTypeToZLib();
            ok = w->Write();
        }
        if (!ok || msgs->has_error()) throw Error(path, "cannot write: " + msgs->first_error());
    });
}

} // namespace iso
