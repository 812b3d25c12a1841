// Piece summaries and their merge (renderer/surface/components.hpp) and the
// chunk partition (renderer/surface/partition.hpp), without MPI: an in-memory
// surface is cut into pieces by chunk-id ranges exactly as the ranks of a
// distributed job cut it, and the merged statistics must equal those of the
// whole welded mesh (mesh_stats, and an independent union-find count).
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "io/mesh.hpp"
#include "io/volume_io.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "tests/support/test_util.hpp"
#include "renderer/core/stream_mesh.hpp"
#include "renderer/surface/components.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/partition.hpp"
#include "renderer/surface/analysis.hpp"

using namespace iso;
using iso::test::sample_field;

namespace {

// A torus about the j axis of the oblique phantom grid (its ring in the i-k
// plane): one component; a piece cut between two k planes through its middle
// holds two separate arcs, joined only through the other pieces.
Volume torus(std::array<std::int64_t, 3> dims, double R, double r) {
    const glm::dvec3 c(0.0);
    const glm::dmat4 a = iso::test::oblique_affine(dims, 1.0, c);
    const glm::dmat3 rot = iso::test::phantom_rotation();
    return sample_field(dims, a, [&](glm::dvec3 p) {
        const glm::dvec3 q = glm::transpose(rot) * (p - c); // grid-aligned frame
        const double ring = std::hypot(q.x, q.z) - R;
        return r - std::hypot(ring, q.y);
    });
}

// Two balls of different radii: two components.
Volume two_balls(std::array<std::int64_t, 3> dims) {
    const glm::dmat4 a = make_affine(glm::dvec3(1.0, 1.1, 0.9), glm::dvec3(0.0), glm::dmat3(1.0));
    return sample_field(dims, a, [&](glm::dvec3 p) {
        const double d1 = 9.0 - glm::length(p - glm::dvec3(12, 12, 10));
        const double d2 = 5.0 - glm::length(p - glm::dvec3(28, 26, 30));
        return std::max(d1, d2);
    });
}

// Connected components of a whole mesh counted independently of the code
// under test: breadth-first over triangles sharing a vertex.
std::size_t count_components(const Mesh& m) {
    std::vector<std::vector<std::uint32_t>> tris_of(m.positions.size());
    for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
        for (auto v : m.triangles[t]) tris_of[v].push_back(t);
    std::vector<char> seen(m.triangles.size(), 0);
    std::size_t n = 0;
    for (std::uint32_t t0 = 0; t0 < m.triangles.size(); ++t0) {
        if (seen[t0]) continue;
        ++n;
        std::vector<std::uint32_t> stack{t0};
        seen[t0] = 1;
        while (!stack.empty()) {
            const auto t = stack.back();
            stack.pop_back();
            for (auto v : m.triangles[t])
                for (auto u : tris_of[v])
                    if (!seen[u]) {
                        seen[u] = 1;
                        stack.push_back(u);
                    }
        }
    }
    return n;
}

struct Split {
    std::vector<SurfacePiece> pieces;
    SurfaceSummary merged;
};

// `far`: summarize every piece about a point far from the surface (as ranks
// do before the whole's bounds are known) instead of the whole's centre.
Split split(const Extractor& x, const ChunkedSurface& s, int nranks, bool far = false) {
    const auto& idx = x.index();
    const double isos[1] = {s.iso};
    const auto plan = partition_chunks(idx, isos, nranks);
    Split out;
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& r : plan) {
        out.pieces.push_back(weld_piece(s, r, idx.dims(), idx.chunk_size()));
        const auto [a, b] = piece_bounds(out.pieces.back().mesh);
        lo = glm::min(lo, a);
        hi = glm::max(hi, b);
    }
    std::vector<PieceSummary> sums;
    // Through the byte form, as the ranks send them.
    for (const auto& p : out.pieces)
        sums.push_back(summarize_piece(p, far ? glm::dvec3(400.0, -250.0, 130.0) : volume_origin(lo, hi)));
    // Through the byte form, as the ranks send them.
    const auto sent = deserialize_piece_summaries(serialize(std::span<const PieceSummary>(sums)));
    out.merged = merge_summaries(sent);
    return out;
}

