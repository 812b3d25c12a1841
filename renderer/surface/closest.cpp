#include "renderer/surface/closest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "io/error.hpp"
#include "renderer/surface/analysis.hpp"

namespace iso {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The closest points of segments [p1, q1] and [p2, q2] (Ericson 5.1.9): the
// parameters minimising |p1 + s d1 - p2 - t d2| over [0, 1]^2, clamped in
// turn; a zero-length segment is its point; parallel segments take s = 0
// and then the t it clamps to (any pair on the overlap is as close).
ClosestPair segment_distance(const glm::dvec3& p1, const glm::dvec3& q1, const glm::dvec3& p2, const glm::dvec3& q2) {
    const glm::dvec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, r);
    double s = 0, t = 0;
    if (a <= 0 && e <= 0) {
        s = t = 0;
    } else if (a <= 0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = glm::dot(d1, r);
        if (e <= 0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = glm::dot(d1, d2), denom = a * e - b * b;
            s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    ClosestPair out;
    out.a = p1 + s * d1;
    out.b = p2 + t * d2;
    out.distance_mm = glm::length(out.a - out.b);
    return out;
}

// Twice the triangle's area, squared, against its longest edge's length to
// the fourth: below this ratio the triangle is a segment for our purposes.
bool degenerate(const TriangleCorners& t) {
    const glm::dvec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
    const double l = std::max(
        {glm::dot(t[1] - t[0], t[1] - t[0]), glm::dot(t[2] - t[1], t[2] - t[1]), glm::dot(t[0] - t[2], t[0] - t[2])});
    return !(glm::dot(n, n) > 1e-24 * l * l);
}

// The point of a non-degenerate triangle nearest to p (Ericson 5.1.5: the
// Voronoi region of p among the corners, edges and face).
glm::dvec3 nearest_on_triangle(const glm::dvec3& p, const TriangleCorners& t) {
    const glm::dvec3 &a = t[0], &b = t[1], &c = t[2];
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

// Where segment [p, q] crosses the (non-degenerate) triangle, if it does
// (Möller-Trumbore with the segment's parameter in [0, 1]).
std::optional<glm::dvec3> segment_crossing(const glm::dvec3& p, const glm::dvec3& q, const TriangleCorners& t) {
    const glm::dvec3 d = q - p, e1 = t[1] - t[0], e2 = t[2] - t[0], h = glm::cross(d, e2);
    const double det = glm::dot(e1, h);
    if (det == 0) return std::nullopt; // parallel: the edge-edge distances see a coplanar overlap
    const glm::dvec3 s = p - t[0], qv = glm::cross(s, e1);
    const double u = glm::dot(s, h) / det, v = glm::dot(d, qv) / det, x = glm::dot(e2, qv) / det;
    if (u < 0 || v < 0 || u + v > 1 || x < 0 || x > 1) return std::nullopt;
    return p + x * d;
}

void keep_nearer(ClosestPair& best, const ClosestPair& c) {
    if (c.distance_mm < best.distance_mm) best = c;
}

double box_distance_sq(const glm::dvec3& lo1, const glm::dvec3& hi1, const glm::dvec3& lo2, const glm::dvec3& hi2) {
    double d = 0;
    for (int k = 0; k < 3; ++k) {
        const double gap = std::max({0.0, lo1[k] - hi2[k], lo2[k] - hi1[k]});
        d += gap * gap;
    }
    return d;
}

void check_mesh(const Mesh& m, const char* what, const std::vector<std::uint32_t>& tris) {
    if (tris.empty()) throw Error(what, "a surface has no triangles");
    for (std::uint32_t t : tris) {
        if (t >= m.triangles.size())
            throw Error(what, "triangle " + std::to_string(t) + " is not in the mesh (" +
                                  std::to_string(m.triangles.size()) + " triangles)");
        for (std::uint32_t v : m.triangles[t]) {
            if (v >= m.positions.size())
                throw Error(what, "a triangle names vertex " + std::to_string(v) + " of " +
                                      std::to_string(m.positions.size()));
            const glm::vec3& p = m.positions[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw Error(what, "vertex " + std::to_string(v) + " is not finite");
        }
    }
}

} // namespace

ClosestPair point_triangle_distance(const glm::dvec3& p, const TriangleCorners& t) {
    ClosestPair out;
    out.a = p;
    if (degenerate(t)) {
        out.distance_mm = kInf;
        for (int i = 0; i < 3; ++i) {
            const ClosestPair s = segment_distance(p, p, t[std::size_t(i)], t[std::size_t((i + 1) % 3)]);
            if (s.distance_mm < out.distance_mm) {
                out.distance_mm = s.distance_mm;
                out.b = s.b;
            }
        }
        return out;
    }
    out.b = nearest_on_triangle(p, t);
    out.distance_mm = glm::length(out.b - p);
    return out;
}

ClosestPair triangle_distance(const TriangleCorners& a, const TriangleCorners& b) {
    ClosestPair best;
    best.distance_mm = kInf;
    for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j)
            keep_nearer(best, segment_distance(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]));
    const bool flat_a = degenerate(a), flat_b = degenerate(b);
    // Corner to face (a degenerate triangle's face is its edges, measured above).
    if (!flat_b)
        for (const auto& p : a) keep_nearer(best, point_triangle_distance(p, b));
    if (!flat_a)
        for (const auto& p : b) {
            const ClosestPair c = point_triangle_distance(p, a);
            keep_nearer(best, ClosestPair{c.distance_mm, c.b, c.a});
        }
    if (best.distance_mm == 0) return best;
    // Crossing triangles: an edge of one passes through the other.
    for (std::size_t i = 0; i < 3; ++i) {
        if (!flat_b)
            if (const auto x = segment_crossing(a[i], a[(i + 1) % 3], b)) return ClosestPair{0.0, *x, *x};
        if (!flat_a)
            if (const auto x = segment_crossing(b[i], b[(i + 1) % 3], a)) return ClosestPair{0.0, *x, *x};
    }
    return best;
}

// ---- the hierarchy ------------------------------------------------------------------

TriangleBvh::TriangleBvh(const Mesh& mesh) : mesh_(mesh), tris_(mesh.triangles.size()) {
    std::iota(tris_.begin(), tris_.end(), std::uint32_t(0));
    build();
}

TriangleBvh::TriangleBvh(const Mesh& mesh, std::vector<std::uint32_t> triangles)
    : mesh_(mesh), tris_(std::move(triangles)) {
    build();
}

TriangleCorners triangle_corners(const Mesh& m, std::uint32_t t) {
    const auto& tri = m.triangles[t];
    return {glm::dvec3(m.positions[tri[0]]), glm::dvec3(m.positions[tri[1]]), glm::dvec3(m.positions[tri[2]])};
}

TriangleCorners TriangleBvh::corners(std::uint32_t t) const { return triangle_corners(mesh_, t); }

// The build works on one array of these, partitioned in place: a median
// split reorders its range and nothing else is allocated (a copy of the
// range per node, kept while its children were built, took 80 bytes a
// triangle at every depth: 8 GB above the mesh for the 1024^3 phantom's
// 32.5 M triangles, and a minute). Boxes in float are exact (the corners
// are floats); the centroids only order the split.
struct TriangleBvh::Prim {
    glm::vec3 centroid, lo, hi;
    std::uint32_t triangle;
};

namespace {
// The nodes build_node makes for `count` triangles (the counts at one depth
// take at most two values, so the memo stays small).
std::size_t node_count(std::size_t count, std::map<std::size_t, std::size_t>& memo) {
    if (count <= 4) return 1;
    if (const auto it = memo.find(count); it != memo.end()) return it->second;
    const std::size_t n = 1 + node_count(count / 2, memo) + node_count(count - count / 2, memo);
    memo[count] = n;
    return n;
}
std::size_t node_count(std::size_t count) {
    std::map<std::size_t, std::size_t> memo;
    return node_count(count, memo);
}
} // namespace

void TriangleBvh::build() {
    check_mesh(mesh_, "surface distance", tris_);
    std::vector<Prim> prims(tris_.size());
    for (std::size_t i = 0; i < tris_.size(); ++i) {
        const auto& t = mesh_.triangles[tris_[i]];
        const glm::vec3 a = mesh_.positions[t[0]], b = mesh_.positions[t[1]], c = mesh_.positions[t[2]];
        prims[i] = {(a + b + c) / 3.0f, glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c)), tris_[i]};
    }
    nodes_.reserve(node_count(tris_.size())); // exactly: a vector grown by doubling held 3x the nodes at once
    build_node(0, std::uint32_t(tris_.size()), prims);
    for (std::size_t i = 0; i < prims.size(); ++i) tris_[i] = prims[i].triangle;
}

