// Out-of-core extraction (renderer/surface/stream.hpp, io/volume_stream.hpp,
// io/mesh_sink.hpp): streaming equals the in-memory extraction, for every
// streamed format, budgets (slab heights) and chunk sizes; the files it writes
// read back (VTK's vtkXMLPPolyDataReader, our PLY/STL readers) as the
// in-memory surface; bad input, cancellation and the memory budget.
//
// Tolerances: positions are compared exactly (float bits): streaming runs the
// same arithmetic on the same samples. Area and volume to 1e-9 relative: the
// sums run in another order (per piece) and the volume about another centre.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <vtkNew.h>
#include <vtkXMLPPolyDataReader.h>

#include "io/mesh_sink.hpp"
#include "io/vtk_mesh.hpp"
#include "io/volume_io.hpp"
#include "io/volume_stream.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/stream.hpp"
#include "tests/support/big_ball.hpp"
#include "tests/support/test_util.hpp"

// Is this an AddressSanitizer build? (GCC defines __SANITIZE_ADDRESS__, Clang answers __has_feature.)
#if defined(__SANITIZE_ADDRESS__)
#define ISOSCOPE_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ISOSCOPE_TEST_ASAN 1
#endif
#endif
#ifndef ISOSCOPE_TEST_ASAN
#define ISOSCOPE_TEST_ASAN 0
#endif

