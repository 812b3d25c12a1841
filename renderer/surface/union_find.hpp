// Disjoint sets over the indices 0..n-1 (union-find), for the connected
// components of a measured surface (measure.cpp) and of the pieces of a
// distributed surface (components.cpp).
#pragma once

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

} // namespace iso
