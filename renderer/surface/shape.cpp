#include "renderer/surface/shape.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include <glm/glm.hpp>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "io/error.hpp"

namespace iso {

namespace {

// The indices of the convex hull's vertices of `pts` (x, y, z each), by
// qhull (Debian's libqhull-dev: the hull code VTK, SciPy and CGAL's users
// rely on, rather than one of ours); a flat or degenerate set is joggled
// (QJ), which changes which vertices qhull reports only among points that
// are nearly coplanar, never the extreme ones.
std::vector<std::size_t> hull_vertices(std::vector<double>& pts) {
    const int n = int(pts.size() / 3);
    for (const char* options : {"qhull Qt", "qhull QJ"}) {
        qhT qh_qh;
        qhT* qh = &qh_qh;
        qh_zero(qh, nullptr);
        std::vector<std::size_t> out;
        const int code = qh_new_qhull(qh, 3, n, pts.data(), False, const_cast<char*>(options), nullptr, nullptr);
        if (code == 0) {
            vertexT* vertex;
            FORALLvertices out.push_back(std::size_t(qh_pointid(qh, vertex->point)));
        }
        qh_freeqhull(qh, !qh_ALL);
        int curlong = 0, totlong = 0;
        qh_memfreeshort(qh, &curlong, &totlong);
        if (code == 0) return out;
    }
    throw Error("largest diameter",
                "qhull could not make the convex hull of the structure's " + std::to_string(n) + " vertices");
}

} // namespace

ShapeMeasures measure_shape(const Mesh& m, bool closed) {
    ShapeMeasures s;
    if (m.empty()) return s;
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& p : m.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    // The centroid: signed tetrahedra from the middle of the bounds (small
    // numbers, no cancellation far from the origin).
    const glm::dvec3 o = 0.5 * (lo + hi);
    double volume = 0;
    glm::dvec3 moment(0.0);
    for (const auto& t : m.triangles) {
        const glm::dvec3 a = glm::dvec3(m.positions[t[0]]) - o, b = glm::dvec3(m.positions[t[1]]) - o,
                         c = glm::dvec3(m.positions[t[2]]) - o;
        const double v = glm::dot(a, glm::cross(b, c)) / 6.0;
        volume += v;
        moment += v * (a + b + c) / 4.0;
    }
    s.solid = closed && volume != 0.0;
    s.centroid = volume != 0.0 ? o + moment / volume : o;
    // The largest diameter: every pair of hull vertices (the two ends of a
    // diameter are extreme points, so hull vertices).
    std::vector<double> pts;
    pts.reserve(3 * m.positions.size());
    for (const auto& p : m.positions) pts.insert(pts.end(), {double(p.x), double(p.y), double(p.z)});
    std::vector<std::size_t> hull;
    if (m.positions.size() >= 4) hull = hull_vertices(pts);
    if (hull.size() < 2) { // too few points for a hull: all of them
        hull.resize(m.positions.size());
        for (std::size_t i = 0; i < hull.size(); ++i) hull[i] = i;
    }
    s.hull_vertices = hull.size();
    double best = -1;
    for (std::size_t i = 0; i < hull.size(); ++i) {
        const glm::dvec3 a(m.positions[hull[i]]);
        for (std::size_t j = i + 1; j < hull.size(); ++j) {
            const glm::dvec3 d = glm::dvec3(m.positions[hull[j]]) - a;
            const double l = glm::dot(d, d);
            if (l > best) {
                best = l;
                s.feret_a = a;
                s.feret_b = glm::dvec3(m.positions[hull[j]]);
            }
        }
    }
    s.feret_mm = best > 0 ? std::sqrt(best) : 0.0;
    return s;
}

} // namespace iso