// Every piece vertex that another piece also holds is on both seams, at the
// same position bit for bit; and the union of the pieces' positions is the
// whole mesh's.
void expect_consistent_seams(const Split& sp, const Mesh& whole) {
    std::map<std::array<float, 3>, int> count;
    for (const auto& p : sp.pieces) {
        std::set<std::array<float, 3>> mine;
        for (const auto& v : p.mesh.positions) mine.insert({v.x, v.y, v.z});
        for (const auto& k : mine) ++count[k];
    }
    std::set<std::array<float, 3>> all;
    for (const auto& v : whole.positions) all.insert({v.x, v.y, v.z});
    EXPECT_EQ(count.size(), all.size()) << "pieces hold other positions than the whole mesh";
    for (const auto& p : sp.pieces) {
        std::set<std::uint32_t> seam;
        for (const auto& [key, v] : p.seam) seam.insert(v);
        for (std::uint32_t v = 0; v < p.mesh.positions.size(); ++v) {
            const auto& q = p.mesh.positions[v];
            if (count[{q.x, q.y, q.z}] > 1) {
                EXPECT_TRUE(seam.count(v)) << "a shared vertex is missing from a seam";
            }
        }
    }
}

} // namespace

TEST(Partition, BalancesWeightsContiguously) {
    // 3 heavy chunks among zeros: 3 ranks get one each; zeros between ranges go to the later rank.
    const std::vector<std::uint32_t> w{0, 1, 0, 0, 1, 0, 1, 0};
    const auto p = partition_weights(w, 3);
    ASSERT_EQ(p.size(), 3u);
    EXPECT_EQ(p[0], (ChunkRange{0, 2}));
    EXPECT_EQ(p[1], (ChunkRange{2, 5}));
    EXPECT_EQ(p[2], (ChunkRange{5, 8}));
    // Uneven weights: 100 chunks of weight 1 and 2: every rank within one chunk's weight of the mean.
    std::vector<std::uint32_t> u(100);
    for (std::size_t i = 0; i < u.size(); ++i) u[i] = 1 + (i % 7 == 0);
    const double total = std::accumulate(u.begin(), u.end(), 0.0);
    for (int n : {1, 2, 3, 4, 7}) {
        const auto q = partition_weights(u, n);
        std::size_t next = 0;
        for (const auto& r : q) {
            EXPECT_EQ(r.first, next) << "contiguous, in rank order";
            next = r.last;
            const double sum = std::accumulate(u.begin() + long(r.first), u.begin() + long(r.last), 0.0);
            EXPECT_LE(std::abs(sum - total / n), 2.0) << n << " ranks";
        }
        EXPECT_EQ(next, u.size()) << "every chunk assigned";
    }
}

TEST(Partition, MoreRanksThanActiveChunksGivesEmptyRanges) {
    const std::vector<std::uint32_t> w{0, 0, 1, 0, 1, 0};
    const auto p = partition_weights(w, 4);
    std::size_t nonempty_work = 0, next = 0;
    for (const auto& r : p) {
        EXPECT_EQ(r.first, next);
        next = r.last;
        std::uint32_t sum = 0;
        for (auto i = r.first; i < r.last; ++i) sum += w[i];
        EXPECT_LE(sum, 1u) << "no rank takes both active chunks while others idle";
        nonempty_work += sum > 0;
    }
    EXPECT_EQ(next, w.size());
    EXPECT_EQ(nonempty_work, 2u);
    // Nothing active at all: rank 0 holds every chunk, the rest are empty.
    const std::vector<std::uint32_t> z(5, 0);
    const auto e = partition_weights(z, 3);
    EXPECT_EQ(e[0], (ChunkRange{0, 5}));
    EXPECT_TRUE(e[1].empty() && e[2].empty());
    EXPECT_THROW(partition_weights(z, 0), Error);
}

