// `mpirun -np N isoscope mesh ... -o out.pvtp` as a real job (label mpi): the
// volumes are written with the real writers, the CLI runs under OpenMPI's
// mpirun (--oversubscribe: more ranks than this machine's cores), and the
// .pvtp is read back with VTK's vtkXMLPPolyDataReader and compared with the
// single-process extraction of the same file (written as .vtp by the CLI).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include <unistd.h>

#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <vtkCleanPolyData.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkXMLPPolyDataReader.h>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "io/volume_io.hpp"
#include "io/vtk_mesh.hpp"
#include "renderer/surface/components.hpp"
#include "renderer/surface/analysis.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

// mpirun refuses to run as root unless told; only then is it told.
std::string mpirun(int n) {
    std::string cmd =
        std::string("timeout 60 ") + ISOSCOPE_MPIRUN + " --oversubscribe --bind-to none -np " + std::to_string(n);
    if (::getuid() == 0) cmd += " --allow-run-as-root";
    return cmd + " ";
}

// An int16 CT-like volume (oblique-free, anisotropic): a torus around the
// j axis (one component that every k cut crosses twice) and a ball (a
// second component), 0 outside and 1000 inside with a linear ramp.
Volume phantom(std::array<std::int64_t, 3> d) {
    const glm::dmat4 a = make_affine(glm::dvec3(0.8, 0.9, 1.1), glm::dvec3(-20, 5, 7), glm::dmat3(1.0));
    Volume v = Volume::dense(d, VoxelType::I16, a);
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const glm::dvec3 p(i * 0.8 - 20.0, j * 0.9 - 14.0, k * 1.1 - 22.0);
                const double ring = std::hypot(p.x, p.z) - 12.0;
                const double torus = 4.0 - std::hypot(ring, p.y);
                const double ball = 3.5 - glm::length(p - glm::dvec3(0.0, 8.0, 0.0));
                const double dist = std::max(torus, ball);
                s[v.linear_index(i, j, k)] = std::int16_t(std::clamp(500.0 + 250.0 * dist, 0.0, 1000.0));
            }
    return v;
}

// One surface read back: the .pvtp's pieces appended (seam vertices twice),
// and welded by position with vtkCleanPolyData (tolerance 0: bit-identical
// coordinates only), as docs/cluster.md tells readers to.
struct ReadBack {
    int pieces = 0;
    Mesh raw, welded;
};
ReadBack read_pvtp(const std::string& path) {
    ReadBack r;
    vtkNew<vtkXMLPPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    r.pieces = reader->GetNumberOfPieces();
    r.raw = from_polydata(reader->GetOutput(), path);
    vtkNew<vtkCleanPolyData> clean;
    clean->SetInputConnection(reader->GetOutputPort());
    clean->SetTolerance(0.0);
    clean->PointMergingOn();
    clean->ConvertLinesToPointsOff();
    clean->ConvertPolysToLinesOff();
    clean->ConvertStripsToPolysOff();
    clean->Update();
    r.welded = from_polydata(clean->GetOutput(), path);
    return r;
}

struct Summary {
    std::size_t triangles = 0, vertices = 0, components = 0, largest = 0, boundary_edges = 0;
    double area = 0;
    bool closed = false;
    std::optional<double> volume_mm3; // a closed surface's only
};
// Rank 0's `mesh --json` (the other ranks print nothing): its surfaces.
std::vector<Summary> parse(const std::string& out) {
    std::vector<Summary> all;
    const auto j = nlohmann::json::parse(out);
    EXPECT_EQ(j["route"], "mpi");
    for (const auto& s : j["surfaces"]) {
        Summary m;
        m.triangles = s["triangles"];
        m.vertices = s["vertices"];
        m.area = s["area_mm2"];
        m.closed = s["closed"];
        m.boundary_edges = s["boundary_edges"];
        if (!s["volume_mm3"].is_null()) m.volume_mm3 = s["volume_mm3"].get<double>();
        m.components = s["components"]["count"];
        m.largest = s["components"]["largest"]["triangles"];
        all.push_back(m);
    }
    return all;
}

