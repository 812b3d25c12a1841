// Small scenes for the GL tests: analytic meshes and cameras.
#pragma once

#include <cmath>

#include <glm/glm.hpp>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/frame/camera.hpp"
#include "test_util.hpp"

namespace iso::test {

// A ball of radius r about the origin: the isosurface of a distance field.
inline Mesh sphere(double r, double voxel = 1.0) {
    const int n = int(std::ceil(2.4 * r / voxel)) + 1;
    const glm::dvec3 origin(-1.2 * r);
    auto v = Volume::dense({n, n, n}, VoxelType::F32, make_affine(glm::dvec3(voxel), origin));
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) v.as<float>()[v.linear_index(i, j, k)] = float(r - glm::length(origin + voxel * glm::dvec3(i, j, k)));
    return extract_isosurface(v, 0.0, {});
}

// A square in the x-z plane at y (facing the anterior camera), half size h.
inline Mesh plate(double y, double h, double z = 0) {
    Mesh m;
    m.positions = {{-h, y, z - h}, {h, y, z - h}, {h, y, z + h}, {-h, y, z + h}};
    m.normals.assign(4, {0, -1, 0});
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// A closed box [lo, hi]: four vertices per face, so each face is flat-shaded.
inline Mesh cuboid(glm::dvec3 lo, glm::dvec3 hi) {
    Mesh m;
    auto corner = [&](int c) { return glm::vec3((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z); };
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        const auto base = std::uint32_t(m.positions.size());
        for (int c : q) m.positions.push_back(corner(c));
        const glm::vec3 n = glm::normalize(glm::cross(corner(q[1]) - corner(q[0]), corner(q[2]) - corner(q[0])));
        m.normals.insert(m.normals.end(), 4, n);
        m.triangles.push_back({base, base + 1, base + 2});
        m.triangles.push_back({base, base + 2, base + 3});
    }
    return m;
}

// Looks at b from the front (anterior), fitted.
inline Camera anterior(const Bounds& b) {
    Camera c;
    c.set_view(PatientView::Anterior, b);
    c.fit(b, 1.0);
    return c;
}

inline double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

inline Bounds box(double h) {
    Bounds b;
    b.add(glm::dvec3(-h));
    b.add(glm::dvec3(h));
    return b;
}

} // namespace iso::test
