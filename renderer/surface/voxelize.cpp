#include "renderer/surface/voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

namespace iso {

namespace {

// The top-left rule for an edge a -> b of a counter-clockwise triangle in
// the (j, k) plane: a point exactly on it belongs to the triangle when the
// edge is a "top" edge (horizontal, going left) or a "left" edge (going down).
bool top_left(const glm::dvec2& a, const glm::dvec2& b) {
    const glm::dvec2 e = b - a;
    return (e.y == 0.0 && e.x < 0.0) || e.y < 0.0;
}

// Inside the counter-clockwise triangle (a, b, c), edges by the top-left rule.
bool inside(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    const auto edge = [&](const glm::dvec2& u, const glm::dvec2& v) {
        const double e = (v.x - u.x) * (p.y - u.y) - (v.y - u.y) * (p.x - u.x);
        return e > 0.0 || (e == 0.0 && top_left(u, v));
    };
    return edge(a, b) && edge(b, c) && edge(c, a);
}

} // namespace

std::size_t voxelize(const Mesh& m, const glm::dmat4& index_to_lps, std::array<std::int64_t, 3> dims,
                     std::span<std::uint16_t> out, std::uint16_t value) {
    const std::int64_t nx = dims[0], ny = dims[1], nz = dims[2];
    if (m.empty() || nx <= 0 || ny <= 0 || nz <= 0) return 0;
    const glm::dmat4 to_index = glm::inverse(index_to_lps);
    std::vector<glm::dvec3> q(m.positions.size());
    for (std::size_t i = 0; i < q.size(); ++i)
        q[i] = glm::dvec3(to_index * glm::dvec4(glm::dvec3(m.positions[i]), 1.0));
    // The crossings of each row (j, k) of voxel centres, as i positions.
    std::vector<std::vector<double>> rows(std::size_t(ny * nz));
    for (const auto& t : m.triangles) {
        const glm::dvec3 p0 = q[t[0]];
        glm::dvec3 p1 = q[t[1]], p2 = q[t[2]];
        glm::dvec2 a(p0.y, p0.z), b(p1.y, p1.z), c(p2.y, p2.z);
        const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if (area == 0.0) continue; // edge-on: crosses no row
        if (area < 0.0) {
            std::swap(b, c);
            std::swap(p1, p2);
        }
        const double det = std::abs(area);
        const std::int64_t j0 = std::max<std::int64_t>(0, std::int64_t(std::ceil(std::min({a.x, b.x, c.x})))),
                           j1 = std::min<std::int64_t>(ny - 1, std::int64_t(std::floor(std::max({a.x, b.x, c.x})))),
                           k0 = std::max<std::int64_t>(0, std::int64_t(std::ceil(std::min({a.y, b.y, c.y})))),
                           k1 = std::min<std::int64_t>(nz - 1, std::int64_t(std::floor(std::max({a.y, b.y, c.y}))));
        for (std::int64_t k = k0; k <= k1; ++k)
            for (std::int64_t j = j0; j <= j1; ++j) {
                const glm::dvec2 p{double(j), double(k)};
                if (!inside(p, a, b, c)) continue;
                // Barycentric weights in the projection give i on the triangle.
                const double wb = ((p.x - a.x) * (c.y - a.y) - (p.y - a.y) * (c.x - a.x)) / det;
                const double wc = ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / det;
                rows[std::size_t(j + ny * k)].push_back(p0.x + wb * (p1.x - p0.x) + wc * (p2.x - p0.x));
            }
    }
    std::size_t set = 0;
    for (std::int64_t k = 0; k < nz; ++k)
        for (std::int64_t j = 0; j < ny; ++j) {
            auto& r = rows[std::size_t(j + ny * k)];
            std::sort(r.begin(), r.end());
            for (std::size_t c = 0; c + 1 < r.size(); c += 2) {
                const std::int64_t i0 = std::max<std::int64_t>(0, std::int64_t(std::ceil(r[c]))),
                                   i1 = std::min<std::int64_t>(nx - 1, std::int64_t(std::floor(r[c + 1])));
                for (std::int64_t i = i0; i <= i1; ++i) {
                    out[std::size_t(i + nx * (j + ny * k))] = value;
                    ++set;
                }
            }
        }
    return set;
}

} // namespace iso