// Positions as exact keys.
std::multiset<std::array<float, 3>> positions(const Mesh& m) {
    std::multiset<std::array<float, 3>> s;
    for (const auto& p : m.positions) s.insert({p.x, p.y, p.z});
    return s;
}

// The slabs the ranks read, from rank 0's `mesh --json`.
int slabs_read(const std::string& out) {
    const auto j = nlohmann::json::parse(out);
    int n = 0;
    for (const auto& r : j["mpi"]["slabs_read"]) n += r.get<int>();
    return n;
}

// The single-process reference: the CLI's in-memory path, written as .vtp.
Mesh reference(const std::string& in, const std::string& args, const std::string& out) {
    const auto r = test::run_command(test::cli() + " mesh " + in + " " + args + " -o " + out, true);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return load_mesh(out);
}

// `pieces`: the .vtp files the .pvtp lists: one per slab that holds
// triangles, on every rank (empty slab pieces are neither written nor listed).
void expect_same_surface(const std::string& pvtp, const Mesh& ref, int pieces, const Summary& printed) {
    const ReadBack got = read_pvtp(pvtp);
    EXPECT_EQ(got.pieces, pieces) << "one piece per non-empty slab";
    EXPECT_EQ(got.raw.triangles.size(), ref.triangles.size());
    EXPECT_EQ(got.welded.positions.size(), ref.positions.size())
        << "welding the seams by exact position gives the single-process vertices";
    // Same vertices: the extraction is deterministic per edge, so positions are
    // bit-identical (tolerance 0 is tighter than the 1e-6 voxel asked).
    EXPECT_TRUE(positions(got.welded) == positions(ref)) << "vertex positions differ from the single process";
    const auto a = mesh_stats(got.welded), b = mesh_stats(ref);
    // Same triangles, summed in another order: 1e-9 relative.
    EXPECT_NEAR(a.area, b.area, 1e-9 * b.area);
    EXPECT_NEAR(a.volume, b.volume, 1e-9 * std::abs(b.volume));
    // The reduced statistics rank 0 printed (JSON: every digit).
    EXPECT_EQ(printed.triangles, ref.triangles.size());
    EXPECT_EQ(printed.vertices, ref.positions.size());
    EXPECT_NEAR(printed.area, b.area, 1e-9 * b.area);
    const SurfaceMeasures measured = measure_surface(ref);
    EXPECT_EQ(printed.closed, measured.closed);
    EXPECT_EQ(printed.boundary_edges, measured.boundary_edges);
    // A volume only where it is the enclosed one.
    EXPECT_EQ(printed.volume_mm3.has_value(), measured.closed);
    if (printed.volume_mm3) EXPECT_NEAR(*printed.volume_mm3, b.volume, 1e-9 * std::abs(b.volume));
    const SurfaceSummary whole = summarize_mesh(ref);
    EXPECT_EQ(printed.components, whole.components);
    EXPECT_EQ(printed.largest, whole.largest.triangles);
}

} // namespace

