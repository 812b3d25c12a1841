// GPU marching cubes (compute shaders) against the CPU extractor, chunk by
// chunk and vertex by vertex (matched by key), on a real GL 4.5 context
// (EGL + llvmpipe in CI, the GPU where there is one).
#include "renderer/gpu/gpu_extract.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "gl_test.hpp"
#include "io/volume_io.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using GpuIsosurface = test::GlTest;

namespace {
// Compares two chunked surfaces chunk by chunk: same vertex keys, positions
// within `pos_tol` mm, normals within 1e-5, same triangles as key triples.
void expect_same(const ChunkedSurface& a, const ChunkedSurface& b, double pos_tol) {
    ASSERT_EQ(a.chunks.size(), b.chunks.size());
    std::size_t verts = 0, tris = 0;
    double worst = 0;
    for (std::size_t id = 0; id < a.chunks.size(); ++id) {
        const auto& ca = a.chunks[id];
        const auto& cb = b.chunks[id];
        ASSERT_EQ(ca.positions.size(), cb.positions.size()) << "chunk " << id;
        ASSERT_EQ(ca.triangles.size(), cb.triangles.size()) << "chunk " << id;
        ASSERT_EQ(ca.keys.size(), ca.positions.size());
        ASSERT_EQ(cb.keys.size(), cb.positions.size());
        std::map<std::uint64_t, std::size_t> kb;
        for (std::size_t i = 0; i < cb.keys.size(); ++i) kb[cb.keys[i]] = i;
        for (std::size_t i = 0; i < ca.keys.size(); ++i) {
            auto it = kb.find(ca.keys[i]);
            ASSERT_NE(it, kb.end()) << "chunk " << id << " key " << ca.keys[i];
            worst = std::max(worst, double(glm::length(ca.positions[i] - cb.positions[it->second])));
            if (!ca.normals.empty()) {
                EXPECT_LT(glm::length(ca.normals[i] - cb.normals[it->second]), 1e-5f) << "chunk " << id;
            }
        }
        auto as_keys = [](const ChunkMesh& m) {
            std::vector<std::array<std::uint64_t, 3>> t;
            for (auto tri : m.triangles) {
                std::array<std::uint64_t, 3> k{m.keys[tri[0]], m.keys[tri[1]], m.keys[tri[2]]};
                std::rotate(k.begin(), std::min_element(k.begin(), k.end()), k.end());
                t.push_back(k);
            }
            std::sort(t.begin(), t.end());
            return t;
        };
        EXPECT_EQ(as_keys(ca), as_keys(cb)) << "chunk " << id;
        auto sorted_border = [](std::vector<std::pair<std::uint64_t, std::uint32_t>> v, const ChunkMesh& m) {
            std::vector<std::uint64_t> k;
            for (auto& e : v) k.push_back(e.first);
            std::sort(k.begin(), k.end());
            return k;
        };
        EXPECT_EQ(sorted_border(ca.border, ca), sorted_border(cb.border, cb)) << "chunk " << id;
        verts += ca.positions.size();
        tris += ca.triangles.size();
    }
    EXPECT_LE(worst, pos_tol);
    EXPECT_GT(tris, 0u);
    ::testing::Test::RecordProperty("vertices", int(verts));
}

} // namespace

TEST_F(GpuIsosurface, ContextIsGl45) {
    const auto& info = test::gl_context().info();
    std::printf("GL: %s | %s | %s | platform %s\n", info.vendor.c_str(), info.renderer.c_str(), info.version.c_str(),
                info.platform.c_str());
    EXPECT_NE(info.version.find("4.5"), std::string::npos);
}

TEST_F(GpuIsosurface, SameAsCpuOnObliqueSphere) {
    const glm::dmat4 aff = glm::translate(glm::dmat4(1.0), glm::dvec3(-40, 12, 300)) *
                           glm::rotate(glm::dmat4(1.0), glm::radians(30.0), glm::normalize(glm::dvec3(1, 2, 0.5))) *
                           glm::scale(glm::dmat4(1.0), glm::dvec3(0.7, 0.9, -2.5));
    auto v = Volume::dense({30, 27, 21}, VoxelType::F32, aff);
    const glm::dvec3 c = glm::dvec3(aff * glm::dvec4(15, 13, 10, 1));
    for (std::int64_t k = 0; k < 21; ++k)
        for (std::int64_t j = 0; j < 27; ++j)
            for (std::int64_t i = 0; i < 30; ++i)
                v.as<float>()[v.linear_index(i, j, k)] =
                    float(11.0 - glm::length(v.index_to_world({double(i), double(j), double(k)}) - c));
    ExtractOptions opt{.chunk_size = 7, .keep_keys = true};
    const auto cpu = Extractor(v, opt).extract(0.25);
    GpuExtractStats st;
    const auto gpu = GpuExtractor(v, opt).extract(0.25, &st);
    expect_same(cpu, gpu, 1e-4); // 1e-5 voxel is 7e-6 mm; float rounding of coordinates near 300 mm is 3e-5
    EXPECT_GT(st.chunks, 0u);
    EXPECT_EQ(weld(cpu).triangles.size(), weld(gpu).triangles.size());
}