TEST(Partition, WeightsCountActiveSurfacesFromTheIndex) {
    const Volume v = two_balls({41, 37, 45});
    const ChunkIndex idx(v, 8);
    const double isos[2] = {0.0, 4.0};
    const auto w = chunk_weights(idx, isos);
    std::size_t checked = 0;
    for (std::size_t id = 0; id < w.size(); ++id) {
        const std::uint32_t expect = std::uint32_t(idx.active(id, 0.0)) + std::uint32_t(idx.active(id, 4.0));
        EXPECT_EQ(w[id], expect);
        checked += expect > 0;
    }
    EXPECT_GT(checked, 0u);
    // Balanced by active chunks: with 4 ranks each gets about a quarter of the weight.
    const auto p = partition_chunks(idx, isos, 4);
    const double total = std::accumulate(w.begin(), w.end(), 0.0);
    for (const auto& r : p) {
        const double sum = std::accumulate(w.begin() + long(r.first), w.begin() + long(r.last), 0.0);
        EXPECT_LE(std::abs(sum - total / 4), 2.0);
    }
}

TEST(Components, TorusCutIntoPiecesIsOneComponentWithTheWholeStats) {
    const Volume v = torus({54, 22, 32}, 12.0, 4.0);
    ExtractOptions eo;
    eo.chunk_size = 8;
    const Extractor x(v, eo);
    const ChunkedSurface s = x.extract(0.0);
    const Mesh whole = weld(s);
    ASSERT_GT(whole.triangles.size(), 1000u);
    ASSERT_EQ(count_components(whole), 1u);
    const MeshStats ms = mesh_stats(whole);
    std::size_t most_pieces = 0; // the most components one piece holds on its own
    for (int n : {1, 2, 3, 4, 7}) {
        SCOPED_TRACE(n);
        const Split sp = split(x, s, n);
        EXPECT_EQ(sp.merged.triangles, ms.triangles);
        EXPECT_EQ(sp.merged.vertices, ms.vertices) << "seam duplicates subtracted";
        // Sums of the same double terms in another order: 1e-12 relative.
        EXPECT_NEAR(sp.merged.area, ms.area, 1e-12 * ms.area);
        EXPECT_NEAR(sp.merged.volume, ms.volume, 1e-12 * std::abs(ms.volume));
        EXPECT_EQ(sp.merged.components, 1u) << "the ring is joined across the seams";
        EXPECT_EQ(sp.merged.boundary_edges, 0u) << "the ring is closed: every seam edge has its other side";
        EXPECT_EQ(sp.merged.largest.triangles, ms.triangles);
        EXPECT_NEAR(sp.merged.largest.area, ms.area, 1e-12 * ms.area);
        if (n > 1) {
            std::size_t seam = 0, most = 0;
            for (const auto& p : sp.pieces) {
                seam += p.seam.size();
                most = std::max(most, summarize_piece(p, glm::dvec3(0.0)).components.size());
            }
            EXPECT_GT(seam, 0u);
            most_pieces = std::max(most_pieces, most);
        }
        expect_consistent_seams(sp, whole);
        // Pieces summarized about a far point: the moments move every volume
        // to the whole's origin (1e-9: the far origin costs digits).
        const Split far = split(x, s, n, true);
        EXPECT_NEAR(far.merged.volume, ms.volume, 1e-9 * std::abs(ms.volume));
        EXPECT_NEAR(far.merged.largest.volume, ms.volume, 1e-9 * std::abs(ms.volume));
        EXPECT_EQ(far.merged.components, 1u);
    }
    EXPECT_GE(most_pieces, 2u) << "some piece holds separate arcs of the ring: the merge must join them";
}

