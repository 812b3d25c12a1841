// The isoscope command line, run as a real process on the bundled data.
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "io/mesh.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

TEST(Cli, InfoJsonHasTheDocumentedKeys) {
    const auto r = test::run_command(test::cli() + " info " + test::data("headsq.nhdr") + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["dims"], nlohmann::json({64, 64, 93}));
    EXPECT_EQ(j["type"], "int16");
    EXPECT_NEAR(j["spacing"][0].get<double>(), 3.2, 1e-12);
    EXPECT_NEAR(j["spacing"][2].get<double>(), 1.5, 1e-12);
    ASSERT_EQ(j["index_to_lps"].size(), 4u);
    // Row-major; the bundled CT's i runs towards the patient's right and k
    // towards inferior (datasets/README.md).
    const double expected[4][4] = {{-3.2, 0, 0, 0}, {0, 3.2, 0, 0}, {0, 0, -1.5, 0}, {0, 0, 0, 1}};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(j["index_to_lps"][r][c].get<double>(), expected[r][c], 1e-12) << r << "," << c;
    EXPECT_EQ(j["range"].size(), 2u);
    EXPECT_GT(j["memory_bytes"].get<double>(), 0);
}

TEST(Cli, InfoHumanReadable) {
    const auto r = test::run_command(test::cli() + " info " + test::data("headsq.mhd"));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("64 x 64 x 93"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("index -> LPS"), std::string::npos) << r.out;
}

TEST(Cli, ErrorsNameTheFileAndExitNonZero) {
    const auto r = test::run_command(test::cli() + " info /no/such/file.nrrd", true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("/no/such/file.nrrd"), std::string::npos) << r.out;
    const auto u = test::run_command(test::cli() + " info", true);
    EXPECT_NE(u.exit_code, 0);
    const auto m = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") + " -o /tmp/x.stl", true);
    EXPECT_EQ(m.exit_code, 1);
    EXPECT_NE(m.out.find("--iso"), std::string::npos) << m.out;
}

TEST(Cli, MeshWritesSkinAndBoneInLps) {
    TempDir dir;
    const auto r = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 500 --iso 1150 -o " + (dir / "head.stl"));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const Mesh skin = load_mesh(dir / "head-iso500.stl"), bone = load_mesh(dir / "head-iso1150.stl");
    const auto s = mesh_stats(skin), b = mesh_stats(bone);
    EXPECT_GT(s.triangles, 10000u);
    EXPECT_GT(b.triangles, 10000u);
    EXPECT_GT(s.volume, b.volume) << "the skin encloses more than the bone";
    EXPECT_GT(b.volume, 0.0) << "outward-facing triangles (the affine is a rotation, no winding flip)";
    // Inside the volume's extent in LPS: i runs to the right (-x), j to
    // posterior (+y), k to inferior (-z) from the origin at voxel 0.
    for (const auto& m : {s, b}) {
        EXPECT_GE(m.bounds_min.x, -63 * 3.2 - 1e-3);
        EXPECT_LE(m.bounds_max.x, 1e-3);
        EXPECT_GE(m.bounds_min.y, -1e-3);
        EXPECT_LE(m.bounds_max.y, 63 * 3.2 + 1e-3);
        EXPECT_GE(m.bounds_min.z, -92 * 1.5 - 1e-3);
        EXPECT_LE(m.bounds_max.z, 1e-3);
    }
    // Post-processing options reach the mesh.
    const auto d = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 500 --decimate 0.5 --smooth 0.3 --largest -o " +
                                     (dir / "dec.ply"));
    ASSERT_EQ(d.exit_code, 0) << d.out;
    EXPECT_LT(mesh_stats(load_mesh(dir / "dec.ply")).triangles, s.triangles * 0.6);
    // An iso value outside the range: empty mesh, reported.
    const auto e = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 99999 -o " + (dir / "e.obj"), true);
    EXPECT_EQ(e.exit_code, 0) << e.out;
    EXPECT_NE(e.out.find("outside the volume's value range"), std::string::npos) << e.out;
}

TEST(Cli, MeshRefusesBadOutputBeforeWorking) {
    const auto r = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 500 -o /no/such/dir/x.stl", true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("does not exist"), std::string::npos) << r.out;
}
