// `isoscope mesh --stream / --memory` and `isoscope info --header-only`, run
// as real processes on the bundled CT (headsq.nhdr, 64 x 64 x 93 int16, raw
// data beside the header): the streamed files equal the in-memory ones.
// Tolerances: triangle and vertex counts exact; area and volume to 1e-9
// relative (another summation order); positions exact (same arithmetic).
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "io/mesh.hpp"
#include "io/volume_io.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::read_file;
using iso::test::TempDir;
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
    const auto ref =
        test::run_command(test::cli() + " mesh " + in + " --iso 500 --iso 1150 --json -o " + (dir / "ref.ply"));
    ASSERT_EQ(ref.exit_code, 0) << ref.out;
    // 2 MiB with 16-cell chunks: several slabs (the volume is 0.7 MiB, so --stream forces streaming).
    const auto r =
        test::run_command(test::cli() + " mesh " + in +
                          " --iso 500 --iso 1150 --stream --memory 2 --chunk 16 --json -o " + (dir / "s.ply"));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto jr = nlohmann::json::parse(ref.out), js = nlohmann::json::parse(r.out);
    EXPECT_EQ(jr["route"], "in memory");
    EXPECT_EQ(js["route"], "streamed");
    ASSERT_TRUE(js["streaming"].is_object()) << r.out;
    EXPECT_GT(js["streaming"]["engine_peak_bytes"].get<double>(), 0.0);
    EXPECT_EQ(js["streaming"]["memory_budget_bytes"], 2u << 20);
    ASSERT_EQ(jr["surfaces"].size(), 2u);
    ASSERT_EQ(js["surfaces"].size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        const std::string v = i == 0 ? "500" : "1150";
        SCOPED_TRACE(v);
        const Mesh a = load_mesh(dir / ("ref-iso" + v + ".ply")), b = load_mesh(dir / ("s-iso" + v + ".ply"));
        const auto sa = mesh_stats(a), sb = mesh_stats(b);
        EXPECT_GT(sa.triangles, 10000u);
        EXPECT_EQ(sb.triangles, sa.triangles);
        EXPECT_EQ(sb.vertices, sa.vertices);
        EXPECT_NEAR(sb.area, sa.area, 1e-9 * sa.area);
        EXPECT_NEAR(sb.volume, sa.volume, 1e-9 * std::abs(sa.volume));
        EXPECT_TRUE(sorted_positions(a) == sorted_positions(b));
        // The summary is the in-memory one's.
        for (const auto* j : {&jr, &js}) {
            const auto& sj = (*j)["surfaces"][i];
            EXPECT_EQ(sj["name"], "iso " + v);
            EXPECT_EQ(sj["triangles"], sa.triangles);
            EXPECT_EQ(sj["vertices"], sa.vertices);
            EXPECT_NEAR(sj["area_mm2"].get<double>(), sa.area, 1e-9 * sa.area);
        }
        EXPECT_EQ(js["surfaces"][i]["path"], (dir / ("s-iso" + v + ".ply")));
    }
    // A budget below the volume's size streams without --stream; .pvtp pieces.
    const auto p = test::run_command(
        test::cli() + " mesh " + in + " --iso 500 --memory 0.5 --chunk 8 -o " + (dir / "p.pvtp"), true);
    ASSERT_EQ(p.exit_code, 0) << p.out;
    EXPECT_NE(p.out.find("streamed:"), std::string::npos) << p.out;
    EXPECT_NE(p.out.find("peak memory"), std::string::npos) << p.out;
    EXPECT_NE(
        p.out.find("iso 500: " + std::to_string(jr["surfaces"][0]["triangles"].get<std::size_t>()) + " triangles, "),
        std::string::npos)
        << p.out;
    EXPECT_NE(p.out.find(", open, volume not known"), std::string::npos)
        << "no volume for an open surface streamed: " << p.out;
    EXPECT_TRUE(fs::exists(dir / "p.pvtp"));
    EXPECT_TRUE(fs::exists(dir / "p_0.vtp"));
}