TEST(Components, SeparateBallsStaySeparateAndTheLargestIsFound) {
    const Volume v = two_balls({41, 37, 45});
    ExtractOptions eo;
    eo.chunk_size = 6;
    const Extractor x(v, eo);
    const ChunkedSurface s = x.extract(0.0);
    const Mesh whole = weld(s);
    ASSERT_EQ(count_components(whole), 2u);
    const SurfaceSummary ref = summarize_mesh(whole);
    EXPECT_EQ(ref.components, 2u);
    // The larger ball (radius 9) against the analytic area 4 pi r^2: within 3 %
    // (marching cubes on a ~1 mm grid cuts corners: measured ~1 %).
    EXPECT_NEAR(ref.largest.area, 4 * M_PI * 81, 0.03 * 4 * M_PI * 81);
    EXPECT_NEAR(ref.largest.volume, 4.0 / 3 * M_PI * 729, 0.03 * 4.0 / 3 * M_PI * 729);
    for (int n : {2, 4, 5}) {
        SCOPED_TRACE(n);
        const Split sp = split(x, s, n);
        EXPECT_EQ(sp.merged.components, 2u);
        EXPECT_EQ(sp.merged.largest.triangles, ref.largest.triangles);
        EXPECT_NEAR(sp.merged.largest.area, ref.largest.area, 1e-12 * ref.largest.area);
        EXPECT_NEAR(sp.merged.largest.volume, ref.largest.volume, 1e-9 * ref.largest.volume);
        EXPECT_EQ(sp.merged.vertices, whole.positions.size());
        expect_consistent_seams(sp, whole);
    }
}

TEST(Components, KeyLeavesRangeMatchesChunkBoxes) {
    // dims 10x9x7, chunks of 4 cells: counts 3x2x2. A sample on a chunk corner
    // belongs to up to 8 chunks; an x edge on the chunk face y = 4 to two.
    const std::array<std::int64_t, 3> d{10, 9, 7};
    auto key = [&](std::int64_t i, std::int64_t j, std::int64_t k, int axis) {
        return (std::uint64_t(i + d[0] * (j + d[1] * k)) << 2) | std::uint64_t(axis);
    };
    const ChunkRange all{0, 12};
    EXPECT_FALSE(key_leaves_range(key(4, 4, 4, 3), all, d, 4));
    // Sample (4,4,4): chunks (0|1, 0|1, 0|1) = every chunk but those with x = 2.
    EXPECT_TRUE(key_leaves_range(key(4, 4, 4, 3), ChunkRange{0, 6}, d, 4)); // misses z = 1
    // x edge from (5,4,2): x chunk 1, y chunks 0 and 1, z chunk 0: ids 1 and 4.
    EXPECT_FALSE(key_leaves_range(key(5, 4, 2, 0), ChunkRange{1, 5}, d, 4));
    EXPECT_TRUE(key_leaves_range(key(5, 4, 2, 0), ChunkRange{2, 5}, d, 4));
    // Interior of chunk 0: only chunk 0.
    EXPECT_FALSE(key_leaves_range(key(1, 2, 3, 1), ChunkRange{0, 1}, d, 4));
    // The last sample (9,8,6) lies in the last chunk only (no chunk beyond the border).
    EXPECT_FALSE(key_leaves_range(key(9, 8, 6, 3), ChunkRange{11, 12}, d, 4));
}

