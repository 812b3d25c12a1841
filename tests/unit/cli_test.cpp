// The isoscope command line, run as a real process on the bundled data.
#include <cstring>
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
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(j["index_to_lps"][r][c].get<double>(), expected[r][c], 1e-12) << r << "," << c;
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
    const auto r = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 500 --iso 1150 -o " +
                                     (dir / "head.stl"));
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
    const auto d = test::run_command(test::cli() + " mesh " + test::data("headsq.nhdr") +
                                     " --iso 500 --decimate 0.5 --smooth 0.3 --largest -o " + (dir / "dec.ply"));
    ASSERT_EQ(d.exit_code, 0) << d.out;
    EXPECT_LT(mesh_stats(load_mesh(dir / "dec.ply")).triangles, s.triangles * 0.6);
    // An iso value outside the range: empty mesh, reported.
    const auto e = test::run_command(
        test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 99999 -o " + (dir / "e.obj"), true);
    EXPECT_EQ(e.exit_code, 0) << e.out;
    EXPECT_NE(e.out.find("outside the volume's value range"), std::string::npos) << e.out;
}

TEST(Cli, MeshRefusesBadOutputBeforeWorking) {
    const auto r = test::run_command(
        test::cli() + " mesh " + test::data("headsq.nhdr") + " --iso 500 -o /no/such/dir/x.stl", true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("does not exist"), std::string::npos) << r.out;
}