TEST(MpiMesh, OneTwoAndFourRanksEqualTheSingleProcess) {
    TempDir dir;
    const std::string in = dir / "phantom.nrrd";
    save_volume(phantom({56, 36, 48}), in, false);
    const Mesh ref = reference(in, "--iso 500", dir / "ref.vtp");
    ASSERT_GT(ref.triangles.size(), 2000u);
    ASSERT_EQ(summarize_mesh(ref).components, 2u) << "the torus and the ball";
    for (int n : {1, 2, 4}) {
        SCOPED_TRACE(n);
        const std::string out = dir / ("n" + std::to_string(n) + ".pvtp");
        const auto r =
            test::run_command(mpirun(n) + test::cli() + " mesh " + in + " --iso 500 --chunk 8 --json -o " + out);
        ASSERT_EQ(r.exit_code, 0) << r.out;
        const auto s = parse(r.out);
        ASSERT_EQ(s.size(), 1u) << "rank 0 alone prints the summary: " << r.out;
        EXPECT_TRUE(fs::exists(dir / ("n" + std::to_string(n)))) << "piece folder";
        expect_same_surface(out, ref, n, s[0]);
    }
    // A budget of a few slabs per rank: each rank writes one piece per slab,
    // welded across slab and rank seams only by the reader.
    {
        // Wide slices (160 x 120) so that a 1 MiB budget holds only a chunk
        // layer or two: several slabs, so several pieces, per rank.
        const std::string wide = dir / "wide.nrrd";
        save_volume(phantom({160, 120, 40}), wide, false);
        const Mesh wref = reference(wide, "--iso 500", dir / "wide.vtp");
        const std::string out = dir / "small.pvtp";
        const auto r = test::run_command(mpirun(2) + test::cli() + " mesh " + wide +
                                         " --iso 500 --chunk 8 --memory 1 --json -o " + out);
        ASSERT_EQ(r.exit_code, 0) << r.out;
        EXPECT_GT(slabs_read(r.out), 2) << "several slabs on some rank: " << r.out;
        const auto s = parse(r.out);
        ASSERT_EQ(s.size(), 1u) << r.out;
        const ReadBack got = read_pvtp(out);
        EXPECT_GT(got.pieces, 2) << "one piece per slab";
        expect_same_surface(out, wref, got.pieces, s[0]);
    }
    // Nothing left behind but the outputs: no staging folders.
    for (const auto& e : fs::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().filename().string().find(".isoscope-partial"), std::string::npos) << e.path();
}

// Each rank runs the streaming driver with its reading, extraction and
// writing overlapped (the default) or not (--no-overlap): both give the
// single-process surface. The budget is one at which the single process
// overlaps on this volume (its `mesh --json` says so).
TEST(MpiMesh, OverlappedAndSerialRanksEqualTheSingleProcess) {
    TempDir dir;
    const std::string wide = dir / "wide.nrrd";
    save_volume(phantom({160, 120, 40}), wide, false);
    const Mesh wref = reference(wide, "--iso 500", dir / "wide.vtp");
    const std::string budget = " --chunk 8 --memory 3";
    {
        const auto r = test::run_command(test::cli() + " mesh " + wide + " --iso 500 --stream" + budget +
                                         " --json -o " + (dir / "one.ply"));
        ASSERT_EQ(r.exit_code, 0) << r.out;
        EXPECT_EQ(nlohmann::json::parse(r.out)["streaming"]["overlapped"], true) << r.out;
    }
    for (const char* mode : {"", " --no-overlap"}) {
        SCOPED_TRACE(*mode ? "serial" : "overlapped");
        const std::string out = dir / (*mode ? "off.pvtp" : "on.pvtp");
        const auto r = test::run_command(mpirun(2) + test::cli() + " mesh " + wide + " --iso 500" + budget + mode +
                                         " --json -o " + out);
        ASSERT_EQ(r.exit_code, 0) << r.out;
        const auto s = parse(r.out);
        ASSERT_EQ(s.size(), 1u) << r.out;
        const ReadBack got = read_pvtp(out);
        if (!*mode) { // serial: taller slabs, maybe one per rank
            EXPECT_GT(got.pieces, 2) << "several slabs, so that the steps overlap";
        }
        expect_same_surface(out, wref, got.pieces, s[0]);
    }
}

