// The union-find of surface measurement and the distributed summaries
// (renderer/surface/union_find.hpp): its sets against a breadth-first search of
// the same graph, and the rule its callers number components by: every
// set's root is its smallest member, whatever the order of the unions.
#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "renderer/surface/union_find.hpp"

using namespace iso;

namespace {

// Per vertex, the smallest vertex reachable from it (breadth-first over the edges).
std::vector<std::uint32_t> smallest_reachable(std::size_t n,
                                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) {
    std::vector<std::vector<std::uint32_t>> next(n);
    for (const auto& [a, b] : edges) {
        next[a].push_back(b);
        next[b].push_back(a);
    }
    std::vector<std::uint32_t> out(n, std::uint32_t(n));
    for (std::uint32_t s = 0; s < n; ++s) { // in index order: the first to reach a vertex is its smallest
        if (out[s] != n) continue;
        std::vector<std::uint32_t> queue{s};
        out[s] = s;
        for (std::size_t q = 0; q < queue.size(); ++q)
            for (const auto v : next[queue[q]])
                if (out[v] == n) {
                    out[v] = s;
                    queue.push_back(v);
                }
    }
    return out;
}

// density x n edges between vertices picked at random.
std::vector<std::pair<std::uint32_t, std::uint32_t>> random_edges(std::mt19937& rng, std::size_t n, double density) {
    std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(n - 1));
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges(std::size_t(density * double(n)));
    for (auto& e : edges) e = {pick(rng), pick(rng)};
    return edges;
}

} // namespace

TEST(UnionFind, SingletonsAreTheirOwnRoots) {
    UnionFind sets(5);
    EXPECT_EQ(sets.size(), 5u);
    for (std::uint32_t i = 0; i < 5; ++i) EXPECT_EQ(sets.find(i), i);
    sets.unite(3, 3);
    EXPECT_EQ(sets.find(3), 3u);
}

TEST(UnionFind, TheSmallestMemberIsTheRootWhateverTheOrderOfUnions) {
    // A chain joined from its far end towards its start, then a second set
    // joined onto it through its largest member.
    UnionFind sets(10);
    sets.unite(9, 7);
    sets.unite(7, 5);
    sets.unite(5, 3);
    sets.unite(8, 6);
    sets.unite(6, 9);
    for (std::uint32_t v : {3u, 5u, 6u, 7u, 8u, 9u}) EXPECT_EQ(sets.find(v), 3u) << v;
    sets.unite(9, 1);
    for (std::uint32_t v : {1u, 3u, 5u, 6u, 7u, 8u, 9u}) EXPECT_EQ(sets.find(v), 1u) << v;
    for (std::uint32_t v : {0u, 2u, 4u}) EXPECT_EQ(sets.find(v), v);
}

TEST(UnionFind, RandomGraphsMatchABreadthFirstSearch) {
    std::mt19937 rng(7);
    for (const std::size_t n : {1u, 2u, 50u, 2000u}) {
        for (const double density : {0.2, 0.5, 1.0, 3.0}) {
            SCOPED_TRACE(::testing::Message() << n << " vertices, " << density << " edges per vertex");
            const auto edges = random_edges(rng, n, density);
            UnionFind sets(n);
            for (const auto& [a, b] : edges) sets.unite(a, b);
            const auto expected = smallest_reachable(n, edges);
            for (std::uint32_t v = 0; v < n; ++v) ASSERT_EQ(sets.find(v), expected[v]) << "vertex " << v;
        }
    }
}

// The concurrent sets (ConcurrentUnionFind): the unions made by many threads
// at once in any order give UnionFind's roots exactly, on graphs large enough
// that the threads race on the same roots.
TEST(UnionFind, ConcurrentUnionsGiveTheSameRootsAsSerialOnes) {
    std::mt19937 rng(11);
    for (const std::size_t n : {1u, 1000u, 200000u}) {
        for (const double density : {0.3, 1.0, 4.0}) {
            SCOPED_TRACE(::testing::Message() << n << " vertices, " << density << " edges per vertex");
            const auto edges = random_edges(rng, n, density);
            UnionFind serial(n);
            for (const auto& [a, b] : edges) serial.unite(a, b);
            ConcurrentUnionFind sets(n);
            tbb::task_arena arena(4);
            arena.execute([&] {
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edges.size(), 64), [&](const auto& r) {
                    for (std::size_t i = r.begin(); i != r.end(); ++i) sets.unite(edges[i].first, edges[i].second);
                });
            });
            for (std::uint32_t v = 0; v < n; ++v) ASSERT_EQ(sets.find(v), serial.find(v)) << "vertex " << v;
        }
    }
}