TEST(StreamCli, PostProcessingAndBadInputAreClearErrors) {
    TempDir dir;
    const std::string in = test::data("headsq.nhdr");
    for (const char* flag : {"--smooth 0.5", "--decimate 0.5", "--largest"}) {
        const auto r = test::run_command(
            test::cli() + " mesh " + in + " --iso 500 --stream " + flag + " -o " + (dir / "x.stl"), true);
        EXPECT_EQ(r.exit_code, 1) << flag;
        EXPECT_NE(r.out.find(std::string(flag).substr(0, std::string(flag).find(' '))), std::string::npos) << r.out;
        EXPECT_FALSE(fs::exists(dir / "x.stl"));
    }
    // A truncated raw file: the error names it, nothing is written.
    {
        std::ofstream h(dir / "cut.nhdr");
        h << "NRRD0004\ntype: short\ndimension: 3\nsizes: 64 64 93\nencoding: raw\nendian: little\ndata file: "
             "cut.raw\n";
        std::ofstream d(dir / "cut.raw", std::ios::binary);
        std::vector<char> bytes(64 * 64 * 50 * 2, 0);
        d.write(bytes.data(), std::streamsize(bytes.size()));
    }
    const auto t = test::run_command(
        test::cli() + " mesh " + (dir / "cut.nhdr") + " --iso 500 --stream -o " + (dir / "x.ply"), true);
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
        const fs::path data_path =
            fs::path(test::data("headsq.nhdr")).parent_path() / data_name.substr(data_name.find_first_not_of(' '));
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
    const auto ref =
        test::run_command(test::cli() + " mesh " + (dir / "h.vdb") + " --iso 500 --json -o " + (dir / "ref.ply"));
    ASSERT_EQ(ref.exit_code, 0) << ref.out;
    EXPECT_EQ(nlohmann::json::parse(ref.out)["route"], "in memory");
    const auto r = test::run_command(test::cli() + " mesh " + (dir / "h.vdb") +
                                     " --iso 500 --memory 2.8 --chunk 8 --json -o " + (dir / "s.ply"));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto js = nlohmann::json::parse(r.out);
    EXPECT_EQ(js["route"], "streamed");
    EXPECT_GT(js["streaming"]["reader_peak_bytes"].get<double>(), 0.0) << "read slab by slab through the reading child";
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
        const auto on = test::run_command(common + (dir / ("on" + std::string(ext))) + " --json");
        const auto off = test::run_command(common + (dir / ("off" + std::string(ext))) + " --no-overlap --json");
        ASSERT_EQ(on.exit_code, 0) << on.out;
        ASSERT_EQ(off.exit_code, 0) << off.out;
        EXPECT_EQ(nlohmann::json::parse(on.out)["streaming"]["overlapped"], true) << on.out;
        EXPECT_EQ(nlohmann::json::parse(off.out)["streaming"]["overlapped"], false) << off.out;
        const std::string a = read_file(dir / ("on" + std::string(ext))),
                          b = read_file(dir / ("off" + std::string(ext)));
        EXPECT_GT(a.size(), 100000u);
        EXPECT_TRUE(a == b) << "the files differ";
    }
}