TEST(MpiMesh, RanksThatOwnOnlyEmptyChunksTakePartAndWriteNothing) {
    // One small ball inside one 8-cell chunk: one active chunk, so three of the
    // four ranks own only chunks no surface crosses.
    TempDir dir;
    const std::string in = dir / "ball.nhdr";
    const std::array<std::int64_t, 3> d{33, 33, 33};
    Volume v = Volume::dense(d, VoxelType::I16, make_affine(glm::dvec3(1.0), glm::dvec3(0.0), glm::dmat3(1.0)));
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i)
                s[v.linear_index(i, j, k)] = std::int16_t(
                    std::clamp(500.0 + 200.0 * (2.5 - glm::length(glm::dvec3(i, j, k) - glm::dvec3(20))), 0.0, 1000.0));
    save_volume(v, in, false);
    const Mesh ref = reference(in, "--iso 500", dir / "ref.vtp");
    ASSERT_GT(ref.triangles.size(), 20u);
    const std::string out = dir / "ball.pvtp";
    const auto r = test::run_command(mpirun(4) + test::cli() + " mesh " + in + " --iso 500 --chunk 8 --json -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto sum = parse(r.out);
    ASSERT_EQ(sum.size(), 1u) << r.out;
    expect_same_surface(out, ref, 1, sum[0]);
    const auto ranks = nlohmann::json::parse(r.out)["mpi"];
    EXPECT_EQ(ranks["ranks"], 4) << r.out;
    ASSERT_EQ(ranks["active_chunks"].size(), 4u) << r.out;
    int idle = 0;
    for (const auto& n : ranks["active_chunks"]) idle += n.get<int>() == 0;
    EXPECT_EQ(idle, 3) << r.out;
    // The three ranks without surface took part in every step (the job
    // finished) and wrote nothing: only pieces with triangles are written
    // and listed.
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir / "ball")) files += e.path().extension() == ".vtp";
    EXPECT_EQ(files, 1);
}

TEST(MpiMesh, SeveralIsoValuesGoToOnePvtpEach) {
    TempDir dir;
    const std::string in = dir / "phantom.nii";
    save_volume(phantom({40, 30, 36}), in, false);
    const auto r = test::run_command(mpirun(2) + test::cli() + " mesh " + in +
                                     " --iso 300 --iso 700 --chunk 8 --json -o " + (dir / "s.pvtp"));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto sums = parse(r.out);
    ASSERT_EQ(sums.size(), 2u) << r.out;
    for (const auto& [iso, i] : {std::pair{300, 0}, std::pair{700, 1}}) {
        SCOPED_TRACE(iso);
        const Mesh ref = reference(in, "--iso " + std::to_string(iso), dir / ("ref" + std::to_string(iso) + ".vtp"));
        expect_same_surface(dir / ("s-iso" + std::to_string(iso) + ".pvtp"), ref, 2, sums[std::size_t(i)]);
    }
}

