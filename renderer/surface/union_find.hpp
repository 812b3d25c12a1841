// Disjoint sets over the indices 0..n-1 (union-find), for the connected
// components of a measured surface (analysis.cpp) and of the pieces of a
// distributed surface (components.cpp); ConcurrentUnionFind for unions made
// in parallel.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace iso {

// Path halving, and a union keeps the smaller of the two roots: every set's
// root is its smallest member, whatever the order of the unions. Callers
// rely on it: numbering the roots in index order numbers the sets in the
// order of their first member, and a member's root is never after it.
class UnionFind {
public:
    explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), std::uint32_t(0)); }

    std::size_t size() const { return parent_.size(); }

    // The root (smallest member) of x's set; shortens the path on the way.
    std::uint32_t find(std::uint32_t x) {
        while (parent_[x] != x) {
            parent_[x] = parent_[parent_[x]];
            x = parent_[x];
        }
        return x;
    }

    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a < b)
            parent_[b] = a;
        else if (b < a)
            parent_[a] = b;
    }

private:
    std::vector<std::uint32_t> parent_;
};

// The same sets, united by many threads at once (lock-free). A root is
// linked only under a smaller root, by compare-and-swap (retried when another
// thread linked it first), and path halving only ever points a member at one
// of its ancestors, so a member's parent is never after it and no cycle can
// form. The sets are those of the pairs united, whatever the order: every
// root is its set's smallest member, as UnionFind's, and find() after the
// parallel phase gives UnionFind's roots exactly.
class ConcurrentUnionFind {
public:
    explicit ConcurrentUnionFind(std::size_t n) : parent_(n) {
        std::iota(parent_.begin(), parent_.end(), std::uint32_t(0));
    }

    std::uint32_t find(std::uint32_t x) {
        for (;;) {
            const std::uint32_t p = at(x).load(std::memory_order_relaxed);
            if (p == x) return x;
            const std::uint32_t g = at(p).load(std::memory_order_relaxed);
            if (g != p) at(x).store(g, std::memory_order_relaxed); // halving: g is an ancestor of x
            x = g;
        }
    }

    void unite(std::uint32_t a, std::uint32_t b) {
        for (;;) {
            a = find(a);
            b = find(b);
            if (a == b) return;
            if (b < a) std::swap(a, b);
            std::uint32_t expected = b; // b, still a root, goes under the smaller root a
            if (at(b).compare_exchange_weak(expected, a, std::memory_order_relaxed)) return;
        }
    }

private:
    std::atomic_ref<std::uint32_t> at(std::uint32_t x) { return std::atomic_ref<std::uint32_t>(parent_[x]); }
    std::vector<std::uint32_t> parent_;
};

} // namespace iso
