#include "renderer/surface/scissors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>
#include <vtkTriangleFilter.h>

#include "io/error.hpp"
#include "io/vtk_mesh.hpp"
#include "renderer/surface/box_clip.hpp"

namespace iso {

namespace {

double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Distance from p to segment ab.
double segment_distance(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b) {
    const glm::dvec2 ab = b - a;
    const double len2 = glm::dot(ab, ab);
    const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    return glm::length(p - (a + t * ab));
}

void douglas_peucker(const std::vector<glm::dvec2>& p, std::size_t i, std::size_t j, double tol,
                     std::vector<bool>& keep) {
    double worst = -1;
    std::size_t at = i;
    for (std::size_t k = i + 1; k < j; ++k) {
        const double d = segment_distance(p[k % p.size()], p[i % p.size()], p[j % p.size()]);
        if (d > worst) {
            worst = d;
            at = k;
        }
    }
    if (worst <= tol) return;
    keep[at % p.size()] = true;
    douglas_peucker(p, i, at, tol, keep);
    douglas_peucker(p, at, j, tol, keep);
}

// Segments ab and cd meet (touching and overlapping included).
bool segments_meet(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c, const glm::dvec2& d) {
    const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
    const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
    const auto on = [](const glm::dvec2& p, const glm::dvec2& q, const glm::dvec2& r, double side) {
        return side == 0 && std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
               r.y <= std::max(p.y, q.y);
    };
    return on(a, b, c, d1) || on(a, b, d, d2) || on(c, d, a, d3) || on(c, d, b, d4);
}

bool in_triangle(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    // Counter-clockwise abc; on an edge counts as inside (it would block the ear).
    return cross2(b - a, p - a) >= 0 && cross2(c - b, p - b) >= 0 && cross2(a - c, p - c) >= 0;
}

// An unordered edge between two image points, for the outline's walls.
using Edge = std::pair<std::pair<double, double>, std::pair<double, double>>;
Edge edge_key(const glm::dvec2& a, const glm::dvec2& b) {
    std::pair<double, double> p{a.x, a.y}, q{b.x, b.y};
    if (q < p) std::swap(p, q);
    return {p, q};
}

// The rectangle around `m`'s projection and the outline, with the outline
// as a hole joined by a bridge from its rightmost corner to the right side:
// the region outside the outline as one polygon.
std::vector<glm::dvec2> outside_polygon(const Mesh& m, const std::vector<glm::dvec2>& outline,
                                        const OutlineSweep& sweep) {
    glm::dvec2 lo(1e300), hi(-1e300);
    for (const auto& p : outline) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    for (const auto& v : m.positions) {
        const auto p = sweep.project(glm::dvec3(v));
        if (!p) throw Error("scissors", "the surface reaches behind the eye: its outside cannot be swept");
        lo = glm::min(lo, *p);
        hi = glm::max(hi, *p);
    }
    const glm::dvec2 margin = 0.1 * (hi - lo) + glm::dvec2(10.0);
    lo -= margin;
    hi += margin;
    // The hole clockwise (the outline is counter-clockwise), from its rightmost corner.
    std::size_t right = 0;
    for (std::size_t i = 1; i < outline.size(); ++i)
        if (outline[i].x > outline[right].x) right = i;
    const glm::dvec2 h = outline[right], r(hi.x, h.y);
    std::vector<glm::dvec2> poly{r, {hi.x, hi.y}, {lo.x, hi.y}, {lo.x, lo.y}, {hi.x, lo.y}, r, h};
    for (std::size_t k = 1; k <= outline.size(); ++k)
        poly.push_back(outline[(right + outline.size() - k) % outline.size()]); // ends at h again
    return poly;
}

// The three inward half-spaces of triangle abc swept along its corners'
// rays; none for a triangle whose sweep is flat.
std::optional<std::array<HalfSpace, 3>> sweep_triangle(const std::array<glm::dvec2, 3>& t, const OutlineSweep& sweep) {
    std::array<std::pair<glm::dvec3, glm::dvec3>, 3> rays;
    for (int i = 0; i < 3; ++i) rays[std::size_t(i)] = sweep.ray(t[std::size_t(i)]);
    std::array<HalfSpace, 3> out;
    for (int i = 0; i < 3; ++i) {
        const auto& [op, dp] = rays[std::size_t(i)];
        const auto& [oq, dq] = rays[std::size_t((i + 1) % 3)];
        const auto& [orr, dr] = rays[std::size_t((i + 2) % 3)];
        glm::dvec3 n = glm::cross(dp, (oq - op) + dq);
        const double len = glm::length(n);
        if (!(len > 1e-12)) return std::nullopt;
        n /= len;
        const double side = glm::dot(n, orr + dr - op);
        if (!(std::abs(side) > 1e-12)) return std::nullopt;
        out[std::size_t(i)] = HalfSpace{op, side > 0 ? n : -n};
    }
    return out;
}

// The edges used by one triangle only, in (lower vertex, higher vertex)
// order, each with that triangle. A sorted array of every edge's use, not a
// map of edges to their triangles: a map allocated a node and a vector per
// edge, and under the sanitizers the scissors' GUI test spent most of its
// cut there.
std::vector<std::pair<std::array<std::uint32_t, 2>, std::size_t>> edges_used_once(const Mesh& m) {
    std::vector<std::pair<std::array<std::uint32_t, 2>, std::size_t>> uses;
    uses.reserve(3 * m.triangles.size());
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = m.triangles[t][std::size_t(e)], b = m.triangles[t][std::size_t((e + 1) % 3)];
            uses.push_back({{std::min(a, b), std::max(a, b)}, t});
        }
    std::sort(uses.begin(), uses.end());
    std::vector<std::pair<std::array<std::uint32_t, 2>, std::size_t>> once;
    for (std::size_t i = 0, j = 0; i < uses.size(); i = j) {
        for (j = i + 1; j < uses.size() && uses[j].first == uses[i].first;) ++j;
        if (j == i + 1) once.push_back(uses[i]);
    }
    return once;
}

// Where caps of two triangles' walls meet along a corner's ray (at a
// reflex corner of the outline), each cap was cut by its own triangle's
// planes: the same segment of the ray, split at different points. Each
// point lying on the other side's edge splits that edge's triangle, until
// every edge along the seam is shared (T-junctions closed).
void close_t_junctions(Mesh& m, double tol) {
    for (int round = 0; round < 64; ++round) {
        const auto once = edges_used_once(m);
        std::vector<std::uint32_t> loose; // vertices on an edge used once
        for (const auto& [e, t] : once) {
            loose.push_back(e[0]);
            loose.push_back(e[1]);
        }
        std::sort(loose.begin(), loose.end());
        loose.erase(std::unique(loose.begin(), loose.end()), loose.end());
        std::vector<bool> split(m.triangles.size(), false);
        std::vector<std::array<std::uint32_t, 3>> added;
        for (const auto& [e, t] : once) {
            if (split[t]) continue;
            const glm::dvec3 a(m.positions[e[0]]), b(m.positions[e[1]]);
            const glm::dvec3 ab = b - a;
            const double len2 = glm::dot(ab, ab);
            std::uint32_t best = 0;
            double best_t = 2;
            for (const std::uint32_t v : loose) {
                if (v == e[0] || v == e[1] || !(len2 > 0)) continue;
                const glm::dvec3 p(m.positions[v]);
                const double s = glm::dot(p - a, ab) / len2;
                if (s <= 0 || s >= 1 || glm::length(p - (a + s * ab)) > tol) continue;
                if (s < best_t) {
                    best_t = s;
                    best = v;
                }
            }
            if (best_t > 1) continue;
            // The triangle (x, y, z) with edge (x, y) on this edge: (x, v, z) and (v, y, z).
            auto tri = m.triangles[t];
            while (!((tri[0] == e[0] && tri[1] == e[1]) || (tri[0] == e[1] && tri[1] == e[0])))
                tri = {tri[1], tri[2], tri[0]};
            m.triangles[t] = {tri[0], best, tri[2]};
            added.push_back({best, tri[1], tri[2]});
            split[t] = true;
        }
        if (added.empty()) return;
        m.triangles.insert(m.triangles.end(), added.begin(), added.end());
    }
}

} // namespace

