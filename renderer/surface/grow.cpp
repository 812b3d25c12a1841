#include "renderer/surface/grow.hpp"

#include <cmath>
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

// 1 where a voxel may be grown into: its value within [lo, hi] and its
// centre within the box.
std::vector<std::uint8_t> candidates(const Volume& v, const GrowOptions& o) {
    std::vector<std::uint8_t> ok(std::size_t(v.voxel_count()), 0);
    dispatch_voxel_type(v.type, [&](auto tag) {
        using T = decltype(tag);
        const auto s = v.as<T>();
        for (std::size_t i = 0; i < ok.size(); ++i) {
            const double x = double(s[i]);
            ok[i] = x >= o.lo && x <= o.hi;
        }
    });
    if (!o.within) return ok;
    for (std::int64_t k = 0; k < v.dims[2]; ++k)
        for (std::int64_t j = 0; j < v.dims[1]; ++j)
            for (std::int64_t i = 0; i < v.dims[0]; ++i) {
                const glm::dvec3 p = v.index_to_world({double(i), double(j), double(k)});
                bool in = true;
                for (int a = 0; a < 3; ++a) in = in && p[a] >= o.within->lo[a] && p[a] <= o.within->hi[a];
                if (!in) ok[v.linear_index(i, j, k)] = 2; // outside the box: never grown into (2: the box stopped it)
            }
    return ok;
}

} // namespace

GrownRegion grow_region(const Volume& v, const glm::dvec3& seed_lps, const GrowOptions& o, const ProgressFn& progress) {
    if (v.is_sparse()) throw Error("grow from a seed", "the volume is sparse (OpenVDB): not supported");
    if (!std::isfinite(o.lo) || !std::isfinite(o.hi) || o.lo > o.hi)
        throw Error("grow from a seed", "the range " + number(o.lo) + " to " + number(o.hi) + " is empty");
    const glm::dvec3 ijk = glm::dvec3(glm::inverse(v.index_to_lps) * glm::dvec4(seed_lps, 1.0));
    std::array<std::int64_t, 3> s{};
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(ijk[a])) throw Error("grow from a seed", "the seed is not finite");
        s[std::size_t(a)] = std::int64_t(std::llround(ijk[a]));
        if (s[std::size_t(a)] < 0 || s[std::size_t(a)] >= v.dims[std::size_t(a)])
            throw Error("grow from a seed", "the seed lies outside the volume");
    }
    report(progress, 0.0, "values in range", "grow");
    std::vector<std::uint8_t> ok = candidates(v, o);
    const std::size_t seed = v.linear_index(s[0], s[1], s[2]);
    if (ok[seed] == 2) throw Error("grow from a seed", "the seed lies outside the box");
    if (ok[seed] != 1)
        throw Error("grow from a seed", "the seed's value " + number(v.value(s[0], s[1], s[2])) +
                                            " is outside the range " + number(o.lo) + " to " + number(o.hi));
    GrownRegion r;
    r.seed = s;
    r.mask = Volume::dense(v.dims, VoxelType::U8, v.index_to_lps);
    r.mask.meta.source = v.meta.source;
    auto mask = r.mask.as<std::uint8_t>();
    // Breadth first through faces; the queue holds linear indices.
    std::vector<std::size_t> queue{seed};
    mask[seed] = 1;
    const std::int64_t nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
    const std::int64_t step[3] = {1, nx, nx * ny};
    report(progress, 0.3, "growing", "grow");
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::size_t at = queue[head];
        const std::int64_t c[3] = {std::int64_t(at) % nx, (std::int64_t(at) / nx) % ny, std::int64_t(at) / (nx * ny)};
        bool boundary = false;
        for (int a = 0; a < 3; ++a)
            for (int d : {-1, 1}) {
                const std::int64_t n = c[a] + d;
                if (n < 0 || n >= (a == 0 ? nx : a == 1 ? ny : nz)) {
                    boundary = true;
                    r.reached_border = true;
                    continue;
                }
                const std::size_t q = std::size_t(std::int64_t(at) + d * step[a]);
                if (mask[q]) continue;
                if (ok[q] == 1) {
                    mask[q] = 1;
                    queue.push_back(q);
                    continue;
                }
                boundary = true;
                r.reached_box = r.reached_box || ok[q] == 2;
            }
        r.boundary_voxels += boundary;
    }
    const glm::dmat3 m(v.index_to_lps);
    r.voxels = queue.size();
    r.voxel_mm3 = std::abs(glm::determinant(m));
    r.volume_ml = double(r.voxels) * r.voxel_mm3 / 1000.0;
    r.partial_volume_ml = 0.5 * double(r.boundary_voxels) * r.voxel_mm3 / 1000.0;
    report(progress, 1.0, "done", "grow");
    return r;
}

} // namespace iso
