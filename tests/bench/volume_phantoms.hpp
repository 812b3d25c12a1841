// The volumes of the volume-rendering benchmark (volume_bench.cpp) that are
// generated: a CT-angiogram-like phantom (branching contrast-filled vessels
// in soft tissue, a spine and ribs, air around an elliptic body), and the
// scaling benchmark's CT-like volume (scale_volume.hpp) made in memory at a
// clinical spacing. int16 Hounsfield units, deterministic for a seed.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <glm/glm.hpp>
#include <tbb/parallel_for.h>

#include "io/volume.hpp"
#include "scale_volume.hpp"

namespace iso::bench {

namespace cta_detail {

struct Segment {
    glm::dvec3 a, b; // mm
    double r;        // mm
    double hu;
};

// A vessel tree: a trunk down the body, branches splitting off with 0.75 of
// their parent's radius, down to about 0.5 mm (1 mm tubes).
inline void branch(std::vector<Segment>& out, std::mt19937& rng, glm::dvec3 p, glm::dvec3 dir, double r, int depth) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double length = 12.0 + 20.0 * u(rng);
    const glm::dvec3 q = p + length * dir;
    out.push_back({p, q, r, 320.0 + 80.0 * u(rng)});
    if (depth == 0 || r < 0.6) return;
    for (int c = 0; c < 2; ++c) {
        glm::dvec3 d = dir + glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 1.4;
        d = glm::normalize(d);
        branch(out, rng, q, d, r * (c == 0 ? 0.85 : 0.7), depth - 1);
    }
}

inline double segment_distance(const glm::dvec3& p, const Segment& s) {
    const glm::dvec3 ab = s.b - s.a;
    const double t = std::clamp(glm::dot(p - s.a, ab) / glm::dot(ab, ab), 0.0, 1.0);
    return glm::length(p - (s.a + t * ab));
}

} // namespace cta_detail