TEST(MpiMesh, FailuresAreErrorsNotHangs) {
    TempDir dir;
    const std::string in = dir / "phantom.nhdr";
    save_volume(phantom({40, 30, 36}), in, false);
    // A raw file missing its last slices: every rank's header check finds it;
    // the job ends (timeout 60 would say 124) with one message naming the file.
    {
        const fs::path raw = fs::path(dir / "phantom.raw");
        ASSERT_TRUE(fs::exists(raw));
        fs::resize_file(raw, fs::file_size(raw) - 40 * 30 * 2 * 3);
        const auto r =
            test::run_command(mpirun(4) + test::cli() + " mesh " + in + " --iso 500 -o " + (dir / "t.pvtp"), true);
        EXPECT_NE(r.exit_code, 0) << r.out;
        EXPECT_NE(r.exit_code, 124) << "the job hung: " << r.out;
        EXPECT_NE(r.out.find("rank 0"), std::string::npos) << r.out;
        EXPECT_NE(r.out.find("phantom"), std::string::npos) << r.out;
        EXPECT_FALSE(fs::exists(dir / "t.pvtp"));
    }
    // A gzip NRRD whose compressed stream is damaged near its end: only the
    // last of 4 ranks reads that far (the index pass gives each rank a quarter
    // of the slices, the extraction only its own chunks' slabs); the others
    // learn of it at the next agreement, and every rank exits non-zero.
    {
        const std::string gz = dir / "damaged.nrrd";
        save_volume(phantom({40, 30, 48}), gz, true);
        std::fstream f(gz, std::ios::in | std::ios::out | std::ios::binary);
        f.seekg(0, std::ios::end);
        const auto size = std::streamoff(f.tellg());
        std::string tail(20, '\0');
        f.seekg(size - 60);
        f.read(tail.data(), 20);
        for (auto& c : tail) c = char(c ^ 0x5a);
        f.seekp(size - 60);
        f.write(tail.data(), 20);
        f.close();
        const auto r = test::run_command(
            mpirun(4) + test::cli() + " mesh " + gz + " --iso 500 --chunk 8 -o " + (dir / "d.pvtp"), true);
        EXPECT_NE(r.exit_code, 0) << r.out;
        EXPECT_NE(r.exit_code, 124) << "the job hung: " << r.out;
        EXPECT_NE(r.out.find("isoscope: error: rank 3: "), std::string::npos) << r.out;
        EXPECT_EQ(r.out.find("other rank"), std::string::npos) << "only the last rank reads the damaged end: " << r.out;
        EXPECT_NE(r.out.find("damaged.nrrd"), std::string::npos) << r.out;
        EXPECT_FALSE(fs::exists(dir / "d.pvtp"));
        EXPECT_FALSE(fs::exists(dir / "d"));
    }
    // A failure on rank 0 only (a folder of the user's where the pieces would
    // go): the other ranks learn of it at the next agreement and stop too; the
    // user's folder is untouched and nothing is written.
    {
        save_volume(phantom({40, 30, 36}), in, false);
        fs::create_directories(dir / "mine");
        std::ofstream(dir / "mine/notes.txt") << "keep me";
        const auto r = test::run_command(
            mpirun(3) + test::cli() + " mesh " + in + " --iso 500 --chunk 8 -o " + (dir / "mine.pvtp"), true);
        EXPECT_NE(r.exit_code, 0) << r.out;
        EXPECT_NE(r.exit_code, 124) << "the job hung: " << r.out;
        EXPECT_NE(r.out.find("rank 0"), std::string::npos) << r.out;
        EXPECT_NE(r.out.find("holds other files"), std::string::npos) << r.out;
        EXPECT_TRUE(fs::exists(dir / "mine/notes.txt"));
        EXPECT_FALSE(fs::exists(dir / "mine.pvtp"));
    }
    // Another format than .pvtp under mpirun: a clear error, not N files.
    {
        const auto r =
            test::run_command(mpirun(2) + test::cli() + " mesh " + in + " --iso 500 -o " + (dir / "x.stl"), true);
        EXPECT_NE(r.exit_code, 0) << r.out;
        EXPECT_NE(r.out.find(".pvtp"), std::string::npos) << r.out;
        EXPECT_FALSE(fs::exists(dir / "x.stl"));
    }
    for (const auto& e : fs::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().filename().string().find(".isoscope-partial"), std::string::npos)
            << "staging left: " << e.path();
}

TEST(MpiMesh, LabelSurfacesEqualTheSingleProcess) {
    // A uint8 label map: two nested labels and a separate one.
    TempDir dir;
    const std::string in = dir / "labels.nii";
    const std::array<std::int64_t, 3> d{36, 30, 40};
    Volume v =
        Volume::dense(d, VoxelType::U8, make_affine(glm::dvec3(0.9, 1.0, 1.2), glm::dvec3(3, -2, 1), glm::dmat3(1.0)));
    auto s = v.as<std::uint8_t>();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const glm::dvec3 p(i, j, k);
                std::uint8_t l = 0;
                if (glm::length(p - glm::dvec3(14, 14, 16)) < 10) l = 1;
                if (glm::length(p - glm::dvec3(14, 14, 16)) < 5) l = 2;
                if (glm::length(p - glm::dvec3(28, 20, 32)) < 5) l = 7;
                s[v.linear_index(i, j, k)] = l;
            }
    save_volume(v, in, false);
    for (int n : {2, 4}) {
        SCOPED_TRACE(n);
        const std::string out = dir / ("l" + std::to_string(n) + ".pvtp");
        const auto r =
            test::run_command(mpirun(n) + test::cli() + " mesh " + in + " --labels --chunk 8 --json -o " + out);
        ASSERT_EQ(r.exit_code, 0) << r.out;
        const auto sums = parse(r.out);
        ASSERT_EQ(sums.size(), 3u) << "labels 1, 2 and 7 found across ranks: " << r.out;
        int i = 0;
        for (int label : {1, 2, 7}) {
            SCOPED_TRACE(label);
            const std::string tag = "-label" + std::to_string(label);
            const Mesh ref = reference(in, "--labels --label " + std::to_string(label), dir / ("ref" + tag + ".vtp"));
            ASSERT_GT(ref.triangles.size(), 50u);
            const ReadBack got = read_pvtp(dir / ("l" + std::to_string(n) + tag + ".pvtp"));
            expect_same_surface(dir / ("l" + std::to_string(n) + tag + ".pvtp"), ref, got.pieces,
                                sums[std::size_t(i++)]);
            EXPECT_GE(got.pieces, 1);
            EXPECT_LE(got.pieces, n);
        }
    }
}

