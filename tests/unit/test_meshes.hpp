// Small analytic meshes shared by the CPU and GL tests.
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"

namespace iso::test {

// The faces of an axis-aligned box as quads, outward by the right-hand rule,
// over corner indices (bit 0: x, bit 1: y, bit 2: z at hi).
inline constexpr int kBoxQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

// A closed axis-aligned box: 8 shared corners, 12 outward triangles, no normals.
inline Mesh box_mesh(glm::dvec3 lo, glm::dvec3 hi) {
    Mesh m;
    for (int k = 0; k < 8; ++k) m.positions.emplace_back(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
    for (const auto& q : kBoxQuads) {
        m.triangles.push_back({std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2])});
        m.triangles.push_back({std::uint32_t(q[0]), std::uint32_t(q[2]), std::uint32_t(q[3])});
    }
    return m;
}

// The same box with flat normals: each face has its own four vertices
// (shared corners would get averaged, tilted normals).
inline Mesh flat_box_mesh(glm::vec3 lo, glm::vec3 hi) {
    Mesh m;
    auto corner = [&](int i) { return glm::vec3((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z); };
    const glm::vec3 normals[6] = {{0, 0, -1}, {0, 0, 1}, {0, -1, 0}, {0, 1, 0}, {-1, 0, 0}, {1, 0, 0}};
    for (int f = 0; f < 6; ++f) {
        const auto b = std::uint32_t(m.positions.size());
        for (int k = 0; k < 4; ++k) {
            m.positions.push_back(corner(kBoxQuads[f][k]));
            m.normals.push_back(normals[f]);
        }
        m.triangles.push_back({b, b + 1, b + 2});
        m.triangles.push_back({b, b + 2, b + 3});
    }
    return m;
}

} // namespace iso::test