namespace iso {
namespace {
namespace fs = std::filesystem;
using test::files_in;
using test::read_file;
using test::TempDir;

// A wobbly ball (values fall off from the centre), in int16, with integer
// values so that iso values equal to samples (ties) occur; or float32.
Volume ball(std::array<std::int64_t, 3> d, VoxelType t, const glm::dmat4& m, glm::dvec3 centre_frac = {0.5, 0.5, 0.5}) {
    Volume v = Volume::dense(d, t, m);
    dispatch_voxel_type(t, [&](auto tag) {
        using T = decltype(tag);
        auto s = v.as<T>();
        for (std::int64_t k = 0; k < d[2]; ++k)
            for (std::int64_t j = 0; j < d[1]; ++j)
                for (std::int64_t i = 0; i < d[0]; ++i) {
                    const double x = i - centre_frac.x * double(d[0] - 1), y = j - centre_frac.y * double(d[1] - 1),
                                 z = k - centre_frac.z * double(d[2] - 1);
                    const double r = std::sqrt(x * x + y * y + z * z);
                    double f = 1000.0 - 25.0 * r + 40.0 * std::sin(0.5 * i) * std::cos(0.3 * j + 0.2 * k);
                    if constexpr (std::is_integral_v<T>) f = std::round(f);
                    s[v.linear_index(i, j, k)] = T(f);
                }
        return 0;
    });
    return v;
}

glm::dmat4 oblique(glm::dvec3 spacing, glm::dvec3 origin, bool mirror) {
    const double a = 0.4;
    glm::dmat3 r(glm::dvec3(std::cos(a), std::sin(a), 0), glm::dvec3(-std::sin(a), std::cos(a), 0),
                 glm::dvec3(0, 0, 1));
    if (mirror) r[2] = -r[2];
    return make_affine(spacing, origin, r);
}

// Collects the pieces and welds them by key (the test's own weld, keeping
// every seam key seen: pieces of chunk ranges that are not whole layers meet
// more than their predecessor): the mesh that stream_extract describes.
class CollectSink : public MeshSink {
public:
    void begin(std::size_t surfaces, std::size_t pieces, bool) override {
        meshes.assign(surfaces, Mesh{});
        seams.assign(surfaces, {});
        this->pieces = pieces;
    }
    void piece(MeshPiece&& p) override {
        Mesh& m = meshes[p.surface];
        auto& seam = seams[p.surface];
        std::vector<std::uint32_t> id(p.mesh.positions.size(), 0xFFFFFFFFu);
        for (const auto& [key, v] : p.lower)
            if (auto it = seam.find(key); it != seam.end()) id[v] = it->second;
        for (std::size_t v = 0; v < id.size(); ++v)
            if (id[v] == 0xFFFFFFFFu) {
                id[v] = std::uint32_t(m.positions.size());
                m.positions.push_back(p.mesh.positions[v]);
            } else {
                EXPECT_EQ(m.positions[id[v]], p.mesh.positions[v]) << "a seam vertex differs between pieces";
            }
        for (const auto& [key, v] : p.upper) seam[key] = id[v];
        for (const auto& t : p.mesh.triangles) m.triangles.push_back({id[t[0]], id[t[1]], id[t[2]]});
        ++received;
    }
    void finish() override { finished = true; }
    std::vector<MeshStats> stats() const override {
        std::vector<MeshStats> s;
        for (const auto& m : meshes) s.push_back(mesh_stats(m));
        return s;
    }
    std::vector<Mesh> meshes;
    std::vector<std::unordered_map<std::uint64_t, std::uint32_t>> seams;
    std::size_t pieces = 0, received = 0;
    bool finished = false;
};

// Keeps the pieces as they come.
class KeepSink : public MeshSink {
public:
    void piece(MeshPiece&& p) override { pieces.push_back(std::move(p)); }
    void finish() override {}
    std::vector<MeshStats> stats() const override { return {}; }
    std::vector<MeshPiece> pieces;
};

std::vector<std::array<float, 3>> sorted_positions(const Mesh& m) {
    std::vector<std::array<float, 3>> p;
    for (const auto& v : m.positions) p.push_back({v.x, v.y, v.z});
    std::sort(p.begin(), p.end());
    return p;
}

// Triangles as sorted position triples (independent of vertex numbering and rotation).
std::vector<std::array<float, 9>> sorted_triangles(const Mesh& m) {
    std::vector<std::array<float, 9>> out;
    for (const auto& t : m.triangles) {
        std::array<std::array<float, 3>, 3> c;
        for (int k = 0; k < 3; ++k) c[k] = {m.positions[t[k]].x, m.positions[t[k]].y, m.positions[t[k]].z};
        // Keep orientation: rotate so that the smallest corner comes first.
        const int s = int(std::min_element(c.begin(), c.end()) - c.begin());
        std::array<float, 9> r;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) r[std::size_t(3 * k + a)] = c[std::size_t((s + k) % 3)][std::size_t(a)];
        out.push_back(r);
    }
    std::sort(out.begin(), out.end());
    return out;
}

void expect_same_surface(const Mesh& ref, const Mesh& got, const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_EQ(got.triangles.size(), ref.triangles.size());
    ASSERT_EQ(got.positions.size(), ref.positions.size());
    EXPECT_TRUE(sorted_positions(got) == sorted_positions(ref));
    EXPECT_TRUE(sorted_triangles(got) == sorted_triangles(ref));
    const auto a = mesh_stats(ref), b = mesh_stats(got);
    EXPECT_NEAR(b.area, a.area, 1e-9 * a.area);
    EXPECT_NEAR(b.volume, a.volume, 1e-9 * std::abs(a.volume));
}

Mesh in_memory(const std::string& path, double iso, int chunk) {
    ExtractOptions eo;
    eo.chunk_size = chunk;
    return extract_isosurface(load_volume(path), iso, eo);
}

StreamStats stream_to(const std::string& path, double iso, int chunk, std::size_t budget, CollectSink& sink,
                      bool overlap = true) {
    auto src = open_volume_stream(path);
    StreamOptions so;
    so.overlap = overlap;
    so.isos = {iso};
    so.extract.chunk_size = chunk;
    so.memory_budget = budget;
    return stream_extract(*src, so, sink);
}

// The engine's fixed costs (index, scratch, read buffer) for this file and
// chunk size, plus `extra` bytes for slabs and output: budgets that give
// slabs of a few chunk layers even on the small volumes of these tests.
std::size_t budget_over_fixed(const std::string& path, int chunk, std::size_t extra) {
    auto src = open_volume_stream(path, std::size_t(1) << 30);
    StreamOptions so;
    so.isos = {0.0};
    so.extract.chunk_size = chunk;
    so.memory_budget = std::size_t(1) << 40;
    return plan_stream(src->header(), so).fixed_bytes + extra;
}

// ---- slab sources ------------------------------------------------------------

TEST(Stream, SlabsHaveTheReadersSamplesAndGeometry) {
    TempDir dir;
    const Volume v = ball({21, 17, 13}, VoxelType::I16, oblique({0.7, 0.9, 1.6}, {-30, 12, 80}, true));
    save_volume(v, dir / "raw.nrrd", false);
    save_volume(v, dir / "gz.nrrd", true);
    save_volume(v, dir / "det.nhdr", false);
    save_volume(v, dir / "v.nii");
    for (const char* name : {"raw.nrrd", "gz.nrrd", "det.nhdr", "v.nii"}) {
        SCOPED_TRACE(name);
        const Volume ref = load_volume(dir / name);
        auto src = open_volume_stream(dir / name);
        ASSERT_TRUE(src->streaming());
        EXPECT_EQ(src->header().dims, ref.dims);
        EXPECT_EQ(src->header().type, ref.type);
        EXPECT_EQ(src->header().index_to_lps, ref.index_to_lps); // the same parsing: bit for bit
        for (auto [k0, k1] : std::vector<std::pair<int, int>>{{0, 0}, {3, 7}, {12, 12}, {0, 12}, {2, 5}}) {
            const Volume s = src->read_slab(k0, k1);
            ASSERT_EQ(s.dims, (std::array<std::int64_t, 3>{21, 17, k1 - k0 + 1}));
            const std::size_t slice = std::size_t(21 * 17) * voxel_size(ref.type);
            EXPECT_EQ(std::memcmp(s.bytes().data(), ref.bytes().data() + std::size_t(k0) * slice, s.bytes().size()), 0);
            const glm::dvec3 a = s.index_to_world({2, 3, 0}), b = ref.index_to_world({2, 3, double(k0)});
            EXPECT_NEAR(glm::length(a - b), 0.0, 1e-12);
        }
        EXPECT_THROW(src->read_slab(5, 13), Error);
    }
    // MetaImage with a detached raw data file (the bundled volumes).
    for (const char* name : {"HeadMRVolume.mhd", "headsq.mhd"}) {
        SCOPED_TRACE(name);
        const Volume ref = load_volume(test::data(name));
        auto src = open_volume_stream(test::data(name));
        ASSERT_TRUE(src->streaming());
        EXPECT_EQ(src->header().index_to_lps, ref.index_to_lps);
        const std::int64_t k0 = ref.dims[2] / 3, k1 = ref.dims[2] - 2;
        const Volume s = src->read_slab(k0, k1);
        const std::size_t slice = std::size_t(ref.dims[0] * ref.dims[1]) * voxel_size(ref.type);
        EXPECT_EQ(std::memcmp(s.bytes().data(), ref.bytes().data() + std::size_t(k0) * slice, s.bytes().size()), 0);
    }
}

TEST(Stream, NiftiRescaleAndByteOrderMatchTheReader) {
    TempDir dir;
    // A big-endian NIfTI with scl_slope/inter, written by hand (header fields
    // at their NIfTI-1 offsets); the reader (nifti_clib) swaps and rescales.
    const int nx = 6, ny = 5, nz = 4;
    std::vector<char> hdr(352, 0);
    auto put32 = [&](int off, std::uint32_t x) {
        for (int b = 0; b < 4; ++b) hdr[std::size_t(off + b)] = char((x >> (24 - 8 * b)) & 0xff);
    };
    auto put16 = [&](int off, std::uint16_t x) {
        hdr[std::size_t(off)] = char(x >> 8);
        hdr[std::size_t(off + 1)] = char(x & 0xff);
    };
    auto putf = [&](int off, float f) {
        std::uint32_t u;
        std::memcpy(&u, &f, 4);
        put32(off, u);
    };
    put32(0, 348);
    const std::uint16_t dim[8] = {3, nx, ny, nz, 1, 1, 1, 1};
    for (int i = 0; i < 8; ++i) put16(40 + 2 * i, dim[i]);
    put16(70, 4);  // DT_INT16
    put16(72, 16); // bitpix
    const float pix[4] = {1, 0.5f, 0.75f, 2.0f};
    for (int i = 0; i < 4; ++i) putf(76 + 4 * i, pix[i]);
    putf(108, 352);   // vox_offset
    putf(112, 0.25f); // scl_slope
    putf(116, -3.0f); // scl_inter
    std::memcpy(hdr.data() + 344, "n+1\0", 4);
    std::ofstream f(dir / "be.nii", std::ios::binary);
    f.write(hdr.data(), std::streamsize(hdr.size()));
    for (int i = 0; i < nx * ny * nz; ++i) {
        const std::int16_t x = std::int16_t(i * 37 - 1000);
        const char b[2] = {char((std::uint16_t(x) >> 8) & 0xff), char(std::uint16_t(x) & 0xff)};
        f.write(b, 2);
    }
    f.close();
    const Volume ref = load_volume(dir / "be.nii");
    ASSERT_EQ(ref.type, VoxelType::F32);
    auto src = open_volume_stream(dir / "be.nii");
    EXPECT_TRUE(src->header().swap_bytes);
    const Volume s = src->read_slab(1, 3);
    for (int k = 1; k <= 3; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                ASSERT_EQ(s.value(i, j, k - 1), ref.value(i, j, k)) << i << " " << j << " " << k;
}

// ---- streaming == in memory ----------------------------------------------------

TEST(Stream, EqualsInMemoryForBudgetsAndChunkSizes) {
    TempDir dir;
    const Volume v = ball({40, 36, 70}, VoxelType::I16, oblique({0.8, 0.7, 1.3}, {5, -7, 11}, false));
    save_volume(v, dir / "v.nrrd", false);
    for (int chunk : {8, 16}) {
        for (double iso : {500.0, 700.5}) { // 500: ties with samples
            const Mesh ref = in_memory(dir / "v.nrrd", iso, chunk);
            ASSERT_GT(ref.triangles.size(), 1000u);
            // Budgets from one chunk layer per slab to the whole volume in one slab.
            std::set<int> heights;
            // Budgets above the fixed costs for one, two, several chunk layers and the whole volume per slab.
            const std::vector<std::size_t> extras =
                chunk == 8 ? std::vector<std::size_t>{450 << 10, 700 << 10, 1500 << 10, 64 << 20}
                           : std::vector<std::size_t>{700 << 10, 1400 << 10, 2100 << 10, 64 << 20};
            for (std::size_t extra : extras)
                for (bool overlap : {false, true}) {
                    const std::size_t budget = budget_over_fixed(dir / "v.nrrd", chunk, extra);
                    CollectSink sink;
                    const auto st = stream_to(dir / "v.nrrd", iso, chunk, budget, sink, overlap);
                    if (!overlap) heights.insert(st.plan.layers_per_slab); // the serial planner's heights
                    EXPECT_TRUE(st.plan.fits);
                    EXPECT_LE(st.peak_bytes, budget);
                    EXPECT_TRUE(sink.finished);
                    expect_same_surface(ref, sink.meshes[0],
                                        "chunk " + std::to_string(chunk) + " iso " + std::to_string(iso) +
                                            " layers/slab " + std::to_string(st.plan.layers_per_slab) +
                                            (st.plan.overlap ? " overlapped" : ""));
                }
            std::string hs;
            for (int hgt : heights) hs += " " + std::to_string(hgt);
            EXPECT_GE(heights.size(), chunk == 8 ? 3u : 2u) << "the budgets should give different slab heights:" << hs;
        }
    }
}

TEST(Stream, FloatWithNanObliqueMirroredGzipAndMetaImage) {
    TempDir dir;
    Volume v = ball({30, 28, 45}, VoxelType::F32, oblique({0.6, 0.6, 1.1}, {100, 50, -20}, true), {0.5, 0.4, 0.6});
    auto s = v.as<float>();
    for (std::size_t i = 0; i < s.size(); i += 97) s[i] = std::nanf("");
    s[v.linear_index(3, 4, 40)] = INFINITY;
    s[v.linear_index(10, 12, 2)] = -INFINITY;
    save_volume(v, dir / "f.nrrd", true); // gzip
    save_volume(v, dir / "f.nii");
    // MetaImage, raw data attached, written by hand (no MetaImage writer).
    {
        std::ofstream f(dir / "f.mha", std::ios::binary);
        const auto& m = v.index_to_lps;
        const glm::dvec3 sp = v.spacing();
        f << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n";
        f << std::setprecision(17) << "TransformMatrix =";
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < 3; ++k) f << " " << m[a][k] / sp[a];
        f << "\nOffset = " << m[3][0] << " " << m[3][1] << " " << m[3][2] << "\nElementSpacing = " << sp.x << " "
          << sp.y << " " << sp.z;
        f << "\nDimSize = 30 28 45\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n";
        f.write(reinterpret_cast<const char*>(v.bytes().data()), std::streamsize(v.bytes().size()));
    }
    for (const char* name : {"f.nrrd", "f.nii", "f.mha"}) {
        for (double iso : {900.0, 620.25}) {
            const Mesh ref = in_memory(dir / name, iso, 8);
            ASSERT_GT(ref.triangles.size(), 500u);
            CollectSink sink;
            const auto st =
                stream_to(dir / name, iso, 8, budget_over_fixed(dir / name, 8, std::size_t(100) << 10), sink);
            EXPECT_GT(st.plan.slabs, 3u);
            EXPECT_TRUE(st.index_pass);
            expect_same_surface(ref, sink.meshes[0], std::string(name) + " iso " + std::to_string(iso));
            if (std::string(name) ==
                "f.nrrd") { // gzip: one restart after the index pass; slab halos come from the kept slices
                EXPECT_EQ(st.source_restarts, 1u);
            }
        }
    }
}

TEST(Stream, VdbIsLoadedWholeAndSlicedSparse) {
    TempDir dir;
    Volume v = ball({24, 24, 40}, VoxelType::F32, oblique({0.5, 0.5, 0.5}, {1, 2, 3}, false));
    save_volume(v, dir / "v.vdb");
    const Mesh ref = in_memory(dir / "v.vdb", 800.0, 8);
    ASSERT_GT(ref.triangles.size(), 100u);
    auto src = open_volume_stream(dir / "v.vdb", std::size_t(64) << 20);
    EXPECT_FALSE(src->streaming());
    StreamOptions so;
    so.isos = {800.0};
    so.extract.chunk_size = 8;
    so.memory_budget = budget_over_fixed(dir / "v.vdb", 8, std::size_t(100) << 10) + src->resident_bytes();
    CollectSink sink;
    const auto st = stream_extract(*src, so, sink);
    EXPECT_GT(st.plan.slabs, 1u);
    expect_same_surface(ref, sink.meshes[0], "vdb");
}

// A VDB larger than the memory allowed for loading it whole (0 here) is read
// slab by slab by the isolating child (topology clipped to the slab, only the
// leaves left read): the header is read_vdb's geometry, the slabs carry
// read_vdb's samples (inside and outside the active voxels) and affine, the
// surface is the in-memory one, and a damaged file is an error naming it.
TEST(Stream, VdbIsReadSlabBySlab) {
    TempDir dir;
    const Volume v = ball({24, 20, 40}, VoxelType::F32, oblique({0.5, 0.7, 0.6}, {1, 2, 3}, true));
    save_volume(v, dir / "v.vdb");
    const Volume whole = load_volume(dir / "v.vdb");
    ASSERT_TRUE(whole.is_sparse());
    // The header, also through read_volume_header (what `isoscope info --header-only` reads).
    const VolumeHeader h = read_volume_header(dir / "v.vdb");
    EXPECT_EQ(h.format, VolumeFormat::Vdb);
    EXPECT_EQ(h.type, VoxelType::F32);
    EXPECT_EQ(h.dims, whole.dims);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_DOUBLE_EQ(h.index_to_lps[c][r], whole.index_to_lps[c][r]);
    auto src = open_volume_stream(dir / "v.vdb", 0);
    EXPECT_TRUE(src->streaming());
    ASSERT_EQ(src->header().dims, whole.dims);
    EXPECT_GT(src->resident_bytes(), 0u); // the topology the child holds
    for (auto [k0, k1] : {std::pair<std::int64_t, std::int64_t>{7, 19},
                          {0, 0},
                          {0, whole.dims[2] - 1},
                          {whole.dims[2] - 3, whole.dims[2] - 1}}) {
        const Volume slab = src->read_slab(k0, k1);
        ASSERT_EQ(slab.dims[2], k1 - k0 + 1);
        EXPECT_TRUE(slab.is_sparse());
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r)
                EXPECT_DOUBLE_EQ(
                    slab.index_to_lps[c][r],
                    (whole.index_to_lps * glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, double(k0))))[c][r]);
        std::size_t differ = 0;
        for (std::int64_t k = 0; k < slab.dims[2]; ++k)
            for (std::int64_t j = 0; j < whole.dims[1]; ++j)
                for (std::int64_t i = 0; i < whole.dims[0]; ++i)
                    differ += slab.value(i, j, k) != whole.value(i, j, k + k0);
        EXPECT_EQ(differ, 0u) << "slab " << k0 << ".." << k1;
    }
    EXPECT_THROW(src->read_slab(5, whole.dims[2]), Error);
    EXPECT_GT(src->reader_peak_bytes(), 0u);
    const Mesh ref = in_memory(dir / "v.vdb", 800.0, 8);
    ASSERT_GT(ref.triangles.size(), 100u);
    StreamOptions so;
    so.isos = {800.0};
    so.extract.chunk_size = 8;
    // The engine's fixed costs, the child's topology and two layers of slab
    // as this stream's header prices them (the leaves the reader holds).
    so.memory_budget = std::size_t(1) << 40;
    so.memory_budget = plan_stream(src->header(), so).fixed_bytes + src->resident_bytes() +
                       std::size_t(src->header().slab_memory_bytes(19)) + (std::size_t(64) << 10);
    CollectSink sink;
    const auto st = stream_extract(*src, so, sink);
    EXPECT_GT(st.plan.slabs, 1u);
    EXPECT_LE(st.peak_bytes, so.memory_budget);
    expect_same_surface(ref, sink.meshes[0], "vdb slabs");
    // A damaged file is an error naming it, also when read slab by slab.
    {
        std::ofstream bad(dir / "bad.vdb", std::ios::binary);
        bad << "not a vdb file at all, but long enough to be looked at";
    }
    for (std::size_t limit : {std::size_t(0), std::size_t(1) << 30}) {
        try {
            open_volume_stream(dir / "bad.vdb", limit);
            ADD_FAILURE() << "a damaged VDB opened";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("bad.vdb"), std::string::npos) << e.what();
        }
    }
}