// `mesh --json` gives a volume only where it means what it says: the bundled
// CT's skin at 500 is open at the neck, so its volume is the lower bound
// that `measure` gives for the same surface, flagged as such, and equal to it.
TEST(Cli, MeshJsonOpenSurfaceVolumeIsMeasuresLowerBound) {
    TempDir dir;
    const std::string in = test::data("headsq.nhdr");
    const auto m = test::run_command(test::cli() + " mesh " + in + " --iso 500 --json -o " + (dir / "skin.ply"));
    ASSERT_EQ(m.exit_code, 0) << m.out;
    const auto mj = nlohmann::json::parse(m.out);
    const auto ms = test::run_command(test::cli() + " measure " + in + " --iso 500 --json");
    ASSERT_EQ(ms.exit_code, 0) << ms.out;
    const auto sj = nlohmann::json::parse(ms.out);
    EXPECT_EQ(mj["route"], "in memory");
    EXPECT_TRUE(mj["streaming"].is_null());
    // Each step's busy seconds, as the streamed route reports its own.
    for (const char* step : {"read", "index", "extract", "weld", "postprocess", "write", "analysis"}) {
        ASSERT_TRUE(mj["busy_seconds"][step].is_number()) << step;
        EXPECT_GE(mj["busy_seconds"][step].get<double>(), 0.0) << step;
    }
    EXPECT_GT(mj["busy_seconds"]["extract"].get<double>(), 0.0);
    ASSERT_EQ(mj["surfaces"].size(), 1u);
    ASSERT_EQ(sj["surfaces"].size(), 1u);
    const auto& a = mj["surfaces"][0];
    const auto& b = sj["surfaces"][0];
    EXPECT_EQ(a["name"], "iso 500");
    EXPECT_EQ(a["iso"], 500.0);
    EXPECT_EQ(a["path"], (dir / "skin.ply"));
    EXPECT_EQ(a["closed"], false);
    EXPECT_EQ(b["closed"], false);
    EXPECT_GT(a["boundary_edges"].get<std::size_t>(), 0u);
    EXPECT_EQ(a["boundary_edges"], b["boundary"]["edges"]);
    EXPECT_EQ(a["volume_kind"], "lower bound");
    EXPECT_EQ(a["volume_kind"], b["volume_kind"]);
    ASSERT_TRUE(a["volume_ml"].is_number());
    EXPECT_EQ(a["volume_ml"].get<double>(), b["volume_ml"].get<double>());
    EXPECT_NEAR(a["volume_mm3"].get<double>(), 1000.0 * b["volume_ml"].get<double>(),
                1e-9 * a["volume_mm3"].get<double>());
    EXPECT_EQ(a["triangles"], b["triangles"]);
    EXPECT_EQ(a["area_mm2"].get<double>(), b["area_mm2"].get<double>());
    EXPECT_EQ(a["components"]["count"].get<std::size_t>(), b["components"].size());
    EXPECT_TRUE(a["components"]["largest"]["volume_ml"].is_null()) << "no volume for a component of an open surface";
    // The file written is the surface measured.
    EXPECT_EQ(mesh_stats(load_mesh(dir / "skin.ply")).triangles, a["triangles"].get<std::size_t>());
    // The text summary says the same: open, a lower bound, never a plain volume.
    const auto t = test::run_command(test::cli() + " mesh " + in + " --iso 500 -o " + (dir / "skin.stl"));
    ASSERT_EQ(t.exit_code, 0) << t.out;
    EXPECT_NE(t.out.find("iso 500: " + std::to_string(a["triangles"].get<std::size_t>()) + " triangles"),
              std::string::npos)
        << t.out;
    EXPECT_NE(t.out.find(", open, volume >= "), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("(lower bound"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("steps (busy seconds): read "), std::string::npos) << t.out;
}

// --version: isoscope's own, then each library's as the installed Debian
// package says it (the package's upstream version begins with it).
TEST(Cli, VersionNamesTheLibrariesAsInstalled) {
    const auto r = test::run_command(test::cli() + " --version");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_EQ(r.out.rfind("isoscope ", 0), 0u) << r.out;
    // The commit it was built from, as git says (when the sources are a git checkout).
    const auto git = test::run_command("git -C " ISOSCOPE_SOURCE_DIR " rev-parse --short=12 HEAD 2>/dev/null");
    if (git.exit_code == 0 && git.out.size() > 12) {
        const std::string commit = git.out.substr(0, 12);
        EXPECT_NE(r.out.substr(0, r.out.find('\n')).find("(commit " + commit), std::string::npos) << r.out;
    }
    const std::pair<const char*, const char*> packages[] = {{"VTK", "libvtk9.1"},
                                                            {"OpenVDB", "libopenvdb10.0"},
                                                            {"Embree", "libembree3-3"},
                                                            {"oneTBB", "libtbb12"},
                                                            {"OpenImageIO", "libopenimageio2.4"}};
    for (const auto& [name, package] : packages) {
        const auto at = r.out.find(std::string("\n") + name + " ");
        ASSERT_NE(at, std::string::npos) << name << " missing: " << r.out;
        const std::size_t from = at + 2 + std::strlen(name);
        const std::string version = r.out.substr(from, r.out.find('\n', from) - from);
        const auto dpkg = test::run_command(std::string("dpkg-query -W -f '${Version}' ") + package);
        if (dpkg.exit_code != 0) continue; // not a Debian system: nothing to compare with
        std::string upstream = dpkg.out.substr(0, dpkg.out.find_first_of("+-"));
        if (const auto really = dpkg.out.find("really"); really != std::string::npos) // 9.1.0+really9.1.0+dfsg2-5
            upstream = dpkg.out.substr(really + 6, dpkg.out.find_first_of("+-", really) - really - 6);
        EXPECT_EQ(upstream.rfind(version, 0), 0u)
            << name << " says " << version << ", " << package << " is " << dpkg.out;
    }
}

TEST(Cli, AJpeg2000SeriesPrintsNoFloodOfLibraryMessages) {
    // The bundled MR series re-encoded as JPEG 2000 (GDCM's gdcmconv, from
    // ./setup.sh --tests): GDCM says "Encapsulated stream has more bits
    // actually stored on disk. correcting." for every file. It decodes in a
    // child process whose messages come back as one warning with a count:
    // nothing on stderr, one line on stdout.
    test::TempDir dir;
    std::filesystem::create_directories(dir / "j2k");
    for (int i = 1; i <= 3; ++i) {
        const std::string name = "1-" + std::to_string(i) + ".dcm";
        const auto c = test::run_command(
            "gdcmconv --j2k " + test::data("dicom-mr-forearm/" + name) + " " + (dir / ("j2k/" + name)), true);
        ASSERT_EQ(c.exit_code, 0) << "gdcmconv (./setup.sh --tests installs libgdcm-tools): " << c.out;
    }
    const auto err = test::run_command(test::cli() + " info " + (dir / "j2k") + " 2>&1 >/dev/null");
    EXPECT_EQ(err.exit_code, 0);
    EXPECT_EQ(err.out, "") << "stderr of isoscope info";
    const auto out = test::run_command(test::cli() + " info " + (dir / "j2k"));
    std::size_t gdcm = 0, pos = 0;
    while ((pos = out.out.find("the DICOM decoder (GDCM) said", pos)) != std::string::npos) ++gdcm, ++pos;
    EXPECT_EQ(gdcm, 1u) << out.out;
    EXPECT_NE(out.out.find("said 3 times"), std::string::npos) << out.out;
    // The voxels are the uncompressed series' (JPEG 2000 lossless).
    const auto a = test::run_command(test::cli() + " info --json " + (dir / "j2k"));
    const auto b = test::run_command(test::cli() + " info --json " + test::data("dicom-mr-forearm"));
    EXPECT_EQ(nlohmann::json::parse(a.out)["range"], nlohmann::json::parse(b.out)["range"]);
}
