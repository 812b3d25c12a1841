// Mesh readers and writers: round trips through every format (a cube and the
// real Stanford bunny), the SPACE tag written and honoured, bad input.
#include <filesystem>
#include <cstring>

#include <glm/glm.hpp>

#include "io/error.hpp"
#include "io/mesh.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::read_file;
using iso::test::TempDir;
using iso::test::write_file;
namespace fs = std::filesystem;

namespace {

// A closed unit cube of 12 outward-facing triangles, offset to LPS (10, 20, 30).
Mesh unit_cube() {
    Mesh m;
    for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 2; ++x) m.positions.emplace_back(10 + x, 20 + y, 30 + z);
    auto q = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
    };
    q(0, 2, 3, 1); // z = 0, facing -z
    q(4, 5, 7, 6); // z = 1
    q(0, 1, 5, 4); // y = 0
    q(2, 6, 7, 3); // y = 1
    q(0, 4, 6, 2); // x = 0
    q(1, 3, 7, 5); // x = 1
    return m;
}

} // namespace

TEST(MeshIo, CubeStatsAreExact) {
    const auto s = mesh_stats(unit_cube());
    EXPECT_DOUBLE_EQ(s.area, 6.0);
    EXPECT_DOUBLE_EQ(s.volume, 1.0);
    EXPECT_EQ(s.bounds_min, glm::dvec3(10, 20, 30));
}

TEST(MeshIo, RoundTripsEveryFormat) {
    TempDir dir;
    Mesh bunny = load_mesh(test::data("bunny.vtp"));
    ASSERT_GE(bunny.triangles.size(), 1000u);
    for (const Mesh& m : {unit_cube(), bunny}) {
        const auto ref = mesh_stats(m);
        for (const char* ext : {".stl", ".ply", ".obj", ".vtp"}) {
            const std::string path = dir / (std::string("m") + ext);
            save_mesh(m, path);
            const Mesh r = load_mesh(path);
            const auto s = mesh_stats(r);
            EXPECT_EQ(s.triangles, ref.triangles) << ext;
            EXPECT_NEAR(s.area, ref.area, 1e-6 * ref.area) << ext;
            EXPECT_NEAR(s.volume, ref.volume, 1e-6 * std::abs(ref.volume) + 1e-9) << ext;
            EXPECT_EQ(s.bounds_min, ref.bounds_min) << ext;
            EXPECT_EQ(s.bounds_max, ref.bounds_max) << ext;
            if (std::string(ext) != ".stl") {
                EXPECT_EQ(r.positions.size(), m.positions.size()) << ext;
            }
        }
    }
}

TEST(MeshIo, StlIsWeldedIntoAnIndexedMesh) {
    TempDir dir;
    save_mesh(unit_cube(), dir / "c.stl");
    const Mesh r = load_mesh(dir / "c.stl");
    EXPECT_EQ(r.positions.size(), 8u); // 36 corners in the file, 8 distinct
}

TEST(MeshIo, NormalsAndColoursSurviveWhereTheFormatHasThem) {
    TempDir dir;
    Mesh m = unit_cube();
    for (auto& p : m.positions) {
        m.normals.push_back(glm::normalize(p - glm::vec3(10.5f, 20.5f, 30.5f)));
        m.colors.emplace_back(std::uint8_t(p.x * 10), 200, 30, 255);
    }
    save_mesh(m, dir / "c.vtp");
    const Mesh v = load_mesh(dir / "c.vtp");
    ASSERT_EQ(v.normals.size(), 8u);
    ASSERT_EQ(v.colors.size(), 8u);
    EXPECT_EQ(v.colors[1], m.colors[1]);
    EXPECT_LT(glm::length(v.normals[5] - m.normals[5]), 1e-6f);
    save_mesh(m, dir / "c.ply");
    const Mesh p = load_mesh(dir / "c.ply");
    ASSERT_EQ(p.colors.size(), 8u);
    EXPECT_EQ(p.colors[7], m.colors[7]);
    save_mesh(m, dir / "c.obj");
    const Mesh o = load_mesh(dir / "c.obj");
    EXPECT_EQ(o.positions.size(), 8u);
}

