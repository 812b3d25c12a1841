#include "renderer/surface/grow.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "io/error.hpp"

namespace iso {

namespace {

std::string number(double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", x);
    return b;
}

// What a voxel is to the region: 1 it may be grown into (its value within
// [lo, hi] and its centre within the box), 2 its centre is outside the box,
// 0 its value is outside the range. Asked only of the voxels the growth
// reaches, not of the whole volume.
template <class T>
int classify(const Volume& v, std::span<const T> s, const GrowOptions& o, std::int64_t i, std::int64_t j,
             std::int64_t k) {
    if (o.within && !o.within->contains(v.index_to_world({double(i), double(j), double(k)}))) return 2;
    const double x = double(s[v.linear_index(i, j, k)]);
    return x >= o.lo && x <= o.hi ? 1 : 0;
}

// Breadth first through faces from r.seed into r.mask; the queue holds
// linear indices. Counts the voxels and the boundary ones.
template <class T> void flood(const Volume& v, const GrowOptions& o, GrownRegion& r) {
    const std::span<const T> s = v.as<T>();
    auto mask = r.mask.as<std::uint8_t>();
    const std::int64_t nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
    const std::int64_t step[3] = {1, nx, nx * ny};
    std::vector<std::size_t> queue{v.linear_index(r.seed[0], r.seed[1], r.seed[2])};
    mask[queue[0]] = 1;
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::size_t at = queue[head];
        const std::int64_t c[3] = {std::int64_t(at) % nx, (std::int64_t(at) / nx) % ny, std::int64_t(at) / (nx * ny)};
        bool boundary = false;
        for (int a = 0; a < 3; ++a)
            for (int d : {-1, 1}) {
                std::int64_t n[3] = {c[0], c[1], c[2]};
                n[a] += d;
                if (n[a] < 0 || n[a] >= (a == 0 ? nx : a == 1 ? ny : nz)) {
                    boundary = true;
                    r.reached_border = true;
                    continue;
                }
                const std::size_t q = std::size_t(std::int64_t(at) + d * step[a]);
                if (mask[q]) continue;
                const int kind = classify(v, s, o, n[0], n[1], n[2]);
                if (kind == 1) {
                    mask[q] = 1;
                    queue.push_back(q);
                    continue;
                }
                boundary = true;
                r.reached_box = r.reached_box || kind == 2;
            }
        r.boundary_voxels += boundary;
    }
    r.voxels = queue.size();
}

// The voxel nearest an LPS point (rounded index): kNearestOk, or why there
// is none, axis by axis (a coordinate not finite, or outside the volume).
enum { kNearestOk, kNearestNotFinite, kNearestOutside };
int nearest_voxel(const Volume& v, const glm::dvec3& lps, std::array<std::int64_t, 3>& s) {
    const glm::dvec3 ijk = glm::dvec3(glm::inverse(v.index_to_lps) * glm::dvec4(lps, 1.0));
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(ijk[a])) return kNearestNotFinite;
        s[std::size_t(a)] = std::int64_t(std::llround(ijk[a]));
        if (s[std::size_t(a)] < 0 || s[std::size_t(a)] >= v.dims[std::size_t(a)]) return kNearestOutside;
    }
    return kNearestOk;
}

} // namespace

std::optional<glm::dvec3> seed_within(const Volume& v, const glm::dvec3& at, const glm::dvec3& forward, double lo,
                                      double hi) {
    const glm::dmat3 m(v.index_to_lps);
    const double step = std::min({glm::length(m[0]), glm::length(m[1]), glm::length(m[2])}) * 0.5;
    for (int k = 0; k <= 6; ++k) {
        const glm::dvec3 p = at + forward * (step * k);
        std::array<std::int64_t, 3> i{};
        if (nearest_voxel(v, p, i) != kNearestOk) continue;
        const double value = v.value(i[0], i[1], i[2]);
        if (value >= lo && value <= hi) return p;
    }
    return std::nullopt;
}

GrownRegion grow_region(const Volume& v, const glm::dvec3& seed_lps, const GrowOptions& o, const ProgressFn& progress) {
    if (v.is_sparse()) throw Error("grow from a seed", "the volume is sparse (OpenVDB): not supported");
    if (!std::isfinite(o.lo) || !std::isfinite(o.hi) || o.lo > o.hi)
        throw Error("grow from a seed", "the range " + number(o.lo) + " to " + number(o.hi) + " is empty");
    std::array<std::int64_t, 3> s{};
    const int nearest = nearest_voxel(v, seed_lps, s);
    if (nearest == kNearestNotFinite) throw Error("grow from a seed", "the seed is not finite");
    if (nearest == kNearestOutside) throw Error("grow from a seed", "the seed lies outside the volume");
    const int seed_kind =
        dispatch_voxel_type(v.type, [&](auto tag) { return classify(v, v.as<decltype(tag)>(), o, s[0], s[1], s[2]); });
    if (seed_kind == 2) throw Error("grow from a seed", "the seed lies outside the box");
    if (seed_kind != 1)
        throw Error("grow from a seed", "the seed's value " + number(v.value(s[0], s[1], s[2])) +
                                            " is outside the range " + number(o.lo) + " to " + number(o.hi));
    GrownRegion r;
    r.seed = s;
    r.mask = Volume::dense(v.dims, VoxelType::U8, v.index_to_lps);
    r.mask.meta.source = v.meta.source;
    report(progress, 0.0, "growing", "grow");
    dispatch_voxel_type(v.type, [&](auto tag) { flood<decltype(tag)>(v, o, r); });
    const glm::dmat3 m(v.index_to_lps);
    r.voxel_mm3 = std::abs(glm::determinant(m));
    r.volume_ml = double(r.voxels) * r.voxel_mm3 / 1000.0;
    r.partial_volume_ml = 0.5 * double(r.boundary_voxels) * r.voxel_mm3 / 1000.0;
    report(progress, 1.0, "done", "grow");
    return r;
}

} // namespace iso