double signed_area2(const std::vector<glm::dvec2>& p) {
    double a = 0;
    for (std::size_t i = 0; i < p.size(); ++i) a += cross2(p[i], p[(i + 1) % p.size()]);
    return a;
}

std::vector<glm::dvec2> simplify_outline(const std::vector<glm::dvec2>& closed, double tolerance) {
    std::vector<glm::dvec2> p;
    for (const auto& q : closed)
        if (std::isfinite(q.x) && std::isfinite(q.y) && (p.empty() || glm::length(q - p.back()) > 1e-9)) p.push_back(q);
    while (p.size() > 1 && glm::length(p.front() - p.back()) <= 1e-9) p.pop_back();
    if (p.size() < 3) return p;
    // Anchored at the first corner and the one farthest from it.
    std::size_t far = 0;
    for (std::size_t i = 1; i < p.size(); ++i)
        if (glm::length(p[i] - p[0]) > glm::length(p[far] - p[0])) far = i;
    std::vector<bool> keep(p.size(), false);
    keep[0] = keep[far] = true;
    douglas_peucker(p, 0, far, tolerance, keep);
    douglas_peucker(p, far, p.size(), tolerance, keep);
    std::vector<glm::dvec2> out;
    for (std::size_t i = 0; i < p.size(); ++i)
        if (keep[i]) out.push_back(p[i]);
    return out;
}