TEST(MeshIo, SpaceTagIsWrittenAndRasIsConverted) {
    TempDir dir;
    save_mesh(unit_cube(), dir / "c.stl");
    EXPECT_EQ(read_file(dir / "c.stl").substr(0, 9), "SPACE=LPS");
    save_mesh(unit_cube(), dir / "c.ply");
    EXPECT_NE(read_file(dir / "c.ply").find("comment SPACE=LPS"), std::string::npos);
    save_mesh(unit_cube(), dir / "c.obj");
    EXPECT_NE(read_file(dir / "c.obj").find("SPACE=LPS"), std::string::npos);
    save_mesh(unit_cube(), dir / "c.vtp");
    EXPECT_NE(read_file(dir / "c.vtp").find("SPACE"), std::string::npos);

    // Slicer writes RAS meshes with such a tag: x and y flip on read.
    write_file(dir / "ras.obj", "# SPACE=RAS\nv 1 2 3\nv 4 5 6\nv 7 8 10\nf 1 2 3\n");
    const Mesh r = load_mesh(dir / "ras.obj");
    EXPECT_EQ(r.positions[0], glm::vec3(-1, -2, 3));
    EXPECT_FALSE(r.warnings.empty());
    write_file(dir / "ras.stl",
               "solid SPACE=RAS\nfacet normal 0 0 1\nouter loop\nvertex 1 2 3\nvertex 4 5 6\nvertex 7 8 10\n"
               "endloop\nendfacet\nendsolid\n");
    EXPECT_EQ(load_mesh(dir / "ras.stl").positions[0], glm::vec3(-1, -2, 3));
    write_file(dir / "ras.ply",
               "ply\nformat ascii 1.0\ncomment SPACE=RAS\nelement vertex 3\nproperty float x\nproperty float y\n"
               "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
               "1 2 3\n4 5 6\n7 8 10\n3 0 1 2\n");
    EXPECT_EQ(load_mesh(dir / "ras.ply").positions[0], glm::vec3(-1, -2, 3));
    write_file(dir / "lps.obj", "v 1 2 3\nv 4 5 6\nv 7 8 10\nf 1 2 3\n");
    EXPECT_EQ(load_mesh(dir / "lps.obj").positions[0], glm::vec3(1, 2, 3)); // untagged: LPS
}

TEST(MeshIo, BadInput) {
    TempDir dir;
    auto expect_error = [&](const std::string& path, const std::string& reason) {
        try {
            load_mesh(path);
            ADD_FAILURE() << path << " loaded";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(fs::path(path).filename().string()), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
        }
    };
    expect_error(dir / "missing.stl", "no such file");
    write_file(dir / "empty.ply", "");
    expect_error(dir / "empty.ply", "empty");
    write_file(dir / "x.off", "OFF");
    expect_error(dir / "x.off", "unsupported mesh format");
    // Binary STL announcing more triangles than it holds.
    std::string stl(84, '\0');
    const std::uint32_t n = 1000;
    std::memcpy(stl.data() + 80, &n, 4);
    write_file(dir / "short.stl", stl + std::string(50 * 10, '\0'));
    expect_error(dir / "short.stl", "truncated");
    write_file(dir / "garbage.stl", std::string(200, 'x'));
    expect_error(dir / "garbage.stl", "");
    write_file(dir / "noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
    expect_error(dir / "noend.ply", "end_header");
    write_file(dir / "huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n");
    expect_error(dir / "huge.ply", "truncated");
    write_file(dir / "nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    expect_error(dir / "nan.obj", "NaN");
    write_file(dir / "bad.vtp", "<VTKFile type=\"PolyData\"><broken");
    expect_error(dir / "bad.vtp", "");
    // A mangled array format: VTK would read it as appended data and trust its
    // compression header (a division by zero the fuzz smoke found).
    {
        std::string v = read_file(
            ISOSCOPE_SOURCE_DIR "/tests/fuzz/regressions/vtp/crash-vtp-crash-4eaf944ab1554cf45e1a8a8200df37f552b003a3");
        ASSERT_FALSE(v.empty());
        write_file(dir / "format.vtp", v);
        expect_error(dir / "format.vtp", "format 'appe' is not ascii, binary or appended");
    }
    // Writing: a bad index is refused; a missing folder is named; nothing overwritten.
    Mesh bad = unit_cube();
    bad.triangles.push_back({0, 1, 99});
    write_file(dir / "keep.stl", "user data");
    EXPECT_THROW(save_mesh(bad, dir / "keep.stl"), Error);
    EXPECT_EQ(read_file(dir / "keep.stl"), "user data");
    EXPECT_THROW(save_mesh(unit_cube(), dir / "no/such/folder/m.stl"), Error);
}

TEST(MeshIo, AVtpThatCrashedVtksParserIsAnErrorNamingTheFile) {
    // Our own writer's .vtp with an offsets array's type changed to Int32 and
    // one base64 character changed (found by the fuzz smoke): the compression
    // headers are valid, and VTK 9.1's parser read through a null block table.
    // VTK reads .vtp in a child process: the crash is an error, and the
    // program goes on (the bunny still loads).
    const std::string f = std::string(ISOSCOPE_SOURCE_DIR) +
                          "/tests/fuzz/regressions/vtp/crash-vtp-crash-88d47079a896cb6486cad74449661ef0b90f8085";
    test::TempDir tmp;
    const std::string copy = tmp / "crash.vtp";
    std::filesystem::copy_file(f, copy);
    const std::string e = test::error_of([&] { load_mesh(copy); });
    EXPECT_NE(e.find(copy + ": VTK's XML PolyData reader failed on this file"), std::string::npos) << e;
    EXPECT_EQ(load_mesh(test::data("bunny.vtp")).triangles.size(), 1000u);
}
