// The hand-written binary PLY and STL writers (io/mesh_writers.*) against
// VTK's, byte for byte: save_mesh() wrote .ply and .stl through
// vtkPLYWriter and vtkSTLWriter until issue 39; the reference here is that
// code path (to_polydata + the VTK writer with save_mesh()'s settings),
// called directly. Meshes: with and without normals, with colours (and
// colours that do not cover every vertex), degenerate triangles, an empty
// mesh, vertices without triangles, and a mesh of several write blocks.
#include <cstring>
#include <filesystem>
#include <string>

#include <glm/glm.hpp>
#include <vtkNew.h>
#include <vtkPLYWriter.h>
#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkSmartPointer.h>

#include "io/error.hpp"
#include "io/mesh.hpp"
#include "io/mesh_writers.hpp"
#include "io/vtk_mesh.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::read_file;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

// save_mesh()'s VTK path before issue 39, as it was.
void vtk_write(const Mesh& m, const std::string& path) {
    const bool stl = fs::path(path).extension() == ".stl";
    auto pd = to_polydata(m, !stl);
    if (stl) {
        vtkNew<vtkSTLWriter> w;
        w->SetInputData(pd);
        w->SetFileName(path.c_str());
        w->SetFileTypeToBinary();
        w->SetHeader("SPACE=LPS isoscope mesh, millimetres");
        ASSERT_EQ(w->Write(), 1);
    } else {
        vtkNew<vtkPLYWriter> w;
        w->SetInputData(pd);
        w->SetFileName(path.c_str());
        w->SetFileTypeToBinary();
        w->AddComment("SPACE=LPS");
        w->AddComment("written by isoscope; coordinates in millimetres");
        if (!m.colors.empty()) {
            w->SetArrayName("RGBA");
            w->SetColorModeToDefault();
            w->EnableAlphaOn();
        }
        ASSERT_EQ(w->Write(), 1);
    }
}

Mesh cube() { return test::box_mesh(glm::dvec3(10.25, -20, 30), glm::dvec3(11, -19.5, 31.125)); }

// Triangles with a repeated vertex, three collinear corners and a
// zero-length normal that rounds (tiny coordinates), beside normal ones.
Mesh degenerate() {
    Mesh m = cube();
    const auto n = std::uint32_t(m.positions.size());
    m.positions.push_back({1, 2, 3});
    m.positions.push_back({2, 4, 6});
    m.positions.push_back({3, 6, 9});
    m.positions.push_back({1e-30f, 0, 0});
    m.positions.push_back({0, 1e-30f, 0});
    m.triangles.push_back({n, n, n + 1});         // repeated vertex
    m.triangles.push_back({n, n + 1, n + 2});     // collinear
    m.triangles.push_back({n + 3, n + 4, n + 3}); // repeated, tiny
    m.triangles.push_back({0, n + 3, n + 4});     // long and thin
    return m;
}

// A mesh of several 4 MiB blocks in either format (STL: 83 886 facets per
// block), far from the origin, with normals and colours.
Mesh big() {
    Mesh m = test::uv_sphere(glm::dvec3(-101.3, 250.7, 1210.1), 37.3, 500, 400);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        m.normals.push_back(glm::normalize(m.positions[i] - glm::vec3(-101.3f, 250.7f, 1210.1f)));
        m.colors.emplace_back(std::uint8_t(i), std::uint8_t(i >> 8), std::uint8_t(i * 7), std::uint8_t(255 - i));
    }
    return m;
}

// save_mesh() and VTK write the same bytes for `m` in both formats.
void expect_as_vtk(const Mesh& m, const std::string& what) {
    TempDir dir;
    for (const char* ext : {".ply", ".stl"}) {
        SCOPED_TRACE(what + " " + ext);
        const std::string ours = dir / (std::string("ours") + ext), ref = dir / (std::string("vtk") + ext);
        save_mesh(m, ours);
        vtk_write(m, ref);
        const std::string a = read_file(ours), b = read_file(ref);
        EXPECT_GE(a.size(), std::string(ext) == ".stl" ? iso::detail::kStlHeaderBytes : 200u);
        EXPECT_EQ(a.size(), b.size());
        EXPECT_TRUE(a == b) << "first difference at byte "
                            << std::mismatch(a.begin(), a.end(), b.begin(), b.end()).first - a.begin();
    }
}

} // namespace