std::uint32_t TriangleBvh::build_node(std::uint32_t first, std::uint32_t count, std::vector<Prim>& prims) {
    const std::uint32_t index = std::uint32_t(nodes_.size());
    nodes_.push_back({});
    glm::vec3 lo(kInf), hi(-kInf), clo(kInf), chi(-kInf);
    for (std::uint32_t i = first; i < first + count; ++i) {
        lo = glm::min(lo, prims[i].lo);
        hi = glm::max(hi, prims[i].hi);
        clo = glm::min(clo, prims[i].centroid);
        chi = glm::max(chi, prims[i].centroid);
    }
    Node n;
    n.lo = lo;
    n.hi = hi;
    if (count <= 4) {
        n.first = first;
        n.count = count;
        nodes_[index] = n;
        return index;
    }
    // The median along the centroids' longest axis (ties by triangle: the same tree every time).
    const glm::vec3 ext = chi - clo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    const std::uint32_t half = count / 2;
    const auto begin = prims.begin() + first;
    std::nth_element(begin, begin + half, begin + count, [axis](const Prim& x, const Prim& y) {
        return x.centroid[axis] < y.centroid[axis] || (x.centroid[axis] == y.centroid[axis] && x.triangle < y.triangle);
    });
    n.left = build_node(first, half, prims);
    n.right = build_node(first + half, count - half, prims);
    nodes_[index] = n;
    return index;
}