// The child reads only the leaves meeting a slab: on a grid of 64 MiB of
// leaf values, the reading child of a thin slab stays far below the child
// that reads every leaf (delayed loading and clipping really skip the rest;
// both include the same program and topology, so the difference is the
// values). A file cut short is an error naming it when a slab is read, not a
// crash; what the stream had read before stays valid.
TEST(Stream, VdbSlabReadsOnlyItsLeaves) {
    TempDir dir;
    // Every voxel active (noise above the background): 2^24 float values.
    Volume v = Volume::dense({256, 256, 256}, VoxelType::F32, glm::dmat4(1.0));
    auto s = v.as<float>();
    for (std::size_t n = 0; n < s.size(); ++n) s[n] = float(1 + (n * 2654435761u) % 1000);
    s[0] = 0.0f; // the minimum stays inactive (the background)
    save_volume(v, dir / "big.vdb");
    const VdbHeader h = read_vdb_header(dir / "big.vdb");
    EXPECT_GE(h.grid_bytes, std::uint64_t(64) << 20);
    EXPECT_LT(h.topology_bytes, h.grid_bytes / 8);
    std::size_t thin = 0, all = 0;
    const Volume a = read_vdb_slab(h, 100, 107, &thin);
    const Volume b = read_vdb_slab(h, 0, 255, &all);
    EXPECT_EQ(a.value(3, 4, 5), v.value(3, 4, 105));
    EXPECT_EQ(b.value(250, 251, 252), v.value(250, 251, 252));
    ASSERT_GT(thin, 0u);
    std::cout << "grid " << (h.grid_bytes >> 20) << " MiB, topology " << (h.topology_bytes >> 10)
              << " KiB; reading child peak: slab of 8 slices " << (thin >> 20) << " MiB, every slice " << (all >> 20)
              << " MiB\n";
    EXPECT_GT(all, thin + (std::size_t(40) << 20))
        << "thin slab child " << (thin >> 20) << " MiB, whole grid child " << (all >> 20) << " MiB";
    // Cut the file in half: the header may still be read (or not), a slab must not.
    const auto size = fs::file_size(dir / "big.vdb");
    fs::resize_file(dir / "big.vdb", size / 2);
    try {
        read_vdb_slab(h, 200, 230);
        ADD_FAILURE() << "a slab of a truncated VDB was read";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("big.vdb"), std::string::npos) << e.what();
        std::cout << "truncated: " << e.what() << "\n";
    }
    EXPECT_EQ(a.value(3, 4, 5), v.value(3, 4, 105));
}