TEST(MpiMesh, FloatVolumeWithNaNAndInfEqualsTheSingleProcess) {
    // Non-finite samples in the first slices only: one rank's share of the
    // index sees them; the reduced index must still substitute NaN below the
    // whole volume's finite range and clamp Inf to it, as one process does.
    TempDir dir;
    const std::string in = dir / "float.nrrd";
    const std::array<std::int64_t, 3> d{30, 28, 40};
    Volume v =
        Volume::dense(d, VoxelType::F32, make_affine(glm::dvec3(1.0, 0.9, 1.1), glm::dvec3(0.0), glm::dmat3(1.0)));
    auto s = v.as<float>();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                float x = float(8.0 - glm::length(glm::dvec3(i, j, k) - glm::dvec3(15, 14, 8)));
                if (k < 3 && i < 10) x = std::nanf("");
                if (k < 3 && i > 24) x = (j % 2) ? INFINITY : -INFINITY;
                s[v.linear_index(i, j, k)] = x;
            }
    save_volume(v, in, false);
    const Mesh ref = reference(in, "--iso 0.5", dir / "ref.vtp");
    ASSERT_GT(ref.triangles.size(), 200u);
    for (int n : {2, 4}) {
        SCOPED_TRACE(n);
        const std::string out = dir / ("f" + std::to_string(n) + ".pvtp");
        const auto r =
            test::run_command(mpirun(n) + test::cli() + " mesh " + in + " --iso 0.5 --chunk 6 --json -o " + out);
        ASSERT_EQ(r.exit_code, 0) << r.out;
        const auto sums = parse(r.out);
        ASSERT_EQ(sums.size(), 1u) << r.out;
        const ReadBack got = read_pvtp(out);
        expect_same_surface(out, ref, got.pieces, sums[0]);
    }
}

// OpenVDB under mpirun: every rank reads its slabs through its own reading
// child (the program exec'd again under the launcher's environment, where it
// must not start MPI); the budget (below twice the grid) makes the ranks
// stream. Same surface as the single process.
TEST(MpiMesh, OpenVdbSlabsOnTwoRanksEqualTheSingleProcess) {
    TempDir dir;
    const std::string in = dir / "phantom.vdb";
    // Every voxel active (VDB leaves samples equal to the minimum inactive):
    // a dense grid of about 2 MiB, so that 3 MiB is below twice the grid.
    Volume v = phantom({64, 48, 160});
    auto s16 = v.as<std::int16_t>();
    for (std::size_t n = 1; n < s16.size(); ++n) s16[n] = std::int16_t(std::max<int>(s16[n], 1));
    save_volume(v, in);
    const Mesh ref = reference(in, "--iso 500", dir / "ref.vtp");
    ASSERT_GT(ref.triangles.size(), 2000u);
    const std::string out = dir / "v.pvtp";
    const auto r =
        test::run_command(mpirun(2) + test::cli() + " mesh " + in + " --iso 500 --chunk 8 --memory 3 --json -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_GT(slabs_read(r.out), 2) << "several slabs: " << r.out;
    const auto s = parse(r.out);
    ASSERT_EQ(s.size(), 1u) << r.out;
    const ReadBack got = read_pvtp(out);
    expect_same_surface(out, ref, got.pieces, s[0]);
}