TEST(MeshWriters, CubeWithoutNormalsIsWrittenAsVtkWroteIt) { expect_as_vtk(cube(), "cube"); }

TEST(MeshWriters, NormalsAreLeftOutOfPlyAsVtkLeftThem) {
    Mesh m = cube();
    for (const auto& p : m.positions) m.normals.push_back(glm::normalize(p - glm::vec3(10.6f, -19.75f, 30.5f)));
    expect_as_vtk(m, "cube with normals");
}

TEST(MeshWriters, ColoursAreRgbaAsVtkWroteThem) {
    Mesh m = cube();
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        m.colors.emplace_back(std::uint8_t(30 * i), 200, 7, std::uint8_t(255 - 20 * i));
    expect_as_vtk(m, "coloured cube");
    EXPECT_NE(iso::detail::ply_header(8, 12, true).find("property uchar alpha\n"), std::string::npos);
    // Colours that do not cover every vertex are not written (to_polydata drops them).
    m.colors.pop_back();
    expect_as_vtk(m, "colours short of the vertices");
}

TEST(MeshWriters, DegenerateTrianglesAreWrittenAsVtkWroteThem) { expect_as_vtk(degenerate(), "degenerate"); }

TEST(MeshWriters, EmptyMeshesAreWrittenAsVtkWroteThem) {
    expect_as_vtk(Mesh{}, "empty");
    Mesh points;
    points.positions = {{1, 2, 3}, {4, 5, 6}};
    expect_as_vtk(points, "vertices without triangles");
}

TEST(MeshWriters, ManyBlocksAreWrittenAsVtkWroteThem) {
    const Mesh m = big();
    ASSERT_GT(m.triangles.size() * iso::detail::kStlFacetBytes, std::size_t(3) * (4u << 20));
    expect_as_vtk(m, "big");
}

TEST(MeshWriters, RecordsAreTheFormatsLayout) {
    unsigned char f[iso::detail::kPlyFaceBytes];
    iso::detail::ply_face(1, 70000, 3, f);
    EXPECT_EQ(f[0], 3);
    std::int32_t ids[3];
    std::memcpy(ids, f + 1, 12);
    EXPECT_EQ(ids[1], 70000);
    unsigned char s[iso::detail::kStlFacetBytes];
    iso::detail::stl_facet({0, 0, 0}, {2, 0, 0}, {0, 3, 0}, s);
    float v[12];
    std::memcpy(v, s, 48);
    EXPECT_EQ(v[2], 1.0f); // counter-clockwise seen from +z
    EXPECT_EQ(v[6], 2.0f);
    EXPECT_EQ(s[48] | s[49], 0);
    unsigned char h[iso::detail::kStlHeaderBytes];
    iso::detail::stl_header(h, 12);
    EXPECT_EQ(std::string(reinterpret_cast<char*>(h)), "SPACE=LPS isoscope mesh, millimetres");
    EXPECT_EQ(h[79], 0);
    EXPECT_EQ(h[80], 12);
}

// Errors name the user's file and leave nothing behind; an existing file is
// kept as it was.
TEST(MeshWriters, AFailedWriteLeavesTheFileAsItWas) {
    TempDir dir;
    test::write_file(dir / "keep.stl", "the user's file");
    Mesh bad = cube();
    bad.triangles.push_back({0, 1, 99});
    for (const char* name : {"keep.stl", "keep.ply"}) {
        const std::string msg = test::error_of([&] { save_mesh(bad, dir / name); });
        EXPECT_NE(msg.find(name), std::string::npos) << msg;
    }
    EXPECT_EQ(read_file(dir / "keep.stl"), "the user's file");
    EXPECT_EQ(test::files_in(dir.path()), std::vector<std::string>{"keep.stl"});
    if (fs::exists("/dev/full")) {
        iso::detail::OutFile f;
        f.open("/dev/full", "full.stl");
        const std::string msg = test::error_of([&] {
            iso::detail::BlockWriter w;
            w.write(f, 100000, iso::detail::kStlFacetBytes, [](std::size_t b, std::size_t e, unsigned char* out) {
                std::memset(out, 0, (e - b) * iso::detail::kStlFacetBytes);
            });
        });
        EXPECT_NE(msg.find("full.stl"), std::string::npos) << msg;
        EXPECT_NE(msg.find("No space left"), std::string::npos) << msg;
    }
}
