// `isoscope mesh --stream / --memory` and `isoscope info --header-only`, run
// as real processes on the bundled CT (headsq.nhdr, 64 x 64 x 93 int16, raw
// data beside the header): the streamed files equal the in-memory ones.
// Tolerances: triangle and vertex counts exact; area and volume to 1e-9
// relative (another summation order); positions exact (same arithmetic).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "io/mesh.hpp"
#include "io/volume_io.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
using iso::test::read_file;
namespace fs = std::filesystem;

namespace {
std::vector<std::array<float, 3>> sorted_positions(const Mesh& m) {
    std::vector<std::array<float, 3>> p;
    for (const auto& v : m.positions) p.push_back({v.x, v.y, v.z});
    std::sort(p.begin(), p.end());
    return p;
}
} // namespace

TEST(StreamCli, MeshStreamEqualsInMemory) {
    TempDir dir;
    const std::string in = test::data("headsq.nhdr");
    const auto ref = test::run_command(test::cli() + " mesh " + in + " --iso 500 --iso 1150 -o " + (dir / "ref.ply"), true);
    ASSERT_EQ(ref.exit_code, 0) << ref.out;
    // 2 MiB with 16-cell chunks: several slabs (the volume is 0.7 MiB, so --stream forces streaming).
    const auto r = test::run_command(test::cli() + " mesh " + in + " --iso 500 --iso 1150 --stream --memory 2 --chunk 16 -o " +
                                         (dir / "s.ply"),
                                     true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("streamed:"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("peak memory"), std::string::npos) << r.out;
    for (const char* v : {"500", "1150"}) {
        SCOPED_TRACE(v);
        const Mesh a = load_mesh(dir / ("ref-iso" + std::string(v) + ".ply")), b = load_mesh(dir / ("s-iso" + std::string(v) + ".ply"));
        const auto sa = mesh_stats(a), sb = mesh_stats(b);
        EXPECT_GT(sa.triangles, 10000u);
        EXPECT_EQ(sb.triangles, sa.triangles);
        EXPECT_EQ(sb.vertices, sa.vertices);
        EXPECT_NEAR(sb.area, sa.area, 1e-9 * sa.area);
        EXPECT_NEAR(sb.volume, sa.volume, 1e-9 * std::abs(sa.volume));
        EXPECT_TRUE(sorted_positions(a) == sorted_positions(b));
        // The printed summary line is the in-memory one's.
        const std::string line = "iso " + std::string(v) + ": " + std::to_string(sa.triangles) + " triangles, " +
                                 std::to_string(sa.vertices) + " vertices";
        EXPECT_NE(ref.out.find(line), std::string::npos) << ref.out;
        EXPECT_NE(r.out.find(line), std::string::npos) << r.out;
    }
    // A budget below the volume's size streams without --stream; .pvtp pieces.
    const auto p = test::run_command(test::cli() + " mesh " + in + " --iso 500 --memory 0.5 --chunk 8 -o " + (dir / "p.pvtp"), true);
    ASSERT_EQ(p.exit_code, 0) << p.out;
    EXPECT_NE(p.out.find("streamed:"), std::string::npos) << p.out;
    EXPECT_TRUE(fs::exists(dir / "p.pvtp"));
    EXPECT_TRUE(fs::exists(dir / "p_0.vtp"));
}

TEST(StreamCli, PostProcessingAndBadInputAreClearErrors) {
    TempDir dir;
    const std::string in = test::data("headsq.nhdr");
    for (const char* flag : {"--smooth 0.5", "--decimate 0.5", "--largest"}) {
        const auto r = test::run_command(test::cli() + " mesh " + in + " --iso 500 --stream " + flag + " -o " + (dir / "x.stl"), true);
        EXPECT_EQ(r.exit_code, 1) << flag;
        EXPECT_NE(r.out.find(std::string(flag).substr(0, std::string(flag).find(' '))), std::string::npos) << r.out;
        EXPECT_FALSE(fs::exists(dir / "x.stl"));
    }
    // A truncated raw file: the error names it, nothing is written.
    {
        std::ofstream h(dir / "cut.nhdr");
        h << "NRRD0004\ntype: short\ndimension: 3\nsizes: 64 64 93\nencoding: raw\nendian: little\ndata file: cut.raw\n";
        std::ofstream d(dir / "cut.raw", std::ios::binary);
        std::vector<char> bytes(64 * 64 * 50 * 2, 0);
        d.write(bytes.data(), std::streamsize(bytes.size()));
    }
    const auto t = test::run_command(test::cli() + " mesh " + (dir / "cut.nhdr") + " --iso 500 --stream -o " + (dir / "x.ply"), true);
    EXPECT_EQ(t.exit_code, 1);
    EXPECT_NE(t.out.find("cut.nhdr"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("truncated"), std::string::npos) << t.out;
    EXPECT_FALSE(fs::exists(dir / "x.ply"));
    const auto v = test::run_command(test::cli() + " mesh " + in + " --iso 500 --stream -o " + (dir / "x.vtp"), true);
    EXPECT_EQ(v.exit_code, 1);
    EXPECT_NE(v.out.find(".pvtp"), std::string::npos) << v.out;
}

TEST(StreamCli, InfoReadsOnlyTheHeader) {
    TempDir dir;
    const auto full = test::run_command(test::cli() + " info " + test::data("headsq.nhdr") + " --json");
    ASSERT_EQ(full.exit_code, 0) << full.out;
    const auto jf = nlohmann::json::parse(full.out);
    // A copy of the header and its data file.
    fs::copy_file(test::data("headsq.nhdr"), dir / "h.nhdr");
    {
        const std::string text = read_file(test::data("headsq.nhdr"));
        const auto at = text.find("data file:");
        ASSERT_NE(at, std::string::npos);
        const auto eol = text.find('\n', at);
        const std::string data_name = text.substr(at + 10, eol - at - 10);
        const fs::path data_path = fs::path(test::data("headsq.nhdr")).parent_path() / data_name.substr(data_name.find_first_not_of(' '));
        fs::copy_file(data_path, dir / data_path.filename());
    }
    for (const std::string args : {" --header-only --json", " --memory 0.1 --json"}) {
        SCOPED_TRACE(args);
        const auto r = test::run_command(test::cli() + " info " + (dir / "h.nhdr") + args);
        ASSERT_EQ(r.exit_code, 0) << r.out;
        const auto j = nlohmann::json::parse(r.out);
        EXPECT_TRUE(j["range"].is_null());
        EXPECT_EQ(j["range_read"], false);
        EXPECT_EQ(j["dims"], jf["dims"]);
        EXPECT_EQ(j["type"], jf["type"]);
        EXPECT_EQ(j["index_to_lps"], jf["index_to_lps"]);
    }
    const auto h = test::run_command(test::cli() + " info " + (dir / "h.nhdr") + " --header-only");
    ASSERT_EQ(h.exit_code, 0) << h.out;
    EXPECT_NE(h.out.find("not read (header only)"), std::string::npos) << h.out;
}

// The bundled CT as OpenVDB: `info --header-only` reads its grid's metadata
// and topology (the geometry of the whole read, no range), and a budget below
// twice the grid streams it slab by slab through the reading child; the
// surface is the in-memory one.
TEST(StreamCli, OpenVdbHeaderAndSlabs) {
    TempDir dir;
    save_volume(load_volume(test::data("headsq.nhdr")), dir / "h.vdb");
    const auto full = test::run_command(test::cli() + " info " + (dir / "h.vdb") + " --json");
    ASSERT_EQ(full.exit_code, 0) << full.out;
    const auto jf = nlohmann::json::parse(full.out);
    const auto hr = test::run_command(test::cli() + " info " + (dir / "h.vdb") + " --header-only --json");
    ASSERT_EQ(hr.exit_code, 0) << hr.out;
    const auto jh = nlohmann::json::parse(hr.out);
    EXPECT_TRUE(jh["range"].is_null());
    EXPECT_EQ(jh["dims"], jf["dims"]);
    EXPECT_EQ(jh["index_to_lps"], jf["index_to_lps"]);
    EXPECT_EQ(jh["grid"], "density");
    EXPECT_GT(jh["topology_bytes"].get<double>(), 0.0);
    EXPECT_LT(jh["topology_bytes"].get<double>(), jh["memory_bytes"].get<double>());
    const auto ref = test::run_command(test::cli() + " mesh " + (dir / "h.vdb") + " --iso 500 -o " + (dir / "ref.ply"), true);
    ASSERT_EQ(ref.exit_code, 0) << ref.out;
    EXPECT_EQ(ref.out.find("streamed:"), std::string::npos) << ref.out;
    const auto r = test::run_command(test::cli() + " mesh " + (dir / "h.vdb") + " --iso 500 --memory 2.8 --chunk 8 -o " + (dir / "s.ply"), true);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("streamed:"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("OpenVDB reader process peak"), std::string::npos) << r.out;
    const Mesh a = load_mesh(dir / "ref.ply"), b = load_mesh(dir / "s.ply");
    const auto sa = mesh_stats(a), sb = mesh_stats(b);
    EXPECT_GT(sa.triangles, 10000u);
    EXPECT_EQ(sb.triangles, sa.triangles);
    EXPECT_EQ(sb.vertices, sa.vertices);
    EXPECT_NEAR(sb.area, sa.area, 1e-9 * sa.area);
    EXPECT_TRUE(sorted_positions(a) == sorted_positions(b));
}

// `--no-overlap` runs the steps one after another (taller slabs for the same
// budget): the same files, byte for byte, and the steps line says which ran.
TEST(StreamCli, NoOverlapWritesTheSameFiles) {
    TempDir dir;
    const std::string in = test::data("headsq.nhdr");
    for (const char* ext : {".ply", ".stl"}) {
        SCOPED_TRACE(ext);
        const std::string common = test::cli() + " mesh " + in + " --iso 500 --stream --memory 6 --chunk 8 -o ";
        const auto on = test::run_command(common + (dir / ("on" + std::string(ext))), true);
        const auto off = test::run_command(common + (dir / ("off" + std::string(ext))) + " --no-overlap", true);
        ASSERT_EQ(on.exit_code, 0) << on.out;
        ASSERT_EQ(off.exit_code, 0) << off.out;
        EXPECT_NE(on.out.find("streaming steps (busy seconds, overlapped)"), std::string::npos) << on.out;
        EXPECT_NE(off.out.find("streaming steps (busy seconds)"), std::string::npos) << off.out;
        const std::string a = read_file(dir / ("on" + std::string(ext))), b = read_file(dir / ("off" + std::string(ext)));
        EXPECT_GT(a.size(), 100000u);
        EXPECT_TRUE(a == b) << "the files differ";
    }
}