TEST(Stream, EmptySlabsAreSkippedAndRangesOfChunksWork) {
    TempDir dir;
    // The ball sits in the lower quarter: most slabs hold no surface.
    const Volume v = ball({24, 24, 120}, VoxelType::I16, glm::dmat4(1.0), {0.5, 0.5, 0.12});
    save_volume(v, dir / "v.nrrd", false);
    const Mesh ref = in_memory(dir / "v.nrrd", 820.0, 8);
    ASSERT_GT(ref.triangles.size(), 100u);
    CollectSink sink;
    const auto st =
        stream_to(dir / "v.nrrd", 820.0, 8, budget_over_fixed(dir / "v.nrrd", 8, std::size_t(30) << 10), sink);
    EXPECT_GT(st.slabs_skipped, st.plan.slabs / 2);
    EXPECT_EQ(st.slabs_read + st.slabs_skipped, st.plan.slabs);
    expect_same_surface(ref, sink.meshes[0], "skipping");

    // Two ranges of chunk ids (as two MPI ranks would take) welded by key = the whole.
    auto src = open_volume_stream(dir / "v.nrrd");
    auto index = build_chunk_index(*src, 8, std::size_t(16) << 20);
    const std::size_t half = index->chunk_count() / 2 + 5; // not on a layer boundary
    CollectSink both;
    both.begin(1, 0, true);
    std::size_t n = 0;
    for (auto [a, b] : {std::pair<std::size_t, std::size_t>{0, half}, {half, index->chunk_count()}}) {
        StreamOptions so;
        so.isos = {820.0};
        so.extract.chunk_size = 8;
        so.memory_budget = budget_over_fixed(dir / "v.nrrd", 8, std::size_t(30) << 10);
        so.first_chunk = a;
        so.last_chunk = b;
        so.index = index; // given: no index pass
        KeepSink part;
        const auto pst = stream_extract(*src, so, part);
        EXPECT_FALSE(pst.index_pass);
        for (auto& p : part.pieces) {
            p.index = n++;
            both.piece(std::move(p));
        }
    }
    expect_same_surface(ref, both.meshes[0], "two ranges of chunk ids");
}

// The engine's errors and warnings name its settings, never command-line
// flags (the CLI maps "memory budget" and "chunk size" to its own).
TEST(Stream, BudgetAndChunkSizeMessagesNameTheSettings) {
    TempDir dir;
    save_volume(ball({24, 24, 40}, VoxelType::I16, glm::dmat4(1.0)), dir / "v.nrrd", false);
    auto src = open_volume_stream(dir / "v.nrrd");
    StreamOptions so;
    so.isos = {820.0};
    so.extract.chunk_size = 8;
    so.memory_budget = 1024; // less than one slice
    auto where = [&](auto&& f) {
        try {
            f();
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << e.what();
            return e.where();
        }
        return std::string("no error");
    };
    EXPECT_EQ(where([&] { plan_stream(src->header(), so); }), "memory budget");
    so.extract.chunk_size = 1;
    EXPECT_EQ(where([&] { plan_stream(src->header(), so); }), "chunk size");

    // A source holding the volume whole holds more than this budget.
    save_volume(ball({24, 24, 40}, VoxelType::F32, glm::dmat4(1.0)), dir / "v.vdb");
    auto whole = open_volume_stream(dir / "v.vdb", std::size_t(64) << 20);
    ASSERT_GT(whole->resident_bytes(), 0u);
    so.extract.chunk_size = 8;
    so.memory_budget = whole->resident_bytes();
    CollectSink none;
    EXPECT_EQ(where([&] { stream_extract(*whole, so, none); }), "memory budget");

    // One slab's samples fit, one chunk layer's estimated output does not: a warning.
    const std::size_t one_layer = std::size_t(src->header().slab_memory_bytes(8 + 3));
    so.memory_budget = budget_over_fixed(dir / "v.nrrd", 8, one_layer + 1024);
    CollectSink sink;
    const auto st = stream_extract(*src, so, sink);
    EXPECT_FALSE(st.plan.fits);
    ASSERT_EQ(st.warnings.size(), 1u);
    EXPECT_NE(st.warnings[0].find("memory budget"), std::string::npos) << st.warnings[0];
    EXPECT_NE(st.warnings[0].find("chunk size"), std::string::npos) << st.warnings[0];
    EXPECT_EQ(st.warnings[0].find("--"), std::string::npos) << st.warnings[0];
}

