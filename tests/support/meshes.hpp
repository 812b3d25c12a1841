// Small analytic meshes shared by the tests and benchmarks: boxes, a sphere
// extracted from a distance field, a UV sphere with an exact equator; and a
// canonical form of a mesh's triangles for comparing meshes exactly.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "renderer/surface/extract.hpp"

namespace iso::test {

// The faces of an axis-aligned box as quads, outward by the right-hand rule,
// over corner indices (bit 0: x, bit 1: y, bit 2: z at hi).
inline constexpr int kBoxQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                        {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

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

// Appends box_mesh(lo, hi) to m (scenes of several boxes).
inline void append_box(Mesh& m, glm::dvec3 lo, glm::dvec3 hi) {
    const Mesh b = box_mesh(lo, hi);
    const auto base = std::uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    for (const auto& t : b.triangles) m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
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

// A fine mesh of a ball of radius r about c: the zero isosurface of a
// distance field sampled every `voxel` mm.
inline Mesh sphere_mesh(glm::dvec3 c, double r, double voxel = 1.0) {
    const int n = int(std::ceil(2.4 * r / voxel)) + 1;
    const glm::dvec3 origin = c - glm::dvec3(1.2 * r);
    auto v = Volume::dense({n, n, n}, VoxelType::F32, make_affine(glm::dvec3(voxel), origin));
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                v.as<float>()[v.linear_index(i, j, k)] =
                    float(r - glm::length(origin + voxel * glm::dvec3(i, j, k) - c));
    return extract_isosurface(v, 0.0, {});
}

// A UV sphere of radius r about c: `stacks` rings (even: one ring on the
// equator), `slices` segments, outward-facing, closed and indexed.
inline Mesh uv_sphere(const glm::dvec3& c, double r, int stacks, int slices) {
    constexpr double kPi = 3.14159265358979323846;
    Mesh m;
    m.positions.emplace_back(glm::vec3(c + glm::dvec3(0, 0, r))); // north pole, 0
    for (int i = 1; i < stacks; ++i) {
        const double th = kPi * double(i) / double(stacks);
        // Exactly 0 on the equator, so its vertices lie exactly on the plane z = c.z.
        const double z = 2 * i == stacks ? 0.0 : std::cos(th);
        for (int j = 0; j < slices; ++j) {
            const double ph = 2 * kPi * double(j) / double(slices);
            m.positions.emplace_back(
                glm::vec3(c + r * glm::dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), z)));
        }
    }
    m.positions.emplace_back(glm::vec3(c - glm::dvec3(0, 0, r))); // south pole
    const auto south = std::uint32_t(m.positions.size() - 1);
    auto ring = [&](int i, int j) { return std::uint32_t(1 + (i - 1) * slices + (j % slices)); };
    for (int j = 0; j < slices; ++j) m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i + 1 < stacks; ++i)
        for (int j = 0; j < slices; ++j) {
            m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
    for (int j = 0; j < slices; ++j) m.triangles.push_back({south, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
    return m;
}

// Triangles as position triples, rotated to start at the smallest vertex
// (orientation kept) and sorted: equal lists mean equal meshes. Compiled in
// tests/support/meshes.cpp with the libraries' flags (library
// isoscope_test_meshes), not inline at the tests' -O0: sorting the bundled
// CT's triangles through std::array's operators, one call each, was most of
// Ties.BundledCtAt500And1150's 25 s under the sanitizers.
using Tri = std::array<std::array<float, 3>, 3>;
std::vector<Tri> canonical(const Mesh& m);

} // namespace iso::test