TEST(Components, SummaryBytesRoundTrip) {
    PieceSummary s;
    s.triangles = 7;
    s.vertices = 9;
    s.area = 1.25;
    s.volume = -3.5;
    s.components = {{3, 0.5, 1.0, glm::dvec3(1, 2, 3)}, {4, 0.75, -4.5, glm::dvec3(-1, 0, 0.5)}};
    s.origin = glm::dvec3(7, 8, 9);
    s.bounds_min = glm::dvec3(-1, -2, -3);
    s.bounds_max = glm::dvec3(1, 2, 3);
    s.seam = {{17, 0}, {99, 1}, {1ull << 40, 0xFFFFFFFFu}};
    s.boundary_edges = 5;
    s.seam_boundary = {{17, 99}, {99, 1ull << 40}};
    const auto t = deserialize_piece_summary(serialize(s));
    EXPECT_EQ(t.triangles, 7u);
    EXPECT_EQ(t.vertices, 9u);
    EXPECT_EQ(t.area, 1.25);
    EXPECT_EQ(t.volume, -3.5);
    ASSERT_EQ(t.components.size(), 2u);
    EXPECT_EQ(t.components[1].triangles, 4u);
    EXPECT_EQ(t.components[1].volume, -4.5);
    EXPECT_EQ(t.components[0].moment, glm::dvec3(1, 2, 3));
    EXPECT_EQ(t.origin, s.origin);
    EXPECT_EQ(t.bounds_max, s.bounds_max);
    EXPECT_EQ(t.boundary_edges, 5u);
    EXPECT_EQ(t.seam_boundary, s.seam_boundary);
    const PieceSummary two[2] = {s, PieceSummary{}};
    const auto back = deserialize_piece_summaries(serialize(std::span<const PieceSummary>(two)));
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(back[0].seam, s.seam);
    EXPECT_TRUE(back[1].components.empty());
    EXPECT_EQ(t.seam, s.seam);
    const auto bytes = serialize(s);
    EXPECT_THROW(deserialize_piece_summary(std::string_view(bytes).substr(0, bytes.size() - 3)), Error);
}

TEST(Components, BundledCtAtATieAndOffIt) {
    // Integer CT: at 500 many samples equal the iso value (vertices on samples,
    // keys 4 x sample + 3), at 500.5 none do.
    const Volume v = load_volume(ISOSCOPE_DATA_DIR "/headsq.nhdr");
    ExtractOptions eo;
    eo.chunk_size = 8;
    const Extractor x(v, eo);
    for (double iso : {500.0, 500.5}) {
        SCOPED_TRACE(iso);
        const ChunkedSurface s = x.extract(iso);
        const Mesh whole = weld(s);
        const SurfaceSummary ref = summarize_mesh(whole);
        EXPECT_EQ(ref.components, count_components(whole));
        const std::size_t open_edges = measure_surface(whole).boundary_edges;
        EXPECT_GT(open_edges, 0u) << "the skin is cut by the volume's border";
        EXPECT_EQ(ref.boundary_edges, open_edges);
        for (int n : {2, 4}) {
            SCOPED_TRACE(n);
            const Split sp = split(x, s, n);
            EXPECT_EQ(sp.merged.triangles, whole.triangles.size());
            EXPECT_EQ(sp.merged.vertices, whole.positions.size());
            EXPECT_EQ(sp.merged.components, ref.components);
            EXPECT_EQ(sp.merged.boundary_edges, open_edges) << "edges on the seams are not the boundary";
            EXPECT_EQ(sp.merged.largest.triangles, ref.largest.triangles);
            EXPECT_NEAR(sp.merged.area, ref.area, 1e-12 * ref.area);
            EXPECT_NEAR(sp.merged.volume, ref.volume, 1e-12 * std::abs(ref.volume));
            expect_consistent_seams(sp, whole);
        }
    }
}

// summarize_piece runs in parallel (the unions, the edges, the sums in fixed
// blocks): its summary is the same bit for bit on one thread and on four, for
// pieces of several blocks with seams, many components and a boundary.
TEST(Components, APieceSummaryDoesNotDependOnTheThreadCount) {
    const Volume v = load_volume(ISOSCOPE_DATA_DIR "/headsq.nhdr");
    ExtractOptions eo;
    eo.chunk_size = 8;
    const Extractor x(v, eo);
    const ChunkedSurface s = x.extract(500.0);
    const Split sp = split(x, s, 2);
    for (const SurfacePiece& p : sp.pieces) {
        ASSERT_GT(p.mesh.triangles.size(), 16384u) << "more than one block of sums";
        ASSERT_FALSE(p.seam.empty());
        PieceSummary one, four;
        tbb::task_arena(1).execute([&] { one = summarize_piece(p, glm::dvec3(3.0, -4.0, 5.0)); });
        tbb::task_arena(4).execute([&] { four = summarize_piece(p, glm::dvec3(3.0, -4.0, 5.0)); });
        EXPECT_GT(one.components.size(), 1u);
        EXPECT_GT(one.boundary_edges, 0u);
        EXPECT_FALSE(one.seam_boundary.empty());
        EXPECT_EQ(serialize(one), serialize(four)) << "the same numbers, bit for bit";
    }
}