// A CT angiogram: `dims` voxels of `spacing` mm (LPS, index axes along
// L, P, S; origin at the first voxel). Air (-1000) outside an elliptic body
// of soft tissue (40 HU, noise sigma 12); vessels of 300-400 HU, 1-6 mm
// across, as a branching tree from a 6 mm trunk, their walls partial-volumed
// over one voxel; a spine of cancellous bone (700) inside a cortical rim
// (1400) behind the vessels, and a few ribs (1100-1500).
inline Volume cta_phantom(std::array<std::int64_t, 3> dims, double spacing, unsigned seed = 7) {
    using cta_detail::Segment;
    auto v = Volume::dense(dims, VoxelType::I16, make_affine(glm::dvec3(spacing), {0, 0, 0}));
    v.meta.modality = "CT";
    v.meta.source = "synthetic CT angiogram phantom";
    const glm::dvec3 ext = glm::dvec3(double(dims[0]), double(dims[1]), double(dims[2])) * spacing;
    const glm::dvec3 c = 0.5 * ext;
    const double bx = 0.45 * ext.x, by = 0.36 * ext.y; // body semi-axes (elliptic cylinder along z)
    std::mt19937 rng(seed);
    std::vector<Segment> vessels;
    for (int t = 0; t < 3; ++t) // trunks entering from the top, heading down
        cta_detail::branch(vessels, rng, glm::dvec3(c.x + (t - 1) * 0.2 * bx, c.y - 0.1 * by, ext.z * 0.95),
                           glm::normalize(glm::dvec3((t - 1) * 0.3, 0.1, -1.0)), 3.0 - 0.5 * t, 6);
    std::vector<Segment> ribs;
    for (int k = 0; k < 6; ++k) { // arcs along the body's back half, as short chords
        const double z = ext.z * (0.15 + 0.14 * k), hu = 1100.0 + 80.0 * k;
        for (int s = 0; s < 12; ++s) {
            const double a0 = 0.15 * 3.14159 + s * 0.06 * 3.14159, a1 = a0 + 0.06 * 3.14159;
            auto at = [&](double a) {
                return glm::dvec3(c.x + 0.88 * bx * std::cos(a), c.y + 0.88 * by * std::sin(a), z);
            };
            ribs.push_back({at(a0), at(a1), 3.0, hu});
        }
    }
    const glm::dvec2 spine(c.x, c.y + 0.55 * by);
    const double spine_r = 0.16 * by;
    auto s = v.as<std::int16_t>();
    tbb::parallel_for(std::int64_t(0), dims[2], [&](std::int64_t k) {
        std::mt19937 r(seed * 7919u + unsigned(k));
        std::normal_distribution<double> noise(0.0, 1.0);
        const double z = double(k) * spacing;
        // Only the segments near this slice.
        std::vector<const Segment*> near;
        for (const auto* list : {&vessels, &ribs})
            for (const auto& g : *list)
                if (std::min(g.a.z, g.b.z) - g.r - 1.0 <= z && std::max(g.a.z, g.b.z) + g.r + 1.0 >= z)
                    near.push_back(&g);
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const glm::dvec3 p(double(i) * spacing, double(j) * spacing, z);
                const double qx = (p.x - c.x) / bx, qy = (p.y - c.y) / by;
                double hu = -1000.0 + 3.0 * noise(r);
                if (qx * qx + qy * qy < 1.0) {
                    hu = 40.0 + 12.0 * noise(r);
                    const double ds = glm::length(glm::dvec2(p.x, p.y) - spine);
                    const double disc = 0.5 + 0.5 * std::cos(z / 25.0 * 6.2832); // vertebrae and discs along z
                    if (ds < spine_r) hu = disc > 0.15 ? (ds > spine_r - 2.5 ? 1400.0 : 700.0) + 30.0 * noise(r) : 90.0;
                    for (const Segment* g : near) {
                        const double w = std::clamp(g->r - cta_detail::segment_distance(p, *g) + 0.5 * spacing, 0.0,
                                                    spacing) /
                                         spacing; // partial volume over one voxel
                        if (w > 0.0) hu = std::max(hu, 40.0 + w * (g->hu - 40.0) + 12.0 * noise(r));
                    }
                }
                s[v.linear_index(i, j, k)] = std::int16_t(std::lround(std::clamp(hu, -1024.0, 3071.0)));
            }
    });
    return v;
}

// scale_volume.hpp's CT-like content (body, cortical shell, trabecular
// lattice, vessels 450, small 2500 objects) as an in-memory volume of
// `dims` at `spacing` mm, centred on the origin.
inline Volume scale_ct(std::array<std::int64_t, 3> dims, double spacing) {
    ScaleVolumeParams p;
    p.dims = dims;
    p.spacing_mm = spacing;
    auto v = Volume::dense(dims, VoxelType::I16, scale_volume_affine(p));
    v.meta.modality = "CT";
    v.meta.source = "synthetic CT (scale_volume.hpp)";
    const detail::Anatomy anatomy(p.seed);
    const double two_pi = 6.283185307179586;
    const auto nx = static_cast<std::size_t>(dims[0]), ny = static_cast<std::size_t>(dims[1]);
    std::vector<double> sx(nx), cx(nx), sy(ny), cy(ny);
    for (std::int64_t i = 0; i < dims[0]; ++i) {
        sx[std::size_t(i)] = std::sin(two_pi * double(i) / p.trabecular_period);
        cx[std::size_t(i)] = std::cos(two_pi * double(i) / p.trabecular_period);
    }
    for (std::int64_t j = 0; j < dims[1]; ++j) {
        sy[std::size_t(j)] = std::sin(two_pi * double(j) / p.trabecular_period);
        cy[std::size_t(j)] = std::cos(two_pi * double(j) / p.trabecular_period);
    }
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 0; k < dims[2]; ++k)
        detail::fill_slice(p, anatomy, k, s.data() + k * dims[0] * dims[1], sx, cx, sy, cy);
    return v;
}

} // namespace iso::bench
