// Clusters and levels of detail (renderer/lod/cluster_lod.hpp) on a closed
// marching-cubes sphere: level 0 is the mesh, reordered, and triangle_order
// names every triangle once; clusters hold at most their share, their
// bounds hold their triangles and their cones their normals; errors grow
// with the level; and, the point of locked borders, any choice of level per
// cell gives a closed surface (every edge twice, in opposite directions):
// no cracks, whatever the view picks. The stand-ins while moving (vertex
// clustering, lod::Proxy) keep the nearest vertex of each grid cell and
// stay within their stated error.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "renderer/lod/cluster_lod.hpp"
#include "renderer/surface/closest.hpp"
#include "tests/support/meshes.hpp"

using namespace iso;

namespace {

lod::BuildOptions small_cells() {
    lod::BuildOptions o;
    o.cell_triangles = 4096;
    o.cluster_triangles = 512;
    return o;
}

const Mesh& sphere() {
    static const Mesh m = test::sphere_mesh({1.0, -2.0, 3.0}, 30.0, 0.5); // ~ 80k triangles
    return m;
}

// Triangles of `c`'s cell at `level` (its clusters of that level).
std::vector<std::array<std::uint32_t, 3>> cell_level(const lod::ClusterLod& l, std::size_t cell, std::uint32_t level) {
    std::vector<std::array<std::uint32_t, 3>> t;
    for (const auto& c : l.clusters)
        if (c.cell == cell && c.level == level)
            for (std::uint32_t i = 0; i < c.index_count; i += 3)
                t.push_back(
                    {l.indices[c.first_index + i], l.indices[c.first_index + i + 1], l.indices[c.first_index + i + 2]});
    return t;
}

// Directed edges that have no opposite: a closed, consistently wound surface has none.
std::size_t open_edges(const std::vector<std::array<std::uint32_t, 3>>& tris) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> e;
    for (const auto& t : tris)
        for (int k = 0; k < 3; ++k) {
            const auto a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
            if (a == b) continue;
            ++e[{a, b}];
        }
    std::size_t open = 0;
    for (const auto& [k, n] : e) {
        const auto it = e.find({k.second, k.first});
        if (it == e.end() || it->second != n) ++open;
    }
    return open;
}

} // namespace