// ---- queries ------------------------------------------------------------------------

SurfaceDistance surface_distance(const TriangleBvh& a, const TriangleBvh& b) {
    SurfaceDistance out;
    out.pair.distance_mm = kInf;
    const auto& na = a.nodes();
    const auto& nb = b.nodes();
    struct Item {
        std::uint32_t i, j;
        double lower_sq; // the boxes' distance, squared
    };
    std::vector<Item> stack{{0, 0, box_distance_sq(na[0].lo, na[0].hi, nb[0].lo, nb[0].hi)}};
    const auto best_sq = [&] { return out.pair.distance_mm * out.pair.distance_mm; };
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        if (it.lower_sq >= best_sq()) continue;
        const auto &x = na[it.i], &y = nb[it.j];
        if (x.count && y.count) {
            for (std::uint32_t p = x.first; p < x.first + x.count; ++p)
                for (std::uint32_t q = y.first; q < y.first + y.count; ++q) {
                    const std::uint32_t ta = a.triangles()[p], tb = b.triangles()[q];
                    const ClosestPair c = triangle_distance(a.corners(ta), b.corners(tb));
                    ++out.triangle_pairs;
                    if (c.distance_mm < out.pair.distance_mm) {
                        out.pair = c;
                        out.triangle_a = ta;
                        out.triangle_b = tb;
                    }
                }
            continue;
        }
        // Split the inner node with the larger box (a leaf is never split).
        const auto diag = [](const TriangleBvh::Node& n) { return glm::dot(n.hi - n.lo, n.hi - n.lo); };
        const bool split_a = !x.count && (y.count || diag(x) >= diag(y));
        Item c1 = split_a ? Item{x.left, it.j, 0} : Item{it.i, y.left, 0};
        Item c2 = split_a ? Item{x.right, it.j, 0} : Item{it.i, y.right, 0};
        for (Item* c : {&c1, &c2}) c->lower_sq = box_distance_sq(na[c->i].lo, na[c->i].hi, nb[c->j].lo, nb[c->j].hi);
        if (c1.lower_sq < c2.lower_sq) std::swap(c1, c2); // the nearer pair is taken first
        stack.push_back(c1);
        stack.push_back(c2);
    }
    out.touching = out.pair.distance_mm == 0;
    return out;
}