TEST(Stream, LabelSurfacesEqualInMemory) {
    TempDir dir;
    // Three labels: nested balls and a slab-crossing bar.
    Volume v = Volume::dense({26, 22, 48}, VoxelType::U8, oblique({0.9, 0.9, 1.4}, {3, 4, 5}, true));
    auto s = v.as<std::uint8_t>();
    for (std::int64_t k = 0; k < 48; ++k)
        for (std::int64_t j = 0; j < 22; ++j)
            for (std::int64_t i = 0; i < 26; ++i) {
                const double r =
                    std::sqrt((i - 12.5) * (i - 12.5) + (j - 10.5) * (j - 10.5) + (k - 20.0) * (k - 20.0) * 0.5);
                std::uint8_t l = r < 6 ? 2 : r < 10 ? 1 : 0;
                if (i > 18 && j < 6) l = 7;
                s[v.linear_index(i, j, k)] = l;
            }
    save_volume(v, dir / "labels.nii");
    ExtractOptions eo;
    eo.chunk_size = 8;
    const auto ref = extract_labels(load_volume(dir / "labels.nii"), {}, eo);
    ASSERT_EQ(ref.size(), 3u);
    auto src = open_volume_stream(dir / "labels.nii");
    StreamOptions so;
    so.labels = true; // every non-zero label, found in the index pass
    so.extract.chunk_size = 8;
    so.memory_budget = budget_over_fixed(dir / "labels.nii", 8, std::size_t(40) << 10);
    CollectSink sink;
    const auto st = stream_extract(*src, so, sink);
    EXPECT_GT(st.plan.slabs, 2u);
    ASSERT_EQ(st.values, (std::vector<double>{1, 2, 7}));
    for (std::size_t l = 0; l < 3; ++l)
        expect_same_surface(ref[l].mesh, sink.meshes[l], "label " + std::to_string(ref[l].label));
}

TEST(Stream, ChunkIndexFromSlabsEqualsTheInMemoryIndex) {
    Volume v = ball({19, 23, 31}, VoxelType::F32, glm::dmat4(1.0));
    auto s = v.as<float>();
    for (std::size_t i = 0; i < s.size(); i += 53) s[i] = std::nanf("");
    s[100] = INFINITY;
    s[2000] = -INFINITY;
    const ChunkIndex ref(v, 8);
    // Slabs of uneven heights, one merged from two halves.
    ChunkSummaries a(v.dims, 8, v.type), b(v.dims, 8, v.type);
    for (auto [k0, k1] : std::vector<std::pair<int, int>>{{0, 6}, {7, 7}, {8, 19}, {20, 30}}) {
        Volume slab = Volume::dense({19, 23, k1 - k0 + 1}, v.type, v.index_to_lps);
        std::memcpy(slab.bytes().data(), v.bytes().data() + std::size_t(k0) * 19 * 23 * 4, slab.bytes().size());
        (k0 < 8 ? a : b).add({&slab, v.dims, k0, v.index_to_lps});
    }
    a.merge(b);
    const ChunkIndex got = a.finish();
    ASSERT_EQ(got.chunk_count(), ref.chunk_count());
    EXPECT_EQ(got.nan_value(), ref.nan_value());
    EXPECT_EQ(got.lowest(), ref.lowest());
    EXPECT_EQ(got.highest(), ref.highest());
    for (std::size_t id = 0; id < ref.chunk_count(); ++id) {
        EXPECT_EQ(got.min(id), ref.min(id)) << id;
        EXPECT_EQ(got.max(id), ref.max(id)) << id;
    }
    // From plain arrays (MPI gathers these).
    const ChunkIndex arr(v.dims, 8, ref.mins(), ref.maxs(), ref.lowest(), ref.highest());
    EXPECT_EQ(arr.nan_value(), ref.nan_value());
    EXPECT_THROW(ChunkIndex(v.dims, 8, {1.0}, {2.0}, 0, 0), Error);
}

// ---- files written ----------------------------------------------------------------

Mesh read_pvtp(const std::string& path, std::size_t& pieces) {
    vtkNew<vtkXMLPPolyDataReader> r;
    r->SetFileName(path.c_str());
    r->Update();
    pieces = std::size_t(r->GetNumberOfPieces());
    const Mesh all = from_polydata(r->GetOutput(), path);
    // Pieces repeat their seam vertices: merge equal positions (exact bits).
    Mesh m;
    std::map<std::array<float, 3>, std::uint32_t> ids;
    std::vector<std::uint32_t> remap(all.positions.size());
    for (std::size_t i = 0; i < all.positions.size(); ++i) {
        const std::array<float, 3> q{all.positions[i].x, all.positions[i].y, all.positions[i].z};
        auto [it, fresh] = ids.emplace(q, std::uint32_t(m.positions.size()));
        if (fresh) m.positions.push_back(all.positions[i]);
        remap[i] = it->second;
    }
    for (const auto& t : all.triangles) m.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
    return m;
}

TEST(Stream, PvtpPlyAndStlReadBackAsTheInMemorySurface) {
    TempDir dir;
    const Volume v = ball({32, 30, 50}, VoxelType::I16, oblique({0.9, 0.8, 1.2}, {0, 0, 0}, true));
    save_volume(v, dir / "v.nii");
    const Mesh ref = in_memory(dir / "v.nii", 640.0, 8);
    for (const char* name : {"out.pvtp", "out.ply", "out.stl"}) {
        SCOPED_TRACE(name);
        auto src = open_volume_stream(dir / "v.nii");
        StreamOptions so;
        so.isos = {640.0};
        so.extract.chunk_size = 8;
        so.memory_budget = budget_over_fixed(dir / "v.nii", 8, std::size_t(60) << 10);
        auto sink = make_mesh_sink({dir / name});
        const auto st = stream_extract(*src, so, *sink);
        ASSERT_GT(st.plan.slabs, 2u);
        const MeshStats ms = sink->stats()[0], rs = mesh_stats(ref);
        EXPECT_EQ(ms.triangles, rs.triangles);
        EXPECT_EQ(ms.vertices, rs.vertices);
        EXPECT_NEAR(ms.area, rs.area, 1e-9 * rs.area);
        EXPECT_NEAR(ms.volume, rs.volume, 1e-9 * std::abs(rs.volume));
        Mesh got;
        if (std::string(name) == "out.pvtp") {
            std::size_t pieces = 0;
            got = read_pvtp(dir / name, pieces);
            EXPECT_EQ(pieces, st.plan.slabs);
        } else {
            got = load_mesh(dir / name); // STL: VTK's reader merges coincident points
        }
        expect_same_surface(ref, got, name);
        for (const auto& e : fs::directory_iterator(dir.path()))
            EXPECT_EQ(e.path().filename().string().find("tmp"), std::string::npos) << "left behind: " << e.path();
    }
    EXPECT_THROW(make_mesh_sink({dir / "x.vtp"}), Error);
    EXPECT_THROW(make_mesh_sink({dir / "x.obj"}), Error);
}

// ---- bad input, cancellation --------------------------------------------------------