bool outline_crosses_itself(const std::vector<glm::dvec2>& p) {
    const std::size_t n = p.size();
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec2 a = p[i], b = p[(i + 1) % n];
        // The next edge folding back over this one.
        const glm::dvec2 c = p[(i + 2) % n];
        if (n > 2 && cross2(b - a, c - b) == 0 && glm::dot(b - a, c - b) < 0) return true;
        for (std::size_t j = i + 2; j < n; ++j) {
            if (i == 0 && j == n - 1) continue; // neighbours through the closing corner
            if (segments_meet(a, b, p[j], p[(j + 1) % n])) return true;
        }
    }
    return false;
}

std::vector<std::array<std::size_t, 3>> triangulate_polygon(const std::vector<glm::dvec2>& poly) {
    std::vector<std::size_t> idx(poly.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
    if (signed_area2(poly) < 0) std::reverse(idx.begin(), idx.end());
    double scale = 0;
    for (const auto& p : poly) scale = std::max({scale, std::abs(p.x), std::abs(p.y)});
    const double eps = 1e-12 * std::max(1.0, scale * scale);
    std::vector<std::array<std::size_t, 3>> out;
    while (idx.size() > 3) {
        const std::size_t m = idx.size();
        bool cut = false;
        for (std::size_t k = 0; k < m && !cut; ++k) {
            const std::size_t a = idx[(k + m - 1) % m], b = idx[k], c = idx[(k + 1) % m];
            if (cross2(poly[b] - poly[a], poly[c] - poly[b]) <= eps) continue; // reflex or flat
            bool empty = true;
            for (const std::size_t v : idx) {
                const glm::dvec2& q = poly[v];
                if (q == poly[a] || q == poly[b] || q == poly[c]) continue; // a corner, or a bridge's copy of one
                if (in_triangle(q, poly[a], poly[b], poly[c])) {
                    empty = false;
                    break;
                }
            }
            if (!empty) continue;
            out.push_back({a, b, c});
            idx.erase(idx.begin() + std::ptrdiff_t(k));
            cut = true;
        }
        // No ear: a flat corner (three corners on a line) goes without a triangle.
        for (std::size_t k = 0; k < m && !cut; ++k) {
            const std::size_t a = idx[(k + m - 1) % m], b = idx[k], c = idx[(k + 1) % m];
            if (std::abs(cross2(poly[b] - poly[a], poly[c] - poly[b])) <= eps) {
                idx.erase(idx.begin() + std::ptrdiff_t(k));
                cut = true;
            }
        }
        if (!cut) throw Error("scissors", "the outline cannot be cut into triangles (it is not a simple polygon)");
    }
    if (idx.size() == 3 && cross2(poly[idx[1]] - poly[idx[0]], poly[idx[2]] - poly[idx[1]]) > eps)
        out.push_back({idx[0], idx[1], idx[2]});
    return out;
}

ScissorsCut scissors_cut(const Mesh& m, const std::vector<glm::dvec2>& outline, const OutlineSweep& sweep,
                         bool keep_inside) {
    ScissorsCut out;
    out.outline = simplify_outline(outline, 0.5);
    if (out.outline.size() < 3) throw Error("scissors", "the outline needs three corners or more");
    if (outline_crosses_itself(out.outline)) throw Error("scissors", "the outline crosses itself");
    if (signed_area2(out.outline) < 0) std::reverse(out.outline.begin(), out.outline.end());
    if (!(signed_area2(out.outline) > 1e-6)) throw Error("scissors", "the outline encloses no area");
    if (m.empty()) return out;
    const std::vector<glm::dvec2> region = keep_inside ? out.outline : outside_polygon(m, out.outline, sweep);
    std::map<Edge, int> walls; // the outline's edges: their caps stay
    for (std::size_t i = 0; i < out.outline.size(); ++i)
        walls[edge_key(out.outline[i], out.outline[(i + 1) % out.outline.size()])] = 1;
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& v : m.positions) {
        lo = glm::min(lo, glm::dvec3(v));
        hi = glm::max(hi, glm::dvec3(v));
    }
    const double tol = 1e-5 * std::max(glm::length(hi - lo), 1e-3);
    vtkNew<vtkPoints> points;
    vtkNew<vtkCellArray> cells;
    for (const auto& t : triangulate_polygon(region)) {
        const std::array<glm::dvec2, 3> corners{region[t[0]], region[t[1]], region[t[2]]};
        const auto planes = sweep_triangle(corners, sweep);
        if (!planes) continue;
        ++out.pieces;
        const Mesh piece = clip_closed(m, {(*planes)[0], (*planes)[1], (*planes)[2]});
        if (piece.triangles.empty()) continue;
        ++out.pieces_with_part;
        // The caps on inner walls go: the triangle beside it covers the other side.
        std::vector<const HalfSpace*> inner;
        for (int i = 0; i < 3; ++i)
            if (!walls.count(edge_key(corners[std::size_t(i)], corners[std::size_t((i + 1) % 3)])))
                inner.push_back(&(*planes)[std::size_t(i)]);
        const vtkIdType base = points->GetNumberOfPoints();
        for (const auto& v : piece.positions) points->InsertNextPoint(v.x, v.y, v.z);
        for (const auto& tri : piece.triangles) {
            bool cap = false;
            for (const HalfSpace* h : inner) {
                bool on = true;
                for (const auto i : tri)
                    on = on && std::abs(glm::dot(glm::dvec3(piece.positions[i]) - h->origin, h->normal)) <= tol;
                cap = cap || on;
            }
            if (cap) continue;
            const vtkIdType ids[3] = {base + vtkIdType(tri[0]), base + vtkIdType(tri[1]), base + vtkIdType(tri[2])};
            cells->InsertNextCell(3, ids);
        }
    }
    if (cells->GetNumberOfCells() == 0) return out;
    vtkNew<vtkPolyData> joined;
    joined->SetPoints(points);
    joined->SetPolys(cells);
    // The crossings both sides of an inner wall computed, welded.
    vtkNew<vtkCleanPolyData> weld;
    weld->SetInputData(joined);
    weld->ToleranceIsAbsoluteOn();
    weld->SetAbsoluteTolerance(tol);
    vtkNew<vtkTriangleFilter> tri;
    tri->SetInputConnection(weld->GetOutputPort());
    tri->PassLinesOff();
    tri->PassVertsOff();
    vtkNew<vtkPolyDataNormals> n;
    n->SetInputConnection(tri->GetOutputPort());
    n->SplittingOff();
    n->ConsistencyOff();
    n->AutoOrientNormalsOff();
    n->ComputeCellNormalsOff();
    n->Update();
    out.part = from_polydata(n->GetOutput(), "scissors");
    close_t_junctions(out.part, tol);
    return out;
}

