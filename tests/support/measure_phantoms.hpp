// Analytic phantoms for the measurement tests and benchmark (measure_test,
// measure_bench): balls and slabs sampled on an oblique, anisotropic grid, so
// that every measure goes through a rotated, non-cubic index -> LPS affine.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/volume.hpp"

namespace iso::test {

// The grid of the phantoms: spacing (0.7, 1.0, 1.3) x `scale` mm, direction
// cosines rotated by 25 degrees about the axis (1, 2, 3).
inline glm::dmat3 phantom_rotation() {
    return glm::dmat3(glm::rotate(glm::dmat4(1.0), glm::radians(25.0), glm::normalize(glm::dvec3(1, 2, 3))));
}
inline glm::dvec3 phantom_spacing(double scale) { return glm::dvec3(0.7, 1.0, 1.3) * scale; }

// An oblique grid of `dims` whose centre (continuous index (dims - 1) / 2) is at `centre` (LPS mm).
inline glm::dmat4 oblique_affine(std::array<std::int64_t, 3> dims, double scale, const glm::dvec3& centre) {
    const glm::dmat3 rot = phantom_rotation();
    const glm::dvec3 sp = phantom_spacing(scale);
    const glm::dvec3 half(0.5 * double(dims[0] - 1) * sp.x, 0.5 * double(dims[1] - 1) * sp.y,
                          0.5 * double(dims[2] - 1) * sp.z);
    return make_affine(sp, centre - rot * half, rot);
}

// The smallest such grid that holds a ball of radius `r` (+ margin mm) about `centre`.
inline std::array<std::int64_t, 3> dims_for(double r, double margin, double scale) {
    const glm::dvec3 sp = phantom_spacing(scale);
    std::array<std::int64_t, 3> d{};
    for (int a = 0; a < 3; ++a) d[a] = std::int64_t(std::ceil(2.0 * (r + margin) / sp[a])) + 1;
    return d;
}

// A float32 volume sampling f(LPS position of each voxel centre).
template <class F> Volume sample_field(std::array<std::int64_t, 3> dims, const glm::dmat4& affine, F f) {
    auto v = Volume::dense(dims, VoxelType::F32, affine);
    auto s = v.as<float>();
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i)
                s[v.linear_index(i, j, k)] = float(f(v.index_to_world({double(i), double(j), double(k)})));
    return v;
}

// A CT-like edge: 1000 HU inside, 0 outside, an erf profile of standard
// deviation `sigma` mm across the boundary (a Gaussian point-spread
// function); the 500 HU level set is exactly the boundary.
inline double ct_edge(double signed_distance_inside, double sigma) {
    return 500.0 * (1.0 + std::erf(signed_distance_inside / (std::sqrt(2.0) * sigma)));
}
inline constexpr double kBallIso = 500.0;

// A ball of radius r about c: value ct_edge(r - |p - c|).
inline Volume ct_ball(std::array<std::int64_t, 3> dims, const glm::dmat4& affine, const glm::dvec3& c, double r,
                      double sigma) {
    return sample_field(dims, affine, [&](const glm::dvec3& p) { return ct_edge(r - glm::length(p - c), sigma); });
}

// A plain loop over the triangles, independent of measure.cpp and of the extraction: area and
// signed volume (relative to the origin, in double).
struct Plain {
    double area = 0, volume_mm3 = 0;
};
inline Plain plain_sums(const Mesh& m) {
    Plain p;
    for (const auto& t : m.triangles) {
        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
        p.area += 0.5 * glm::length(glm::cross(b - a, c - a));
        p.volume_mm3 += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return p;
}

} // namespace iso::test