TEST(Stream, TruncatedAndMalformedFilesAreErrorsAndNothingIsWritten) {
    TempDir dir;
    const Volume v = ball({16, 16, 20}, VoxelType::I16, glm::dmat4(1.0));
    save_volume(v, dir / "full.nrrd", false);
    save_volume(v, dir / "full.nii");
    save_volume(v, dir / "gz.nrrd", true);
    auto cut = [&](const std::string& from, const std::string& to, std::uintmax_t drop) {
        fs::copy_file(dir / from, dir / to);
        fs::resize_file(dir / to, fs::file_size(dir / to) - drop);
    };
    cut("full.nrrd", "cut.nrrd", 100);
    cut("full.nii", "cut.nii", 1000);
    cut("gz.nrrd", "cutgz.nrrd", 200);
    {
        std::ofstream(dir / "bad.mha")
            << "NDims = 3\nDimSize = 4 4\nElementType = MET_SHORT\nElementDataFile = LOCAL\n";
        std::ofstream(dir / "bad.nrrd") << "NRRD0004\ntype: nonsense\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n";
    }
    for (const char* name : {"cut.nrrd", "cut.nii", "bad.mha", "bad.nrrd"}) {
        try {
            open_volume_stream(dir / name);
            ADD_FAILURE() << name << " opened";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            if (std::string(name).rfind("cut", 0) == 0) {
                EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
            }
        }
    }
    // gzip is only found short while reading: the error comes before the output is moved into place.
    fs::remove(dir / "out.ply");
    try {
        auto src = open_volume_stream(dir / "cutgz.nrrd");
        StreamOptions so;
        so.isos = {800};
        so.extract.chunk_size = 8;
        auto sink = make_mesh_sink({dir / "out.ply"});
        stream_extract(*src, so, *sink);
        ADD_FAILURE() << "truncated gzip read";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cutgz.nrrd"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "out.ply"));
    // .nii.gz cannot stream: an error naming it, unless it may be loaded whole.
    save_volume(v, dir / "c.nii.gz");
    EXPECT_THROW(open_volume_stream(dir / "c.nii.gz"), Error);
    EXPECT_FALSE(open_volume_stream(dir / "c.nii.gz", std::size_t(1) << 20)->streaming());
}

TEST(Stream, CancellingLeavesNoOutputAndKeepsTheUsersFile) {
    TempDir dir;
    const Volume v = ball({24, 24, 60}, VoxelType::I16, glm::dmat4(1.0));
    save_volume(v, dir / "v.nrrd", false);
    for (const char* name : {"out.pvtp", "out.ply", "out.stl"}) {
        SCOPED_TRACE(name);
        { std::ofstream(dir / name) << "the user's file"; }
        auto src = open_volume_stream(dir / "v.nrrd");
        StreamOptions so;
        so.isos = {800};
        so.extract.chunk_size = 8;
        so.memory_budget = budget_over_fixed(dir / "v.nrrd", 8, std::size_t(30) << 10);
        int calls = 0;
        so.progress = [&](double f, std::string_view) { return ++calls < 5 || f < 0.5; };
        {
            auto sink = make_mesh_sink({dir / name});
            EXPECT_THROW(stream_extract(*src, so, *sink), Cancelled);
        }
        EXPECT_EQ(read_file(dir / name), "the user's file");
        // v.nrrd and the user's file: no pieces, no temporaries
        EXPECT_EQ(files_in(dir.path()), (std::vector<std::string>{name, "v.nrrd"}));
        fs::remove(dir / name);
    }
}

// ---- overlap: reader, extraction and writer as a pipeline (StreamOptions::overlap) ----------

template <class V> bool same_bits(const V& a, const V& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

// Every piece the same, in the same order, bit for bit (positions, normals,
// triangles and both seam lists).
void expect_same_pieces(const std::vector<MeshPiece>& a, const std::vector<MeshPiece>& b, const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        SCOPED_TRACE("piece " + std::to_string(i));
        EXPECT_EQ(a[i].surface, b[i].surface);
        EXPECT_EQ(a[i].index, b[i].index);
        EXPECT_TRUE(same_bits(a[i].mesh.positions, b[i].mesh.positions));
        EXPECT_TRUE(same_bits(a[i].mesh.normals, b[i].mesh.normals));
        EXPECT_TRUE(same_bits(a[i].mesh.triangles, b[i].mesh.triangles));
        EXPECT_TRUE(a[i].lower == b[i].lower);
        EXPECT_TRUE(a[i].upper == b[i].upper);
    }
}

// Passes everything on to another sink and counts the pieces; throws an
// iso::Error at piece `fail_at` (a failing writer).
class ForwardSink : public MeshSink {
public:
    explicit ForwardSink(MeshSink& to, std::size_t fail_at = std::size_t(-1)) : to_(to), fail_at_(fail_at) {}
    void begin(std::size_t s, std::size_t n, bool normals) override { to_.begin(s, n, normals); }
    void piece(MeshPiece&& p) override {
        if (pieces == fail_at_) throw Error("test sink", "disk full (made up)");
        ++pieces;
        to_.piece(std::move(p));
    }
    void finish() override { to_.finish(); }
    std::size_t memory_bytes() const override { return to_.memory_bytes(); }
    std::vector<MeshStats> stats() const override { return to_.stats(); }
    std::size_t pieces = 0;

private:
    MeshSink& to_;
    std::size_t fail_at_;
};

// A wobbly int16 tube along k: the surface at 700 crosses every slab (none is skipped).
Volume tube(std::array<std::int64_t, 3> d) {
    Volume v = Volume::dense(d, VoxelType::I16, glm::dmat4(1.0));
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const double x = i - 0.5 * double(d[0] - 1), y = j - 0.5 * double(d[1] - 1);
                s[v.linear_index(i, j, k)] = std::int16_t(std::round(
                    1000.0 - 40.0 * std::sqrt(x * x + y * y) + 40.0 * std::sin(0.5 * i) * std::cos(0.3 * j + 0.2 * k)));
            }
    return v;
}

