// A thin-structure CT phantom: a CT-angiogram-like volume in
// Hounsfield units with a branching, contrast-filled vessel tree whose radii
// go from 3.5 mm down to ~0.45 mm (below the 0.7 x 0.7 x 1.0 mm voxel), two
// thin bone shells (1.2 and 2 mm) and a thin bone plate (1 mm) behind it, in
// a soft-tissue body with a fat layer, placed with a rotated, offset affine.
// Every edge is a partial-volume ramp one voxel wide, so marching cubes at
// iso 150 gives the thin, uneven tubes and plates a real angiogram gives.
//
// Deterministic: the same bytes for the same arguments with the same
// standard library (std::mt19937; the distributions are written out here, not
// std::uniform_real_distribution, whose output the standard leaves open).
//
// Used by ao_bench (scene `thin`, written once as NRRD because the reference
// goes through core::render_input(path)) and by tests/gl/ao_thin_test.cpp.
// Header-only and no TBB: GL tests and benchmarks include it as it is.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "io/volume.hpp"
#include "io/volume_io.hpp"

namespace iso::bench {

struct ThinPhantomOptions {
    std::array<std::int64_t, 3> dims{160, 160, 120};
    glm::dvec3 spacing{0.7, 0.7, 1.0};
    unsigned seed = 15;
    double root_radius = 3.5; // mm (an internal carotid / a large cerebral artery)
    double min_radius = 0.35; // mm: branches stop below this (sub-voxel: the iso-150 tube is ~0.9 mm wide)
    double ramp = 0.85;       // mm: partial-volume edge width (about one voxel)
    bool bone = true;         // the thin shells, plate and air cells behind and beside the tree
};

// One straight piece of a vessel: a capsule whose radius goes linearly from r0 to r1.
struct VesselSegment {
    glm::dvec3 a, b;
    double r0, r1, hu;
};

namespace thin_detail {

inline double uniform01(std::mt19937& g) { return double(g()) / 4294967296.0; }

// The tree in the volume's own frame (mm from voxel (0,0,0) along its axes).
// Murray's law splits a parent of radius r into children of r * 0.79 and
// r * 0.72 (r^3 ~ r1^3 + r2^3); each branch is a few bent pieces with length
// ~ 6-9 radii + 3 mm; the children turn 25-50 degrees away from the parent
// around a random azimuth, pulled back towards the body's centre plane when
// they would leave it.
inline void grow(std::vector<VesselSegment>& out, std::mt19937& g, glm::dvec3 p, glm::dvec3 dir, double r,
                 const ThinPhantomOptions& o, const glm::dvec3& ext, int depth) {
    if (r < o.min_radius || depth > 12) return;
    const double len = (6.0 + 3.0 * uniform01(g)) * r + 3.0;
    const int pieces = 3;
    const double r_end = std::max(r * 0.93, o.min_radius);
    const double hu = 300.0 + 100.0 * uniform01(g); // contrast varies from vessel to vessel
    for (int i = 0; i < pieces; ++i) {
        // bend a little, and stay inside the field of view (a soft pull towards the centre)
        glm::dvec3 bend(uniform01(g) - 0.5, uniform01(g) - 0.5, uniform01(g) - 0.5);
        const glm::dvec3 to_c = (ext * 0.5 - p) / ext;
        dir = glm::normalize(dir + 0.35 * bend +
                             0.8 * glm::dvec3(to_c.x, to_c.y * 2.0, 0.0) * std::max(0.0, glm::length(to_c) - 0.25));
        const glm::dvec3 q = p + dir * (len / pieces);
        const double ra = r + (r_end - r) * i / pieces, rb = r + (r_end - r) * (i + 1) / pieces;
        out.push_back({p, q, ra, rb, hu});
        p = q;
    }
    // two children: a random azimuth around the parent's direction
    const glm::dvec3 any = std::abs(dir.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::dvec3 u = glm::normalize(glm::cross(dir, any)), v = glm::cross(dir, u);
    const double phi = 6.283185307179586 * uniform01(g);
    for (int c = 0; c < 2; ++c) {
        const double ang = (25.0 + 25.0 * uniform01(g)) * 3.141592653589793 / 180.0;
        const double az = phi + c * 3.141592653589793;
        const glm::dvec3 side = std::cos(az) * u + std::sin(az) * v;
        glm::dvec3 d = std::cos(ang) * dir + std::sin(ang) * side;
        d.y *= 0.6; // spread mostly across the anterior view (x-z), less in depth
        d = glm::normalize(d);
        grow(out, g, p, d, r_end * (c == 0 ? 0.79 : 0.72), o, ext, depth + 1);
    }
}

// Distance from x to segment ab, and the parameter t of the nearest point.
inline double segment_distance(const glm::dvec3& x, const glm::dvec3& a, const glm::dvec3& b, double& t) {
    const glm::dvec3 ab = b - a;
    const double l2 = glm::dot(ab, ab);
    t = l2 > 0 ? std::clamp(glm::dot(x - a, ab) / l2, 0.0, 1.0) : 0.0;
    return glm::length(x - (a + t * ab));
}

} // namespace thin_detail

// The vessel tree (volume frame, mm), exposed so tests can place probes on it.
inline std::vector<VesselSegment> thin_phantom_vessels(const ThinPhantomOptions& o = {}) {
    const glm::dvec3 ext = glm::dvec3(o.dims[0], o.dims[1], o.dims[2]) * o.spacing;
    std::mt19937 g(o.seed);
    std::vector<VesselSegment> v;
    // The root enters near the top (high k: superior in LPS) and runs down
    // (towards low k) close in front of the bone shells, plus two trunks from
    // the sides.
    thin_detail::grow(v, g, {ext.x * 0.45, ext.y * 0.55, ext.z * 0.95}, glm::normalize(glm::dvec3(0.1, 0.05, -1.0)),
                      o.root_radius, o, ext, 0);
    thin_detail::grow(v, g, {ext.x * 0.8, ext.y * 0.6, ext.z * 0.7}, glm::normalize(glm::dvec3(-1.0, 0.1, -0.3)),
                      o.root_radius * 0.7, o, ext, 1);
    thin_detail::grow(v, g, {ext.x * 0.15, ext.y * 0.6, ext.z * 0.55}, glm::normalize(glm::dvec3(1.0, 0.2, 0.2)),
                      o.root_radius * 0.6, o, ext, 1);
    return v;
}

// The index -> LPS affine: rotated 12 degrees about z and 7 about x (not
// identity, like a tilted acquisition), origin offset.
inline glm::dmat4 thin_phantom_affine(const ThinPhantomOptions& o = {}) {
    glm::dmat4 rot = glm::rotate(glm::dmat4(1.0), glm::radians(12.0), glm::dvec3(0, 0, 1));
    rot = glm::rotate(rot, glm::radians(7.0), glm::dvec3(1, 0, 0));
    return make_affine(o.spacing, {-61.0, -48.5, 20.25}, glm::dmat3(rot));
}

inline Volume thin_phantom(const ThinPhantomOptions& o = {}) {
    auto v = Volume::dense(o.dims, VoxelType::I16, thin_phantom_affine(o));
    v.meta.modality = "CT";
    v.meta.source = "synthetic thin-structure CT phantom (issue 15)";
    const glm::dvec3 sp = o.spacing;
    const glm::dvec3 ext = glm::dvec3(o.dims[0], o.dims[1], o.dims[2]) * sp;
    const glm::dvec3 c = ext * 0.5;
    const double w = o.ramp;
    // partial-volume fraction of a solid whose signed distance (outside > 0) is d
    auto pv = [w](double d) { return std::clamp(0.5 - d / w, 0.0, 1.0); };
    std::vector<double> hu(std::size_t(o.dims[0] * o.dims[1] * o.dims[2]));
    // Background: air, a body (ellipse in x-y, the whole z extent) of soft
    // tissue (40 HU) under a 4 mm fat layer (-90 HU), mild noise.
    std::mt19937 g(o.seed * 7919u);
    const glm::dvec2 semi(ext.x * 0.47, ext.y * 0.47);
    for (std::int64_t k = 0; k < o.dims[2]; ++k)
        for (std::int64_t j = 0; j < o.dims[1]; ++j)
            for (std::int64_t i = 0; i < o.dims[0]; ++i) {
                const glm::dvec3 p = glm::dvec3(i, j, k) * sp;
                const glm::dvec2 q = (glm::dvec2(p.x, p.y) - glm::dvec2(c.x, c.y)) / semi;
                const double rho = glm::length(q);
                const double edge = (rho - 1.0) * std::min(semi.x, semi.y); // ~mm outside the body
                const double body = pv(edge), tissue = pv(edge + 4.0);
                const double noise =
                    (thin_detail::uniform01(g) + thin_detail::uniform01(g) + thin_detail::uniform01(g) - 1.5) * 10.0;
                hu[std::size_t(i + o.dims[0] * (j + o.dims[1] * k))] =
                    -1000.0 + body * 910.0 + tissue * 130.0 + body * noise;
            }
    // Solids: max over the background of (its HU blended by partial volume).
    auto stamp = [&](const glm::dvec3& lo, const glm::dvec3& hi, auto&& f) { // f(p) -> (HU, fraction)
        const glm::ivec3 a = glm::max(glm::ivec3(glm::floor(lo / sp)), glm::ivec3(0));
        const glm::ivec3 b =
            glm::min(glm::ivec3(glm::ceil(hi / sp)), glm::ivec3(o.dims[0] - 1, o.dims[1] - 1, o.dims[2] - 1));
        for (int k = a.z; k <= b.z; ++k)
            for (int j = a.y; j <= b.y; ++j)
                for (int i = a.x; i <= b.x; ++i) {
                    const auto [value, f01] = f(glm::dvec3(i, j, k) * sp);
                    if (f01 <= 0) continue;
                    double& h = hu[std::size_t(i + o.dims[0] * (j + o.dims[1] * std::int64_t(k)))];
                    h = std::max(h, h + (value - h) * f01);
                }
    };
    if (o.bone) {
        // Two thin shells (skull-base-like caps of spheres) behind the tree
        // (posterior: high j) and a 1 mm plate across the bottom, tilted.
        struct Shell {
            glm::dvec3 centre;
            double radius, thickness, hu;
        };
        const Shell shells[] = {{{c.x, c.y - 40.0, c.z}, 90.0, 1.2, 900.0},
                                {{c.x + 10.0, c.y - 20.0, c.z - 10.0}, 50.0, 2.0, 1100.0}};
        for (const auto& s : shells) {
            stamp(glm::dvec3(0), ext, [&](const glm::dvec3& p) {
                const double d = std::abs(glm::length(p - s.centre) - s.radius) - 0.5 * s.thickness;
                // only the posterior part of the sphere, within the body
                const bool keep =
                    p.y > c.y + 8.0 && glm::length((glm::dvec2(p.x, p.y) - glm::dvec2(c.x, c.y)) / semi) < 0.92;
                return std::pair<double, double>{s.hu, keep ? pv(d) : 0.0};
            });
        }
        const glm::dvec3 n = glm::normalize(glm::dvec3(0.15, -0.35, 1.0));
        const glm::dvec3 p0(c.x, c.y, ext.z * 0.12);
        stamp(glm::dvec3(0), glm::dvec3(ext.x, ext.y, ext.z * 0.3), [&](const glm::dvec3& p) {
            const double d = std::abs(glm::dot(p - p0, n)) - 0.5;
            const glm::dvec2 q = (glm::dvec2(p.x, p.y) - glm::dvec2(c.x, c.y)) / semi;
            return std::pair<double, double>{800.0, glm::length(q) < 0.8 ? pv(d) : 0.0};
        });
        // Air cells (ethmoid-like): a block of 5 mm cells with 0.8 mm walls,
        // open to the front (no wall at the anterior face), 14 mm deep: narrow
        // cavities with sub-voxel walls.
        const glm::dvec3 lo(c.x - 32.0, c.y - 2.0, ext.z * 0.3), hi(c.x - 7.0, c.y + 12.0, ext.z * 0.3 + 20.0);
        stamp(lo - 1.0, hi + 1.0, [&](const glm::dvec3& p) {
            const glm::dvec3 q = p - lo;
            auto wall = [](double x) {
                return std::abs(x - 5.0 * std::round(x / 5.0));
            };                                                             // distance to the nearest cell wall plane
            double d = std::min({wall(q.x), wall(q.z), hi.y - p.y}) - 0.4; // walls along x and z, and the back wall
            const double outside = std::max({lo.x - p.x, p.x - hi.x, lo.y - p.y, p.y - hi.y, lo.z - p.z, p.z - hi.z});
            d = std::max(d, outside);
            return std::pair<double, double>{750.0, pv(d)};
        });
    }
    for (const auto& s : thin_phantom_vessels(o)) {
        const double rmax = std::max(s.r0, s.r1) + w;
        stamp(glm::min(s.a, s.b) - rmax, glm::max(s.a, s.b) + rmax, [&](const glm::dvec3& p) {
            double t = 0;
            const double d = thin_detail::segment_distance(p, s.a, s.b, t) - (s.r0 + (s.r1 - s.r0) * t);
            return std::pair<double, double>{s.hu, pv(d)};
        });
    }
    auto out = v.as<std::int16_t>();
    for (std::size_t n = 0; n < hu.size(); ++n) out[n] = std::int16_t(std::lround(std::clamp(hu[n], -1024.0, 3071.0)));
    return v;
}

// thin_phantom() written as uncompressed NRRD at `path` unless a file is
// already there (the same bytes every time, so the Embree reference cache,
// keyed by the file's SHA-256, stays valid). Returns the path.
inline std::string write_thin_phantom(const std::string& path, const ThinPhantomOptions& o = {}) {
    namespace fs = std::filesystem;
    if (fs::exists(path)) return path;
    if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
    save_volume(thin_phantom(o), path, /*compress=*/false); // save_volume writes a temporary and renames it
    return path;
}

} // namespace iso::bench