TEST(Components, SingleProcessStreamingReportsTheWholeMeshStatistics) {
    // core::stream_mesh summarizes each slab's piece as it passes (a
    // SummarizingSink before the .ply sink); the merge must equal the
    // in-memory mesh's statistics and components. A 1 MiB budget makes
    // several slabs of the bundled CT.
    iso::test::TempDir dir;
    core::StreamMeshRequest req;
    req.input = ISOSCOPE_DATA_DIR "/headsq.nhdr";
    req.output = dir / "s.ply";
    req.isos = {500.0, 1150.0};
    req.extract.chunk_size = 8;
    req.memory_budget = std::size_t(1) << 20;
    const auto r = core::stream_mesh(req);
    ASSERT_EQ(r.summaries.size(), 2u);
    EXPECT_GT(r.stream.slabs_read, 1u);
    const Volume v = load_volume(ISOSCOPE_DATA_DIR "/headsq.nhdr");
    for (std::size_t i = 0; i < 2; ++i) {
        SCOPED_TRACE(req.isos[i]);
        const Mesh whole = extract_isosurface(v, req.isos[i]);
        const SurfaceSummary ref = summarize_mesh(whole);
        const MeshStats ms = mesh_stats(whole);
        const auto& got = r.summaries[i];
        EXPECT_EQ(got.triangles, ms.triangles);
        EXPECT_EQ(got.vertices, ms.vertices);
        EXPECT_NEAR(got.area, ms.area, 1e-9 * ms.area);
        EXPECT_NEAR(got.volume, ms.volume, 1e-9 * std::abs(ms.volume));
        EXPECT_EQ(got.components, count_components(whole));
        EXPECT_EQ(got.boundary_edges, measure_surface(whole).boundary_edges)
            << "edges on the slab seams are not the boundary";
        EXPECT_EQ(got.largest.triangles, ref.largest.triangles);
        EXPECT_NEAR(got.largest.area, ref.largest.area, 1e-9 * ref.largest.area);
        EXPECT_NEAR(got.largest.volume, ref.largest.volume, 1e-9 * std::abs(ref.largest.volume));
    }
}

TEST(Components, ATieForTheLargestGoesToTheFirstInPieceOrder) {
    // Two pieces, no moments (volumes independent of the origin). A seam key
    // joins a component of piece 0 with piece 1's only one: 2 + 2 triangles,
    // area 1 + 1, as large as piece 0's other component. The tie goes to the
    // component that holds the first in piece order (piece 0's first).
    auto piece = [](std::vector<ComponentStats> comps, std::uint32_t seam_comp) {
        PieceSummary p;
        p.components = std::move(comps);
        p.seam = {{7, seam_comp}};
        p.bounds_min = glm::dvec3(-1.0);
        p.bounds_max = glm::dvec3(1.0);
        return p;
    };
    const ComponentStats half_a{2, 1.0, 10.0, glm::dvec3(0.0)}, half_b{2, 1.0, 20.0, glm::dvec3(0.0)};
    const ComponentStats whole{4, 2.0, 50.0, glm::dvec3(0.0)};
    {
        const PieceSummary pieces[2] = {piece({half_a, whole}, 0), piece({half_b}, 0)};
        const SurfaceSummary s = merge_summaries(pieces);
        EXPECT_EQ(s.components, 2u);
        EXPECT_EQ(s.largest.triangles, 4u);
        EXPECT_EQ(s.largest.volume, 30.0); // the joined halves
    }
    {
        const PieceSummary pieces[2] = {piece({whole, half_a}, 1), piece({half_b}, 0)};
        const SurfaceSummary s = merge_summaries(pieces);
        EXPECT_EQ(s.components, 2u);
        EXPECT_EQ(s.largest.triangles, 4u);
        EXPECT_EQ(s.largest.volume, 50.0); // the whole component
    }
}