// Overlap on == off, bit for bit: the same pieces in the same order when both
// run one plan (the overlapped plan's slab height given to the serial run),
// and the same welded surface (vertex order included) when each runs its own
// plan (overlap halves the slabs for the same budget). Raw and gzip NRRD,
// float NIfTI with NaN, two iso values at once, a label map; budgets from
// slabs of one chunk layer to a few.
TEST(Stream, OverlapGivesTheSamePiecesAsSerial) {
    TempDir dir;
    const Volume v = ball({40, 36, 90}, VoxelType::I16, oblique({0.8, 0.7, 1.3}, {5, -7, 11}, false));
    save_volume(v, dir / "v.nrrd", false);
    save_volume(v, dir / "g.nrrd", true); // gzip, read forward only
    Volume f = ball({30, 28, 70}, VoxelType::F32, oblique({0.6, 0.6, 1.1}, {100, 50, -20}, true), {0.5, 0.4, 0.6});
    auto fs_ = f.as<float>();
    for (std::size_t i = 0; i < fs_.size(); i += 97) fs_[i] = std::nanf("");
    save_volume(f, dir / "f.nii");
    Volume l = Volume::dense({26, 22, 64}, VoxelType::U8, glm::dmat4(1.0));
    auto ls = l.as<std::uint8_t>();
    for (std::int64_t k = 0; k < 64; ++k)
        for (std::int64_t j = 0; j < 22; ++j)
            for (std::int64_t i = 0; i < 26; ++i) {
                const double r =
                    std::sqrt((i - 12.5) * (i - 12.5) + (j - 10.5) * (j - 10.5) + (k - 30.0) * (k - 30.0) * 0.4);
                ls[l.linear_index(i, j, k)] = r < 6 ? 2 : r < 10 ? 1 : (i > 18 && j < 6) ? 7 : 0;
            }
    save_volume(l, dir / "l.nii");

    struct Case {
        std::string name;
        std::vector<double> isos;
        bool labels;
    };
    const std::vector<Case> cases = {{"v.nrrd", {500.0}, false},        // ties with samples
                                     {"g.nrrd", {700.5, 820.0}, false}, // two surfaces interleaved
                                     {"f.nii", {620.25}, false},
                                     {"l.nii", {}, true}};
    std::size_t overlapped = 0, shrunk = 0;
    for (const auto& c : cases) {
        for (std::size_t extra :
             {std::size_t(800) << 10, std::size_t(1600) << 10, std::size_t(2400) << 10, std::size_t(3200) << 10}) {
            const std::string what = c.name + " extra " + std::to_string(extra >> 10) + " KiB";
            SCOPED_TRACE(what);
            StreamOptions so;
            so.isos = c.isos;
            so.labels = c.labels;
            so.extract.chunk_size = 8;
            so.extract.threads = 2;
            so.memory_budget = budget_over_fixed(dir / c.name, 8, extra);
            auto run = [&](const StreamOptions& o, MeshSink& sink) {
                auto src = open_volume_stream(dir / c.name);
                return stream_extract(*src, o, sink);
            };
            KeepSink on;
            const auto st_on = run(so, on);
            EXPECT_LE(st_on.peak_bytes, so.memory_budget);
            overlapped += st_on.plan.overlap;
            if (st_on.plan.overlap) {
                // The planner's own sum for two slabs and two outputs in flight.
                EXPECT_LE(st_on.plan.fixed_bytes + 2 * (st_on.plan.slab_bytes + st_on.plan.output_estimate),
                          so.memory_budget);
            }
            // Serial, same plan: the same pieces.
            StreamOptions same = so;
            same.overlap = false;
            same.max_layers_per_slab = st_on.plan.layers_per_slab;
            KeepSink off;
            const auto st_off = run(same, off);
            EXPECT_FALSE(st_off.plan.overlap);
            ASSERT_EQ(st_off.plan.chunk_size, st_on.plan.chunk_size);
            ASSERT_EQ(st_off.plan.layers_per_slab, st_on.plan.layers_per_slab);
            ASSERT_EQ(st_off.plan.slabs, st_on.plan.slabs);
            EXPECT_EQ(st_off.slabs_read, st_on.slabs_read);
            EXPECT_GT(on.pieces.size(), 0u);
            expect_same_pieces(off.pieces, on.pieces, "same plan");
            // Serial, its own plan (taller slabs): the same welded surfaces, vertex for vertex.
            StreamOptions own = so;
            own.overlap = false;
            CollectSink a, b;
            run(so, a);
            const auto st_own = run(own, b);
            EXPECT_LE(st_own.peak_bytes, so.memory_budget);
            shrunk += st_own.plan.layers_per_slab > st_on.plan.layers_per_slab;
            ASSERT_EQ(a.meshes.size(), b.meshes.size());
            for (std::size_t s = 0; s < a.meshes.size(); ++s) {
                EXPECT_GT(a.meshes[s].triangles.size(), 100u);
                EXPECT_TRUE(same_bits(a.meshes[s].positions, b.meshes[s].positions)) << "surface " << s;
                EXPECT_TRUE(same_bits(a.meshes[s].triangles, b.meshes[s].triangles)) << "surface " << s;
            }
        }
    }
    // The budgets must exercise the pipeline, and the planner must give it lower slabs.
    EXPECT_GE(overlapped, 12u);
    EXPECT_GE(shrunk, 6u);
}

// The files written with overlap == without, byte for byte: .pvtp pieces and
// summary on one plan, assembled .ply/.stl also each on its own plan.
TEST(Stream, OverlapWritesTheSameFiles) {
    TempDir dir;
    const Volume v = ball({32, 30, 80}, VoxelType::I16, oblique({0.9, 0.8, 1.2}, {0, 0, 0}, true));
    save_volume(v, dir / "v.nii");
    for (const char* name : {"out.pvtp", "out.ply", "out.stl"}) {
        SCOPED_TRACE(name);
        for (bool same_plan : {true, false}) {
            if (std::string(name) == "out.pvtp" && !same_plan) continue; // another plan: other pieces
            std::vector<std::string> listing[2], bytes[2];
            int layers = 0;
            for (int overlap : {1, 0}) {
                const fs::path out = dir / (overlap ? "on" : "off");
                fs::create_directories(out);
                auto src = open_volume_stream(dir / "v.nii");
                StreamOptions so;
                so.isos = {640.0};
                so.extract.chunk_size = 8;
                so.memory_budget = budget_over_fixed(dir / "v.nii", 8, std::size_t(1600) << 10);
                so.overlap = overlap;
                if (!overlap && same_plan) so.max_layers_per_slab = layers;
                auto sink = make_mesh_sink({out / name});
                const auto st = stream_extract(*src, so, *sink);
                if (overlap) {
                    EXPECT_TRUE(st.plan.overlap);
                    EXPECT_GT(st.plan.slabs, 3u);
                    layers = st.plan.layers_per_slab;
                }
                listing[overlap] = files_in(out);
                for (const auto& f : listing[overlap]) bytes[overlap].push_back(read_file(out / f));
            }
            EXPECT_EQ(listing[0], listing[1]);
            EXPECT_GT(listing[1].size(), 0u);
            EXPECT_TRUE(bytes[0] == bytes[1]) << "same plan " << same_plan;
            fs::remove_all(dir / "on");
            fs::remove_all(dir / "off");
        }
    }
}

// A gzip NRRD cut short, found by the reader thread in the middle of the
// slabs (the index is given, as MPI ranks give it, so that no index pass
// finds it first): the same iso::Error as without overlap, after some pieces
// were written; nothing at the output path, no temporaries, no thread left.
// A sink that fails at its third piece: its error, from the writer thread.
TEST(Stream, OverlapReaderAndWriterErrorsPropagate) {
    TempDir dir;
    const Volume v = tube({24, 24, 100});
    save_volume(v, dir / "gz.nrrd", true);
    fs::copy_file(dir / "gz.nrrd", dir / "cutgz.nrrd");
    fs::resize_file(dir / "cutgz.nrrd", fs::file_size(dir / "gz.nrrd") * 6 / 10);
    std::shared_ptr<const ChunkIndex> index;
    {
        auto full = open_volume_stream(dir / "gz.nrrd");
        index = build_chunk_index(*full, 8, std::size_t(16) << 20);
    }
    StreamOptions so;
    so.isos = {700};
    so.extract.chunk_size = 8;
    so.extract.threads = 2;
    so.index = index;
    so.memory_budget = budget_over_fixed(dir / "gz.nrrd", 8, std::size_t(500) << 10);
    {
        // The overlapped plan, also given to the serial run (which would make taller slabs).
        auto src = open_volume_stream(dir / "gz.nrrd");
        const StreamPlan plan = plan_stream(src->header(), so, index.get());
        ASSERT_TRUE(plan.overlap);
        ASSERT_GT(plan.slabs, 6u);
        so.max_layers_per_slab = plan.layers_per_slab;
    }
    std::string message[2];
    for (int overlap : {1, 0}) {
        SCOPED_TRACE(overlap ? "overlap" : "serial");
        so.overlap = overlap;
        auto src = open_volume_stream(dir / "cutgz.nrrd");
        std::size_t pieces = 0;
        try {
            auto sink = make_mesh_sink({dir / "out.ply"});
            ForwardSink counting(*sink);
            try {
                const auto st = stream_extract(*src, so, counting);
                ADD_FAILURE() << "a truncated gzip streamed, " << st.plan.slabs << " slabs";
            } catch (...) {
                pieces = counting.pieces;
                throw;
            }
        } catch (const Cancelled&) {
            ADD_FAILURE() << "a read error came out as a cancel";
        } catch (const Error& e) {
            message[overlap] = e.what();
            EXPECT_NE(message[overlap].find("cutgz.nrrd"), std::string::npos) << e.what();
        }
        EXPECT_GT(pieces, 1u) << "the error should come in the middle of the slabs";
        EXPECT_FALSE(fs::exists(dir / "out.ply"));
        EXPECT_EQ(files_in(dir.path()), (std::vector<std::string>{"cutgz.nrrd", "gz.nrrd"}));
        EXPECT_EQ(stream_threads_running(), 0u) << "a reader or writer thread is left running";
    }
    EXPECT_EQ(message[0], message[1]);

    // The writer fails.
    for (int overlap : {1, 0}) {
        SCOPED_TRACE(overlap ? "overlap, writer" : "serial, writer");
        so.overlap = overlap;
        auto src = open_volume_stream(dir / "gz.nrrd");
        auto sink = make_mesh_sink({dir / "out.stl"});
        ForwardSink failing(*sink, 2);
        try {
            stream_extract(*src, so, failing);
            ADD_FAILURE() << "the failing sink did not fail";
        } catch (const Cancelled&) {
            ADD_FAILURE() << "a write error came out as a cancel";
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()).find("test sink"), 0u) << e.what();
            EXPECT_NE(std::string(e.what()).find("disk full"), std::string::npos) << e.what();
        }
        EXPECT_EQ(failing.pieces, 2u);
        EXPECT_EQ(stream_threads_running(), 0u) << "a reader or writer thread is left running";
    }
}