// A closed surface (a ball inside the grid): `mesh --json` gives its
// enclosed volume, `measure`'s, in memory and streamed alike; the streamed
// numbers are the in-memory ones. An open surface streamed (the bundled
// CT's skin) has no volume: its pieces' statistics have no caps.
TEST(StreamCli, MeshJsonStreamedEqualsInMemory) {
    TempDir dir;
    {
        const std::array<std::int64_t, 3> d{40, 36, 44};
        Volume v = Volume::dense(d, VoxelType::I16,
                                 make_affine(glm::dvec3(0.9, 1.0, 1.1), glm::dvec3(5, -3, 2), glm::dmat3(1.0)));
        auto s = v.as<std::int16_t>();
        for (std::int64_t k = 0; k < d[2]; ++k)
            for (std::int64_t j = 0; j < d[1]; ++j)
                for (std::int64_t i = 0; i < d[0]; ++i)
                    s[v.linear_index(i, j, k)] = std::int16_t(
                        std::clamp(500.0 + 100.0 * (13.5 - glm::length(glm::dvec3(i, j, k) - glm::dvec3(19, 18, 21))),
                                   0.0, 1000.0));
        save_volume(v, dir / "ball.nhdr", false);
    }
    const std::string ball = dir / "ball.nhdr";
    const auto mem = test::run_command(test::cli() + " mesh " + ball + " --iso 500 --json -o " + (dir / "m.ply"));
    const auto str = test::run_command(test::cli() + " mesh " + ball +
                                       " --iso 500 --json --stream --memory 0.3 --chunk 8 -o " + (dir / "s.ply"));
    const auto mea = test::run_command(test::cli() + " measure " + ball + " --iso 500 --json");
    ASSERT_EQ(mem.exit_code, 0) << mem.out;
    ASSERT_EQ(str.exit_code, 0) << str.out;
    ASSERT_EQ(mea.exit_code, 0) << mea.out;
    const auto jm = nlohmann::json::parse(mem.out), js = nlohmann::json::parse(str.out),
               jq = nlohmann::json::parse(mea.out);
    EXPECT_EQ(js["route"], "streamed");
    ASSERT_TRUE(js["streaming"].is_object());
    // Each step's busy seconds at the top level on both routes (the streamed
    // route's also under "streaming"); the summaries' time is the analysis.
    EXPECT_EQ(js["busy_seconds"], js["streaming"]["busy_seconds"]);
    for (const char* step : {"index", "read", "extract", "weld", "write", "analysis", "extraction_waited"})
        EXPECT_TRUE(js["busy_seconds"][step].is_number()) << step;
    EXPECT_GT(js["busy_seconds"]["analysis"].get<double>(), 0.0);
    for (const char* step : {"read", "index", "extract", "weld", "write", "analysis"})
        EXPECT_TRUE(jm["busy_seconds"][step].is_number()) << step;
    EXPECT_GT(js["streaming"]["slabs_read"].get<int>(), 1) << "several slabs";
    const auto& a = jm["surfaces"][0];
    const auto& b = js["surfaces"][0];
    EXPECT_EQ(a["closed"], true);
    EXPECT_EQ(a["volume_kind"], "enclosed");
    EXPECT_EQ(a["volume_ml"].get<double>(), jq["surfaces"][0]["volume_ml"].get<double>())
        << "measure's enclosed volume";
    EXPECT_NEAR(a["volume_ml"].get<double>(), 4.0 / 3.0 * M_PI * std::pow(13.5, 3) * 0.99 / 1000.0,
                0.02 * a["volume_ml"].get<double>());
    for (const char* key : {"triangles", "vertices", "closed", "boundary_edges", "volume_kind"})
        EXPECT_EQ(b[key], a[key]) << key;
    EXPECT_EQ(b["components"]["count"], a["components"]["count"]);
    EXPECT_EQ(b["components"]["largest"]["triangles"], a["components"]["largest"]["triangles"]);
    for (const char* key : {"area_mm2", "volume_ml"})
        EXPECT_NEAR(b[key].get<double>(), a[key].get<double>(), 1e-9 * a[key].get<double>()) << key;
    EXPECT_NEAR(b["components"]["largest"]["volume_ml"].get<double>(), a["volume_ml"].get<double>(),
                1e-9 * a["volume_ml"].get<double>());
    // The skin, open at the neck: the same counts, no volume where streamed.
    const std::string in = test::data("headsq.nhdr");
    const auto om = test::run_command(test::cli() + " mesh " + in + " --iso 500 --json -o " + (dir / "om.ply"));
    const auto os = test::run_command(test::cli() + " mesh " + in +
                                      " --iso 500 --json --stream --memory 2 --chunk 16 -o " + (dir / "os.ply"));
    ASSERT_EQ(om.exit_code, 0) << om.out;
    ASSERT_EQ(os.exit_code, 0) << os.out;
    const auto jom = nlohmann::json::parse(om.out), jos = nlohmann::json::parse(os.out);
    const auto& c = jom["surfaces"][0];
    const auto& o = jos["surfaces"][0];
    for (const char* key : {"triangles", "vertices", "closed", "boundary_edges"}) EXPECT_EQ(o[key], c[key]) << key;
    EXPECT_EQ(o["components"]["count"], c["components"]["count"]);
    EXPECT_NEAR(o["area_mm2"].get<double>(), c["area_mm2"].get<double>(), 1e-9 * c["area_mm2"].get<double>());
    EXPECT_EQ(c["volume_kind"], "lower bound");
    EXPECT_TRUE(o["volume_ml"].is_null());
    EXPECT_TRUE(o["volume_kind"].is_null());
    EXPECT_TRUE(o["components"]["largest"]["volume_ml"].is_null()) << "no volume for a component of an open surface";
}