SurfaceDistance surface_distance_brute_force(const Mesh& a, const Mesh& b) {
    std::vector<std::uint32_t> all_a(a.triangles.size()), all_b(b.triangles.size());
    std::iota(all_a.begin(), all_a.end(), 0u);
    std::iota(all_b.begin(), all_b.end(), 0u);
    check_mesh(a, "surface distance", all_a);
    check_mesh(b, "surface distance", all_b);
    SurfaceDistance out;
    out.pair.distance_mm = kInf;
    for (std::uint32_t i : all_a)
        for (std::uint32_t j : all_b) {
            const ClosestPair c = triangle_distance(triangle_corners(a, i), triangle_corners(b, j));
            ++out.triangle_pairs;
            if (c.distance_mm < out.pair.distance_mm) {
                out.pair = c;
                out.triangle_a = i;
                out.triangle_b = j;
            }
        }
    out.touching = out.pair.distance_mm == 0;
    return out;
}

NearestPoint nearest_point(const TriangleBvh& bvh, const glm::dvec3& p) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw Error("nearest point", "the point is not finite");
    NearestPoint out;
    out.distance_mm = kInf;
    const auto& nodes = bvh.nodes();
    std::vector<std::pair<std::uint32_t, double>> stack{{0, box_distance_sq(p, p, nodes[0].lo, nodes[0].hi)}};
    while (!stack.empty()) {
        const auto [i, lower_sq] = stack.back();
        stack.pop_back();
        if (lower_sq >= out.distance_mm * out.distance_mm) continue;
        const auto& n = nodes[i];
        if (n.count) {
            for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
                const std::uint32_t t = bvh.triangles()[k];
                const ClosestPair c = point_triangle_distance(p, bvh.corners(t));
                if (c.distance_mm < out.distance_mm) out = {c.b, c.distance_mm, t};
            }
            continue;
        }
        const double l = box_distance_sq(p, p, nodes[n.left].lo, nodes[n.left].hi);
        const double r = box_distance_sq(p, p, nodes[n.right].lo, nodes[n.right].hi);
        if (l < r) {
            stack.push_back({n.right, r});
            stack.push_back({n.left, l});
        } else {
            stack.push_back({n.left, l});
            stack.push_back({n.right, r});
        }
    }
    return out;
}

NearestComponent nearest_component(const Mesh& m, const glm::dvec3& at) {
    NearestComponent out;
    out.nearest = nearest_point(TriangleBvh(m), at);
    out.triangle_component = triangle_components(m);
    out.component = out.triangle_component[out.nearest.triangle];
    return out;
}

std::vector<SegmentCrossing> segment_crossings(const TriangleBvh& bvh, const glm::dvec3& p, const glm::dvec3& q) {
    std::vector<SegmentCrossing> out;
    const glm::dvec3 lo = glm::min(p, q), hi = glm::max(p, q);
    const auto& nodes = bvh.nodes();
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {
        const auto& n = nodes[stack.back()];
        stack.pop_back();
        // The segment's box against the node's: a cheap, conservative cull.
        if (box_distance_sq(lo, hi, n.lo, n.hi) > 0) continue;
        if (!n.count) {
            stack.push_back(n.left);
            stack.push_back(n.right);
            continue;
        }
        for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
            const std::uint32_t t = bvh.triangles()[k];
            const TriangleCorners c = bvh.corners(t);
            if (degenerate(c)) continue;
            if (const auto x = segment_crossing(p, q, c)) {
                const glm::dvec3 d = q - p;
                const double len2 = glm::dot(d, d);
                out.push_back({len2 > 0 ? glm::dot(*x - p, d) / len2 : 0.0, t});
            }
        }
    }
    std::sort(out.begin(), out.end(), [](const SegmentCrossing& a, const SegmentCrossing& b) {
        return a.t < b.t || (a.t == b.t && a.triangle < b.triangle);
    });
    return out;
}

} // namespace iso