// Cancelling half-way with overlap: iso::Cancelled, the user's file kept, no
// pieces or temporaries, and no reader or writer thread left (both were
// running during the extraction); the extraction stops at
// the first progress call that asks it to (no further progress calls).
TEST(Stream, OverlapCancelStopsEveryStep) {
    TempDir dir;
    const Volume v = tube({24, 24, 120});
    save_volume(v, dir / "v.nrrd", false);
    for (const char* name : {"out.pvtp", "out.ply", "out.stl"}) {
        SCOPED_TRACE(name);
        { std::ofstream(dir / name) << "the user's file"; }
        auto src = open_volume_stream(dir / "v.nrrd");
        StreamOptions so;
        so.isos = {700};
        so.extract.chunk_size = 8;
        so.extract.threads = 2;
        so.memory_budget = budget_over_fixed(dir / "v.nrrd", 8, std::size_t(500) << 10);
        {
            const StreamPlan plan = plan_stream(src->header(), so);
            ASSERT_TRUE(plan.overlap);
            ASSERT_GT(plan.slabs, 8u);
        }
        std::atomic<int> calls_after{0};
        std::atomic<bool> asked{false};
        std::atomic<std::size_t> seen_running{0};
        so.progress = [&](double f, std::string_view) {
            seen_running = std::max(seen_running.load(), stream_threads_running());
            if (asked) ++calls_after;
            if (f > 0.6) asked = true;
            return !asked;
        };
        std::size_t pieces = 0;
        {
            auto sink = make_mesh_sink({dir / name});
            ForwardSink counting(*sink);
            EXPECT_THROW(stream_extract(*src, so, counting), Cancelled);
            pieces = counting.pieces;
        }
        EXPECT_GT(pieces, 1u) << "cancelled after some pieces were written";
        EXPECT_EQ(calls_after.load(), 0);
        EXPECT_EQ(seen_running.load(), 2u) << "the reader and the writer run while the extraction reports progress";
        EXPECT_EQ(stream_threads_running(), 0u) << "a reader or writer thread is left running";
        EXPECT_EQ(read_file(dir / name), "the user's file");
        EXPECT_EQ(files_in(dir.path()), (std::vector<std::string>{name, "v.nrrd"}));
        fs::remove(dir / name);
    }
}

// ---- memory ------------------------------------------------------------------------------

std::size_t status_kib(const char* key) {
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind(key, 0) == 0) return std::size_t(std::atoll(line.c_str() + std::strlen(key)));
    return 0;
}

// Streams the 128 MiB volume in `budget_mib` and checks the engine's
// accounting and the growth of resident memory against the budget plus the
// stated constant; returns the plan. `index`: given (no index pass, whose
// slabs as large as the budget would otherwise make the peak).
StreamPlan check_memory_bound(const TempDir& dir, std::size_t budget_mib,
                              std::shared_ptr<const ChunkIndex> index = {}) {
    const std::size_t budget = budget_mib << 20;
    // Peak resident memory from here on: reset the high-water mark (Linux: clear_refs 5).
    { std::ofstream("/proc/self/clear_refs") << "5"; }
    const std::size_t base_kib = status_kib("VmRSS:");
    auto src = open_volume_stream(dir / "big.nhdr");
    StreamOptions so;
    so.isos = {500.0};
    so.memory_budget = budget;
    so.extract.threads = 2;
    so.index = index;
    auto sink = make_mesh_sink({dir / "big.ply"});
    const auto st = stream_extract(*src, so, *sink);
    const std::size_t hwm_kib = status_kib("VmHWM:");
    EXPECT_EQ(st.index_pass, !index);
    const auto ms = sink->stats()[0];
    EXPECT_GT(ms.triangles, 100000u);
    EXPECT_LE(st.peak_bytes, budget);
    // The stated constant: 24 MiB beyond the budget for the program's own
    // growth (allocator arenas of the TBB threads and of the reader and
    // writer threads, VTK/zlib buffers, stdio buffers).
    const double grown_mib = double(hwm_kib - std::min(hwm_kib, base_kib)) / 1024.0;
    std::printf("128 MiB int16 volume, budget %zu MiB: engine peak %.1f MiB, VmHWM grew %.1f MiB over %.1f MiB; %zu "
                "slabs of %d layers, chunk %d%s, "
                "read %.2f s, extract %.2f s, weld %.2f s, write %.2f s, %zu triangles\n",
                budget_mib, double(st.peak_bytes) / 1048576.0, grown_mib, double(base_kib) / 1024.0, st.plan.slabs,
                st.plan.layers_per_slab, st.plan.chunk_size, st.plan.overlap ? ", overlapped" : "", st.read_seconds,
                st.extract_seconds, st.weld_seconds, st.write_seconds, std::size_t(ms.triangles));
    // Under AddressSanitizer freed memory sits in its quarantine (256 MiB by
    // default) and every allocation has red zones: resident memory says
    // nothing about the engine there, so only the engine's accounting is checked.
#if ISOSCOPE_TEST_ASAN
    std::printf("AddressSanitizer build: the resident-memory bound is not checked\n");
#else
    EXPECT_LE(grown_mib, double(budget_mib) + 24.0);
#endif
    return st.plan;
}

TEST(Stream, A128MiBVolumeStreamsWithin32MiB) {
    TempDir dir;
    // 512 x 512 x 256 int16 (128 MiB), never held whole.
    test::write_big_ball(dir.path(), 256, 0.8, false);
    // 32 MiB: two slabs and their output do not fit, the steps run one after another.
    const StreamPlan serial = check_memory_bound(dir, 32);
    EXPECT_FALSE(serial.overlap);
    EXPECT_GT(serial.slabs, 4u);
    // 96 MiB: overlapped (two slabs of samples and two of output in flight);
    // the index is given so that the peak is the pipeline's.
    std::shared_ptr<const ChunkIndex> index;
    {
        auto src = open_volume_stream(dir / "big.nhdr");
        index = build_chunk_index(*src, 32, std::size_t(16) << 20);
    }
    const StreamPlan overlapped = check_memory_bound(dir, 96, index);
    EXPECT_TRUE(overlapped.overlap);
    EXPECT_GT(overlapped.slabs, 2u);
}

} // namespace
} // namespace iso