OutlineSweep outline_sweep(const ViewOutline& v) {
    if (v.width <= 0 || v.height <= 0) throw Error("scissors", "the view has no size");
    if (!(std::abs(glm::determinant(v.view_projection)) > 0)) throw Error("scissors", "the view's matrix is singular");
    const glm::dmat4 clip = v.view_projection, inv = glm::inverse(clip);
    const double w = v.width, h = v.height;
    OutlineSweep sweep;
    sweep.project = [clip, w, h](const glm::dvec3& p) -> std::optional<glm::dvec2> {
        const glm::dvec4 c = clip * glm::dvec4(p, 1.0);
        if (!(c.w > 0)) return std::nullopt;
        return glm::dvec2((c.x / c.w + 1) * 0.5 * w, (1 - c.y / c.w) * 0.5 * h);
    };
    sweep.ray = [inv, eye = v.eye, w, h](const glm::dvec2& q) {
        const double nx = q.x / w * 2.0 - 1.0, ny = 1.0 - q.y / h * 2.0;
        const auto unproject = [&](double z) {
            const glm::dvec4 p = inv * glm::dvec4(nx, ny, z, 1.0);
            return glm::dvec3(p) / p.w;
        };
        // Reversed Z: depth 1 at the near plane, 0.5 on the way to the far one.
        return std::make_pair(eye, glm::normalize(unproject(0.5) - unproject(1.0)));
    };
    return sweep;
}

ScissorsCut scissors_cut(const Mesh& m, const ViewOutline& v) {
    return scissors_cut(m, v.outline, outline_sweep(v), v.keep_inside);
}

} // namespace iso