TEST_F(GpuIsosurface, SameAsCpuWithTiesAndNaN) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> u(0, 3);
    auto v = Volume::dense({19, 17, 16}, VoxelType::F32, glm::dmat4(1.0));
    for (auto& x : v.as<float>()) x = float(u(rng));
    v.as<float>()[v.linear_index(5, 5, 5)] = std::nanf("");
    v.as<float>()[v.linear_index(9, 3, 7)] = INFINITY;
    for (double iso : {1.0, 2.0, 2.5}) {
        ExtractOptions opt{.chunk_size = 6, .keep_keys = true};
        const auto cpu = Extractor(v, opt).extract(iso);
        const auto gpu = GpuExtractor(v, opt).extract(iso);
        expect_same(cpu, gpu, 0.0);
    }
}

TEST_F(GpuIsosurface, SmallBatchesGiveTheSameResult) {
    auto v = Volume::dense({40, 33, 29}, VoxelType::I16, glm::dmat4(1.0));
    std::mt19937 rng(9);
    std::uniform_int_distribution<int> u(-100, 100);
    for (auto& x : v.as<std::int16_t>()) x = std::int16_t(u(rng));
    ExtractOptions opt{.chunk_size = 8, .keep_keys = true};
    const auto cpu = Extractor(v, opt).extract(3.5);
    opt.memory_budget = 16 << 10; // below one chunk's buffers: one chunk per batch
    GpuExtractStats st;
    const auto gpu = GpuExtractor(v, opt).extract(3.5, &st);
    EXPECT_EQ(st.batches, st.chunks);
    EXPECT_GT(st.batches, 10u);
    expect_same(cpu, gpu, 0.0);
}

// Ties: every cut edge has its own vertex, at t clamped to
// [kEdgeMargin, 1 - kEdgeMargin], on both paths, bit for bit: integer
// checkerboards with every inside sample a tie, plateaus and single voxels
// equal to iso, the bundled CT at 500 and 1150 (int16: exact in float).
TEST_F(GpuIsosurface, SameAsCpuAtTies) {
    auto v = Volume::dense({21, 18, 17}, VoxelType::I16, glm::dmat4(1.0));
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 0; k < 17; ++k)
        for (std::int64_t j = 0; j < 18; ++j)
            for (std::int64_t i = 0; i < 21; ++i) {
                std::int16_t x = std::int16_t(499 + (i + 2 * j + k) % 3);             // three-level checkerboard
                if (i >= 12) x = (i + j + k) % 2 ? 500 : 499;                         // two-level
                if (k >= 12) x = 100;                                                 // background...
                if (k >= 12 && i >= 3 && i < 8 && j >= 2 && j < 9 && k < 16) x = 500; // ...a plateau
                if (k == 14 && i == 15 && j == 10) x = 500;                           // ...a single voxel
                s[v.linear_index(i, j, k)] = x;
            }
    for (double iso : {500.0, 501.0}) {
        ExtractOptions opt{.chunk_size = 5, .keep_keys = true};
        const auto cpu = Extractor(v, opt).extract(iso);
        const auto gpu = GpuExtractor(v, opt).extract(iso);
        expect_same(cpu, gpu, 0.0);
    }
    const Volume ct = read_nrrd(test::data("headsq.nhdr"));
    for (double iso : {500.0, 1150.0}) {
        ExtractOptions opt{.keep_keys = true};
        const auto cpu = Extractor(ct, opt).extract(iso);
        const auto gpu = GpuExtractor(ct, opt).extract(iso);
        expect_same(cpu, gpu, 0.0);
        EXPECT_EQ(weld(cpu).triangles.size(), weld(gpu).triangles.size());
    }
}