TEST(ClusterLod, LevelZeroIsTheMeshReorderedAndNamed) {
    const Mesh& m = sphere();
    ASSERT_EQ(open_edges(m.triangles), 0u) << "the test sphere must be closed";
    const auto l = lod::build_cluster_lod(m, small_cells());
    ASSERT_GT(l.cells.size(), 8u);
    ASSERT_EQ(l.level0_indices, 3 * m.triangles.size());
    ASSERT_EQ(l.triangle_order.size(), m.triangles.size());
    std::vector<int> seen(m.triangles.size(), 0);
    for (std::size_t i = 0; i < l.triangle_order.size(); ++i) {
        const auto t = l.triangle_order[i];
        ASSERT_LT(t, m.triangles.size());
        ++seen[t];
        for (int k = 0; k < 3; ++k) EXPECT_EQ(l.indices[3 * i + std::size_t(k)], m.triangles[t][std::size_t(k)]);
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
    EXPECT_EQ(l.level_triangles[0], m.triangles.size());
}

TEST(ClusterLod, ClustersBoundTheirTrianglesAndNormals) {
    const Mesh& m = sphere();
    const auto o = small_cells();
    const auto l = lod::build_cluster_lod(m, o);
    std::size_t coned = 0;
    for (const auto& c : l.clusters) {
        ASSERT_LE(c.index_count / 3, o.cluster_triangles);
        ASSERT_GT(c.index_count, 0u);
        ASSERT_LT(c.cell, l.cells.size());
        ASSERT_LT(c.level, l.cells[c.cell].levels);
        for (std::uint32_t i = 0; i < c.index_count; i += 3) {
            glm::vec3 p[3];
            for (int k = 0; k < 3; ++k) {
                p[k] = m.positions[l.indices[c.first_index + i + std::uint32_t(k)]];
                EXPECT_TRUE(glm::all(glm::greaterThanEqual(p[k], c.lo)) && glm::all(glm::lessThanEqual(p[k], c.hi)));
                EXPECT_LE(glm::length(p[k] - c.centre), c.radius * 1.0001f + 1e-5f);
            }
            const glm::vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
            if (c.cos_angle > 0.0f && glm::length(n) > 0.0f) {
                EXPECT_GE(glm::dot(glm::normalize(n), c.axis), c.cos_angle - 1e-5f);
            }
        }
        coned += c.cos_angle > 0.0f;
    }
    // A sphere's small clusters are nearly flat: most have a cone.
    EXPECT_GT(coned, l.clusters.size() / 2);
}

TEST(ClusterLod, CoarserLevelsHaveFewerTrianglesAndLargerErrors) {
    const auto l = lod::build_cluster_lod(sphere(), small_cells());
    ASSERT_GE(l.max_levels, 2);
    for (int k = 1; k < l.max_levels; ++k)
        EXPECT_LT(l.level_triangles[std::size_t(k)], l.level_triangles[std::size_t(k - 1)]);
    for (const auto& c : l.cells) {
        EXPECT_EQ(c.error[0], 0.0f);
        for (std::uint32_t k = 1; k < c.levels; ++k) {
            EXPECT_GE(c.error[k], c.error[k - 1]);
            EXPECT_LT(c.error[k], 30.0f); // below the sphere's radius
        }
    }
}

TEST(ClusterLod, AnyLevelPerCellIsCrackFree) {
    const auto l = lod::build_cluster_lod(sphere(), small_cells());
    std::mt19937 rng(7);
    for (int trial = 0; trial < 6; ++trial) {
        std::vector<std::array<std::uint32_t, 3>> tris;
        for (std::size_t c = 0; c < l.cells.size(); ++c) {
            // All at level 0, all at their coarsest, then random mixes.
            const std::uint32_t n = l.cells[c].levels;
            const std::uint32_t level = trial == 0 ? 0 : trial == 1 ? n - 1 : std::uint32_t(rng() % n);
            const auto t = cell_level(l, c, level);
            tris.insert(tris.end(), t.begin(), t.end());
        }
        EXPECT_EQ(open_edges(tris), 0u) << "trial " << trial;
    }
}

TEST(ClusterLod, TheLevelDrawnIsTheCoarsestWithinTheBound) {
    lod::Cell c;
    c.lo = glm::vec3(-1.0f);
    c.hi = glm::vec3(1.0f);
    c.levels = 4;
    c.error = {0.0f, 0.01f, 0.05f, 0.2f};
    const float k = 1000.0f; // pixels per mm at 1 mm
    // At 101 mm from the eye (100 from the nearest face), 0.5 px is 0.05 mm.
    EXPECT_EQ(lod::select_level(c, {0.0f, 0.0f, 101.0f}, k, 0.5f, 1.0f), 2u);
    EXPECT_EQ(lod::select_level(c, {0.0f, 0.0f, 11.0f}, k, 0.5f, 1.0f), 0u);  // 0.005 mm
    EXPECT_EQ(lod::select_level(c, {0.0f, 0.0f, 401.0f}, k, 0.5f, 1.0f), 3u); // 0.2 mm
    EXPECT_EQ(lod::select_level(c, {0.0f, 0.0f, 0.0f}, k, 0.5f, 1.0f), 0u);   // inside: the near plane's distance
}

TEST(ClusterLod, TinyAndEmptyMeshes) {
    EXPECT_TRUE(lod::build_cluster_lod(Mesh{}).clusters.empty());
    const Mesh box = test::box_mesh({0, 0, 0}, {1, 2, 3});
    const auto l = lod::build_cluster_lod(box);
    ASSERT_EQ(l.cells.size(), 1u);
    EXPECT_EQ(l.level0_indices, 36u);
    EXPECT_EQ(l.cells[0].levels, 1u); // too few triangles to simplify
}

namespace {

double signed_volume(const std::vector<std::array<std::uint32_t, 3>>& tris, const std::vector<glm::vec3>& p) {
    double v = 0;
    for (const auto& t : tris) v += double(glm::dot(p[t[0]], glm::cross(p[t[1]], p[t[2]]))) / 6.0;
    return v;
}

} // namespace

// Vertex clustering (the stand-ins' step): each vertex goes to the one of
// its grid cell nearest the cell's centre (checked against a brute-force
// search of every cell), nothing collapsed or repeated is left, the same
// input gives the same output, and the enclosed volume moves by less than
// the area times the cell's diagonal.
TEST(ClusterLod, VertexClusteringKeepsTheNearestVertexOfEachCell) {
    const Mesh& m = sphere();
    const glm::vec3 origin(-40.0f, -45.0f, -40.0f);
    const float cell = 2.0f;
    const auto out = lod::cluster_vertices(m.triangles, m.positions, origin, cell);
    ASSERT_GT(out.size(), 1000u);
    EXPECT_LT(out.size(), m.triangles.size() / 4);
    EXPECT_EQ(out, lod::cluster_vertices(m.triangles, m.positions, origin, cell));
    // The brute-force representative of every cell.
    std::map<std::array<int, 3>, std::pair<float, std::uint32_t>> best;
    for (std::uint32_t v = 0; v < m.positions.size(); ++v) {
        const glm::vec3 q = glm::floor((m.positions[v] - origin) / cell);
        const glm::vec3 d = m.positions[v] - (origin + (q + 0.5f) * cell);
        const std::pair<float, std::uint32_t> k{glm::dot(d, d), v};
        auto [it, fresh] = best.try_emplace({int(q.x), int(q.y), int(q.z)}, k);
        if (!fresh && k < it->second) it->second = k;
    }
    std::set<std::uint32_t> reps;
    for (const auto& [c, k] : best) reps.insert(k.second);
    std::set<std::array<std::uint32_t, 3>> seen;
    for (const auto& t : out) {
        for (const auto v : t) EXPECT_TRUE(reps.count(v)) << "vertex " << v << " is not its cell's nearest";
        EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
        EXPECT_TRUE(seen.insert(t).second) << "a triangle is repeated";
    }
    const double v0 = signed_volume(m.triangles, m.positions), v1 = signed_volume(out, m.positions);
    const double area = 4.0 * M_PI * 30.0 * 30.0;
    EXPECT_LT(std::abs(v1 - v0), area * std::sqrt(3.0) * cell);
    EXPECT_LT(std::abs(v1 - v0) / v0, 0.02) << v0 << " -> " << v1;
}

// The stand-ins: coarser step by step, after every level in the indices,
// and every vertex of the surface within a stand-in's error of one of its
// vertices; none for a surface under eight times a grid's triangles.
TEST(ClusterLod, StandInsAreCoarserStepByStepAndWithinTheirError) {
    const Mesh& m = sphere();
    auto o = small_cells();
    o.proxy_triangles = {8192, 2048, 512};
    const auto l = lod::build_cluster_lod(m, o);
    ASSERT_EQ(l.proxies.size(), 3u);
    std::size_t end_of_levels = 0;
    for (const auto& c : l.clusters)
        end_of_levels = std::max<std::size_t>(end_of_levels, c.first_index + c.index_count);
    std::size_t next = end_of_levels;
    for (std::size_t k = 0; k < l.proxies.size(); ++k) {
        const auto& p = l.proxies[k];
        EXPECT_EQ(p.first_index, next);
        next = p.first_index + p.index_count;
        ASSERT_LE(next, l.indices.size());
        EXPECT_GT(p.error, p.cell * std::sqrt(3.0f) - 1e-4f);
        if (k > 0) {
            EXPECT_LT(p.index_count, l.proxies[k - 1].index_count);
            EXPECT_GT(p.error, l.proxies[k - 1].error);
            EXPECT_FLOAT_EQ(p.cell, 2.0f * l.proxies[k - 1].cell);
        }
        // Every vertex of the sphere is within the error of the stand-in's surface.
        Mesh standin;
        standin.positions = m.positions;
        for (std::size_t i = p.first_index; i < next; i += 3)
            standin.triangles.push_back({l.indices[i], l.indices[i + 1], l.indices[i + 2]});
        const TriangleBvh bvh(standin);
        double worst = 0.0;
        for (std::size_t v = 0; v < m.positions.size(); v += 5)
            worst = std::max(worst, nearest_point(bvh, glm::dvec3(m.positions[v])).distance_mm);
        EXPECT_LE(worst, double(p.error)) << "stand-in " << k << ": " << p.index_count / 3 << " triangles";
        std::printf("stand-in %zu: %u triangles, error %.3f mm, farthest vertex of the sphere %.3f mm\n", k,
                    p.index_count / 3, double(p.error), worst);
    }
    EXPECT_EQ(next, l.indices.size());
    o.proxy_triangles = {m.triangles.size() / 8 + 1}; // more than an eighth of the sphere's triangles
    EXPECT_TRUE(lod::build_cluster_lod(m, o).proxies.empty());
}
