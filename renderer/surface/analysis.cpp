// Measurements (measure.hpp, docs/measure.md).
//
// Written here rather than taken from VTK: vtkMassProperties (Slicer's
// Segment Statistics) assumes a closed surface and never checks, so on an
// open surface its volume is meaningless; vtkMultiObjectMassProperties flags
// open objects but neither caps them nor reports their boundaries; neither
// welds STL triangle soups, runs in parallel or estimates an uncertainty.
#include "io/finite.hpp"
#include "io/markups.hpp"
#include "renderer/surface/arena.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/atomic.hpp"
#include "renderer/surface/component_sums.hpp"
#include "renderer/surface/edges.hpp"
#include "renderer/surface/union_find.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "io/error.hpp"
#include "io/sparse.hpp"

namespace iso {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::uint32_t kNone = ~std::uint32_t(0);
constexpr const char* kWhere = "surface measure";

// a + (b - a) t that ignores b at t == 0 (and a at t == 1), so a NaN sample
// with no weight does not spread.
double lerp(double a, double b, double t) { return t == 0.0 ? a : t == 1.0 ? b : a + (b - a) * t; }

// ---- welding by exact position ---------------------------------------------------

struct PosKey {
    std::uint32_t x, y, z;
    bool operator==(const PosKey&) const = default;
};

PosKey pos_key(const glm::vec3& p) {
    auto bits = [](float f) {
        if (f == 0.0f) f = 0.0f; // -0 and +0 are one position
        std::uint32_t u;
        std::memcpy(&u, &f, sizeof u);
        return u;
    };
    return {bits(p.x), bits(p.y), bits(p.z)};
}

std::uint64_t mix64(std::uint64_t h) { // splitmix64's finalizer
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ULL;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebULL;
    return h ^ (h >> 31);
}

std::uint64_t hash_key(const PosKey& k) {
    return mix64(((std::uint64_t(k.x) << 32) | k.y) ^ mix64(k.z + 0x9e3779b97f4a7c15ULL));
}

// For each vertex, the smallest index of a vertex at the same position. The
// vertices are partitioned by the top bits of their hash, and each partition
// is welded through its own small open-addressing table (cache-resident) in
// parallel; partitions keep index order, so the result is deterministic.
std::vector<std::uint32_t> weld_positions(const std::vector<glm::vec3>& p) {
    const std::size_t n = p.size();
    std::vector<std::uint32_t> canon(n);
    if (n == 0) return canon;
    int bits = 0;
    while ((std::size_t(4096) << bits) < n && bits < 16) ++bits;
    const std::size_t parts = std::size_t(1) << bits;
    auto part_of = [&](std::uint64_t h) { return bits ? std::size_t(h >> (64 - bits)) : 0; };
    // The vertices as (key, index) records, grouped by partition in index order.
    struct Record {
        PosKey key;
        std::uint32_t index;
    };
    std::vector<std::uint64_t> h(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) h[i] = hash_key(pos_key(p[i]));
    });
    std::vector<std::size_t> start(parts + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++start[part_of(h[i]) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<Record> records(n);
    {
        std::vector<std::size_t> cur(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < n; ++i) records[cur[part_of(h[i])]++] = {pos_key(p[i]), std::uint32_t(i)};
    }
    h = {};
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> tables; // slot -> record offset in the partition
    tbb::parallel_for(std::size_t(0), parts, [&](std::size_t part) {
        const Record* rec = records.data() + start[part];
        const std::size_t count = start[part + 1] - start[part];
        if (count == 0) return;
        std::size_t cap = 16;
        while (cap < 2 * count) cap *= 2;
        auto& table = tables.local();
        table.assign(cap, kNone);
        const std::size_t mask = cap - 1;
        for (std::uint32_t o = 0; o < count; ++o) {
            for (std::size_t s = hash_key(rec[o].key) & mask;; s = (s + 1) & mask) {
                if (table[s] == kNone) {
                    table[s] = o;
                    canon[rec[o].index] = rec[o].index;
                    break;
                }
                if (rec[table[s]].key == rec[o].key) {
                    canon[rec[o].index] = rec[table[s]].index;
                    break;
                }
            }
        }
    });
    return canon;
}

// ---- the analysis ----------------------------------------------------------------
//
// measure_surface's steps (docs/measure.md, "Surfaces"), each a function:
// check_input, weld_triangles, connected_components, component_bounds,
// classify_edges, component_sums, boundary_loops, then the components
// ordered and totalled (order_components, add_totals) and the warnings.

using Triangle = std::array<std::uint32_t, 3>;

// A triangle with a repeated vertex after welding: zero area, left out of the edges.
bool collapsed(const Triangle& w) { return w[0] == w[1] || w[1] == w[2] || w[0] == w[2]; }

struct Analysis {
    SurfaceMeasures m;
    // Per input vertex: its component (index into m.components), kNone when
    // no triangle uses it.
    std::vector<std::uint32_t> vertex_component;
};

// Throws for a mesh beyond the edge encoding's sizes, a triangle that names
// a missing vertex or a vertex that is not finite. The checks run in
// parallel; the first bad triangle or vertex is named.
void check_input(const Mesh& mesh) {
    const auto& P = mesh.positions;
    const auto& T = mesh.triangles;
    const std::size_t nv = P.size(), nt = T.size();
    // Vertex indices fit 31 bits (edge entries) and 3 x triangles fit 32 (edge offsets).
    if (nv >= (std::size_t(1) << 31) || nt >= (std::size_t(1) << 30))
        throw Error(kWhere, "more than 2^31 vertices or 2^30 triangles");
    std::atomic<std::size_t> bad_tri{nt}, bad_vertex{nv};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t)
            if (T[t][0] >= nv || T[t][1] >= nv || T[t][2] >= nv) atomic_min(bad_tri, t);
    });
    if (bad_tri.load() < nt) {
        const std::size_t t = bad_tri.load();
        throw Error(kWhere, "triangle " + std::to_string(t) + " names vertex " +
                                std::to_string(std::max({T[t][0], T[t][1], T[t][2]})) + " of " + std::to_string(nv));
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 14), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            if (!finite(glm::dvec3(P[i]))) atomic_min(bad_vertex, i);
    });
    if (bad_vertex.load() < nv) throw Error(kWhere, "vertex " + std::to_string(bad_vertex.load()) + " is not finite");
}

// Step 1: the triangles over canonical vertices (equal positions are one
// vertex). Where no vertex is renamed (an extracted surface: its vertices
// are distinct), the mesh's own triangles, not a copy of them.
struct Welded {
    std::vector<std::uint32_t> canon; // per input vertex: weld_positions
    std::vector<Triangle> renamed;    // the triangles with renamed vertices, if any was
    bool any_renamed = false;
    const std::vector<Triangle>& triangles(const Mesh& m) const { return any_renamed ? renamed : m.triangles; }
};

Welded weld_triangles(const Mesh& mesh) {
    const auto& T = mesh.triangles;
    Welded w{weld_positions(mesh.positions), {}, false};
    w.any_renamed = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, w.canon.size(), 1 << 16), false,
        [&](const auto& r, bool any) {
            for (std::size_t v = r.begin(); v != r.end() && !any; ++v) any = w.canon[v] != v;
            return any;
        },
        [](bool a, bool b) { return a || b; });
    if (!w.any_renamed) return w;
    w.renamed.resize(T.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, T.size(), 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t)
            w.renamed[t] = {w.canon[T[t][0]], w.canon[T[t][1]], w.canon[T[t][2]]};
    });
    return w;
}

// Step 2: the components of the canonical vertices that triangles use.
struct Components {
    std::uint32_t count = 0;
    std::vector<std::uint8_t> used;   // per canonical vertex: a triangle uses it
    std::vector<std::uint32_t> label; // per used canonical vertex: its component; kNone elsewhere
    std::uint32_t of(std::uint32_t canonical) const { return label[canonical]; }
};

// Union-find in parallel (collapsed triangles connect too). Every set's root
// is its smallest member, whatever the order of the unions, so the
// components are numbered in the order of their smallest vertex
// (deterministic), and a vertex's root is labelled before it.
Components connected_components(const std::vector<Triangle>& W, std::size_t nv) {
    Components c;
    c.used.assign(nv, 0);
    ConcurrentUnionFind sets(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, W.size(), 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const auto& w = W[t];
            for (const auto v : w) std::atomic_ref<std::uint8_t>(c.used[v]).store(1, std::memory_order_relaxed);
            sets.unite(w[0], w[1]);
            sets.unite(w[0], w[2]);
        }
    });
    c.label.assign(nv, kNone);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 16), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v)
            if (c.used[v]) c.label[v] = sets.find(std::uint32_t(v));
    });
    for (std::uint32_t v = 0; v < nv; ++v) { // roots to numbers; a root comes before its members
        if (!c.used[v]) continue;
        const std::uint32_t root = c.label[v];
        c.label[v] = root == v ? c.count++ : c.label[root];
    }
    return c;
}

// Per component: bounds and the reference point (the bounds' centre) that
// its sums are taken about; and the distinct vertices the triangles use.
struct ComponentBounds {
    std::vector<glm::dvec3> lo, hi, ref;
    std::size_t vertices = 0;
};

// In parallel (sum_by_component over the used canonical vertices: minima
// and maxima are exact in any order).
ComponentBounds component_bounds(const std::vector<glm::vec3>& P, const std::vector<std::uint32_t>& canon,
                                 const Components& comps) {
    struct Box {
        glm::dvec3 lo{std::numeric_limits<double>::max()}, hi{std::numeric_limits<double>::lowest()};
        std::size_t vertices = 0;
    };
    const auto comp = [&](std::size_t v) {
        return comps.used[v] && canon[v] == v ? comps.of(std::uint32_t(v)) : kNotInAComponent;
    };
    const auto add = [&](Box& b, std::size_t v) {
        b.lo = glm::min(b.lo, glm::dvec3(P[v]));
        b.hi = glm::max(b.hi, glm::dvec3(P[v]));
        ++b.vertices;
    };
    const auto merge = [](Box& b, const Box& part) {
        b.lo = glm::min(b.lo, part.lo);
        b.hi = glm::max(b.hi, part.hi);
        b.vertices += part.vertices;
    };
    const std::vector<Box> boxes = sum_by_component<Box>(P.size(), comps.count, comp, add, merge);
    ComponentBounds b;
    for (const Box& box : boxes) {
        b.lo.push_back(box.lo);
        b.hi.push_back(box.hi);
        b.ref.push_back(0.5 * (box.lo + box.hi));
        b.vertices += box.vertices;
    }
    return b;
}

struct BoundaryEdge {
    std::uint32_t from, to;
    bool operator<(const BoundaryEdge& o) const { return from != o.from ? from < o.from : to < o.to; }
};

// Step 3: every edge classified by its uses (SurfaceMeasures' edge counts),
// with the boundary edges kept for the loops and the counts per component.
struct EdgeCounts {
    std::size_t boundary = 0, non_manifold = 0, misoriented = 0;
    std::vector<BoundaryEdge> chain; // boundary edges, directed as the triangles use them (with multiplicity), sorted
    std::vector<std::size_t> comp_boundary, comp_misoriented;
};

// Each bucket sorted and its runs (one edge each) classified, in parallel.
EdgeCounts classify_edges(const std::vector<Triangle>& W, const Components& comps, std::size_t nv) {
    EdgeBuckets buckets = bucket_edges(W, nv, true); // the non-collapsed triangles' edges
    struct EdgeLocal {
        std::size_t boundary = 0, non_manifold = 0, misoriented = 0;
        std::vector<BoundaryEdge> chain;
        std::vector<std::uint32_t> boundary_comp; // component of each boundary edge (undirected, once)
        std::vector<std::uint32_t> misoriented_comp;
    };
    tbb::enumerable_thread_specific<EdgeLocal> edge_locals;
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, std::uint32_t(nv), 4096), [&](const auto& r) {
        auto& L = edge_locals.local();
        for (std::uint32_t l = r.begin(); l != r.end(); ++l) {
            auto* b = buckets.entries.data() + buckets.offset[l];
            auto* e = buckets.entries.data() + buckets.offset[l + 1];
            if (b == e) continue;
            std::sort(b, e);
            for (auto* run = b; run != e;) {
                const std::uint32_t upper = *run >> 1;
                std::size_t fwd = 0, back = 0;
                for (; run != e && (*run >> 1) == upper; ++run) (*run & 1 ? fwd : back)++;
                const std::uint32_t u = std::uint32_t(upper);
                const std::size_t uses = fwd + back;
                if (uses >= 3) ++L.non_manifold;
                if (fwd == back) continue;
                if (uses == 2) { // two triangles, same direction
                    ++L.misoriented;
                    L.misoriented_comp.push_back(comps.of(l));
                    continue;
                }
                ++L.boundary;
                L.boundary_comp.push_back(comps.of(l));
                const BoundaryEdge d = fwd > back ? BoundaryEdge{l, u} : BoundaryEdge{u, l};
                for (std::size_t x = 0; x < (fwd > back ? fwd - back : back - fwd); ++x) L.chain.push_back(d);
            }
        }
    });
    EdgeCounts out;
    out.comp_boundary.assign(comps.count, 0);
    out.comp_misoriented.assign(comps.count, 0);
    for (auto& L : edge_locals) {
        out.boundary += L.boundary;
        out.non_manifold += L.non_manifold;
        out.misoriented += L.misoriented;
        out.chain.insert(out.chain.end(), L.chain.begin(), L.chain.end());
        for (auto c : L.boundary_comp) ++out.comp_boundary[c];
        for (auto c : L.misoriented_comp) ++out.comp_misoriented[c];
    }
    std::sort(out.chain.begin(), out.chain.end());
    return out;
}

struct Accum {
    double area = 0, volume = 0; // mm^2, mm^3 (relative to the component's reference point)
    std::size_t triangles = 0, degenerate = 0;
};

// Step 4: area and volume per component, summed in a way that does not
// depend on the thread count (sum_by_component).
std::vector<Accum> component_sums(const std::vector<glm::vec3>& P, const std::vector<Triangle>& W,
                                  const Components& comps, const std::vector<glm::dvec3>& ref) {
    const auto comp = [&](std::size_t t) { return comps.of(W[t][0]); };
    const auto add = [&](Accum& a, std::size_t t) {
        const auto& w = W[t];
        ++a.triangles;
        if (collapsed(w)) {
            ++a.degenerate;
            return;
        }
        const glm::dvec3& r = ref[comps.of(w[0])];
        const glm::dvec3 p0 = glm::dvec3(P[w[0]]) - r, p1 = glm::dvec3(P[w[1]]) - r, p2 = glm::dvec3(P[w[2]]) - r;
        const double area = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
        if (area == 0.0) ++a.degenerate;
        a.area += area;
        a.volume += glm::dot(p0, glm::cross(p1, p2)) / 6.0;
    };
    const auto merge = [](Accum& a, const Accum& part) {
        a.area += part.area;
        a.volume += part.volume;
        a.triangles += part.triangles;
        a.degenerate += part.degenerate;
    };
    return sum_by_component<Accum>(W.size(), comps.count, comp, add, merge);
}

// Step 5: per component, its boundary loops, their length and the volume of
// their caps (mm^3, about the component's reference point).
struct BoundaryLoops {
    std::vector<std::size_t> loops;
    std::vector<double> length, cap;
    bool open_chain = false; // a walk found no way on: some boundary edges form no closed loop
};

// The boundary edges, as the triangles use them, form closed walks (the
// boundary of a boundary is empty) when no edge is misoriented. Each walk is
// closed as soon as it returns to its start (two loops touching at a vertex
// stay two) and capped by a fan around its length-weighted centroid; the fan
// runs against the boundary's direction, so the capped surface is closed and
// oriented as the mesh.
BoundaryLoops boundary_loops(const std::vector<glm::vec3>& P, const std::vector<BoundaryEdge>& chain,
                             const Components& comps, const std::vector<glm::dvec3>& ref) {
    BoundaryLoops out{std::vector<std::size_t>(comps.count, 0), std::vector<double>(comps.count, 0.0),
                      std::vector<double>(comps.count, 0.0)};
    const std::size_t ne = chain.size();
    std::vector<std::uint8_t> done(ne, 0);
    std::unordered_map<std::uint32_t, std::size_t> next_out; // vertex -> first possibly unused outgoing edge
    auto outgoing = [&](std::uint32_t v) -> std::size_t {
        auto it = next_out.find(v);
        std::size_t i =
            it != next_out.end()
                ? it->second
                : std::size_t(std::lower_bound(chain.begin(), chain.end(), BoundaryEdge{v, 0}) - chain.begin());
        while (i < ne && chain[i].from == v && done[i]) ++i;
        next_out[v] = i;
        return i < ne && chain[i].from == v ? i : ne;
    };
    std::vector<std::size_t> walk;
    for (std::size_t e0 = 0; e0 < ne; ++e0) {
        if (done[e0]) continue;
        walk.clear();
        const std::uint32_t start = chain[e0].from;
        std::size_t cur = e0;
        for (;;) {
            done[cur] = 1;
            walk.push_back(cur);
            const std::uint32_t x = chain[cur].to;
            if (x == start) break;
            cur = outgoing(x);
            if (cur == ne) {
                out.open_chain = true;
                break;
            }
        }
        const std::uint32_t c = comps.of(start);
        const glm::dvec3 r = ref[c];
        double length = 0;
        glm::dvec3 mid(0.0), mean(0.0);
        for (auto i : walk) {
            const glm::dvec3 a = glm::dvec3(P[chain[i].from]) - r, b = glm::dvec3(P[chain[i].to]) - r;
            const double l = glm::length(b - a);
            length += l;
            mid += l * 0.5 * (a + b);
            mean += a;
        }
        const glm::dvec3 apex = length > 0 ? mid / length : mean / double(walk.size());
        double cap = 0;
        for (auto i : walk) {
            const glm::dvec3 a = glm::dvec3(P[chain[i].from]) - r, b = glm::dvec3(P[chain[i].to]) - r;
            cap += glm::dot(b, glm::cross(a, apex)) / 6.0;
        }
        ++out.loops[c];
        out.length[c] += length;
        out.cap[c] += cap;
    }
    return out;
}

// Step 6: the components' measures, in the order of their numbering.
std::vector<SurfacePart> component_parts(const ComponentBounds& bounds, const EdgeCounts& edges,
                                         const std::vector<Accum>& acc, const BoundaryLoops& loops) {
    std::vector<SurfacePart> parts(acc.size());
    for (std::size_t c = 0; c < acc.size(); ++c) {
        SurfacePart& s = parts[c];
        s.triangles = acc[c].triangles;
        s.area_mm2 = acc[c].area;
        s.boundary_edges = edges.comp_boundary[c];
        s.boundary_loops = loops.loops[c];
        s.boundary_length_mm = loops.length[c];
        s.closed = edges.comp_boundary[c] == 0;
        s.volume_kind = edges.comp_misoriented[c] ? VolumeKind::Undefined
                        : s.closed                ? VolumeKind::Enclosed
                                                  : VolumeKind::LowerBound;
        s.volume_ml = s.volume_kind == VolumeKind::Undefined ? kNaN : (acc[c].volume + loops.cap[c]) / 1000.0;
        s.bounds_min = bounds.lo[c];
        s.bounds_max = bounds.hi[c];
    }
    return parts;
}

// The parts into m.components by volume, descending (undefined volumes
// last, ties by area, then by numbering); returns each part's rank there.
std::vector<std::uint32_t> order_components(const std::vector<SurfacePart>& parts, SurfaceMeasures& m) {
    const auto ncomp = std::uint32_t(parts.size());
    std::vector<std::uint32_t> perm(ncomp);
    std::iota(perm.begin(), perm.end(), 0u);
    std::stable_sort(perm.begin(), perm.end(), [&](std::uint32_t a, std::uint32_t b) {
        const SurfacePart &x = parts[a], &y = parts[b];
        const bool ux = x.volume_kind == VolumeKind::Undefined, uy = y.volume_kind == VolumeKind::Undefined;
        if (ux != uy) return uy;
        if (!ux && x.volume_ml != y.volume_ml) return x.volume_ml > y.volume_ml;
        return x.area_mm2 > y.area_mm2;
    });
    std::vector<std::uint32_t> rank(ncomp);
    m.components.reserve(ncomp);
    for (std::uint32_t i = 0; i < ncomp; ++i) {
        rank[perm[i]] = i;
        m.components.push_back(parts[perm[i]]);
    }
    return rank;
}

// The whole surface's measures from its components' (in their order).
void add_totals(SurfaceMeasures& m) {
    m.volume_kind = VolumeKind::Enclosed;
    m.bounds_min = m.bounds_max = glm::dvec3(0.0);
    bool first_part = true;
    for (const auto& s : m.components) {
        m.area_mm2 += s.area_mm2;
        m.boundary_loops += s.boundary_loops;
        m.boundary_length_mm += s.boundary_length_mm;
        if (s.volume_kind == VolumeKind::Undefined)
            m.volume_kind = VolumeKind::Undefined;
        else if (s.volume_kind == VolumeKind::LowerBound && m.volume_kind == VolumeKind::Enclosed)
            m.volume_kind = VolumeKind::LowerBound;
        if (s.volume_kind != VolumeKind::Undefined) m.volume_ml += s.volume_ml;
        m.bounds_min = first_part ? s.bounds_min : glm::min(m.bounds_min, s.bounds_min);
        m.bounds_max = first_part ? s.bounds_max : glm::max(m.bounds_max, s.bounds_max);
        first_part = false;
    }
    if (m.volume_kind == VolumeKind::Undefined) m.volume_ml = kNaN;
    m.closed = m.boundary_edges == 0;
}

void add_topology_warnings(SurfaceMeasures& m, bool open_chain) {
    if (m.misoriented_edges)
        m.warnings.push_back(std::to_string(m.misoriented_edges) +
                             " edges are used twice in the same direction: the triangles are not consistently "
                             "oriented, so the volume is undefined");
    if (m.non_manifold_edges)
        m.warnings.push_back(std::to_string(m.non_manifold_edges) +
                             " edges are shared by three or more triangles (non-manifold)");
    if (m.boundary_edges && m.volume_kind == VolumeKind::LowerBound)
        m.warnings.push_back("the surface is open (" + std::to_string(m.boundary_edges) + " boundary edges in " +
                             std::to_string(m.boundary_loops) +
                             " loops): its volume is a lower bound, with the loops capped");
    if (open_chain) m.warnings.push_back("some boundary edges do not form closed loops");
    if (m.degenerate_triangles)
        m.warnings.push_back(std::to_string(m.degenerate_triangles) +
                             " degenerate triangles (zero area) count as zero");
}

Analysis analyse(const Mesh& mesh) {
    check_input(mesh);
    const auto& P = mesh.positions;
    const std::size_t nv = P.size();
    const Welded welded = weld_triangles(mesh);
    const std::vector<Triangle>& W = welded.triangles(mesh);
    const Components comps = connected_components(W, nv);
    const ComponentBounds bounds = component_bounds(P, welded.canon, comps);
    const EdgeCounts edges = classify_edges(W, comps, nv);
    const std::vector<Accum> acc = component_sums(P, W, comps, bounds.ref);
    const BoundaryLoops loops = boundary_loops(P, edges.chain, comps, bounds.ref);

    Analysis out;
    SurfaceMeasures& m = out.m;
    m.triangles = mesh.triangles.size();
    m.vertices = bounds.vertices;
    m.boundary_edges = edges.boundary;
    m.non_manifold_edges = edges.non_manifold;
    m.misoriented_edges = edges.misoriented;
    for (const auto& a : acc) m.degenerate_triangles += a.degenerate;
    const std::vector<std::uint32_t> rank = order_components(component_parts(bounds, edges, acc, loops), m);
    add_totals(m);
    out.vertex_component.assign(nv, kNone);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 16), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v)
            if (comps.used[welded.canon[v]]) out.vertex_component[v] = rank[comps.of(welded.canon[v])];
    });
    add_topology_warnings(m, loops.open_chain);
    return out;
}

// ---- coarse comparison -------------------------------------------------------------

// Which fine component has vertices near each grid sample: every fine
// vertex is entered at the sample it rounds to (the smallest component index
// wins where several meet), in an open-addressing table.
class FineCells {
public:
    FineCells(const Volume& v, const Mesh& fine, const std::vector<std::uint32_t>& fine_comp)
        : inv_(glm::inverse(v.index_to_lps)), dims_(v.dims) {
        std::size_t cap = 16;
        while (cap < 2 * fine.positions.size()) cap *= 2;
        keys_.assign(cap, kEmptyKey);
        comps_.assign(cap, kNone);
        for (std::size_t i = 0; i < fine.positions.size(); ++i) {
            if (fine_comp[i] == kNone) continue;
            const std::uint64_t k = key(sample_of(fine.positions[i]));
            std::size_t s = mix64(k) & (cap - 1);
            while (keys_[s] != kEmptyKey && keys_[s] != k) s = (s + 1) & (cap - 1);
            keys_[s] = k;
            comps_[s] = std::min(comps_[s], fine_comp[i]);
        }
    }

    // The fine component at the sample nearest to p, else the smallest at the
    // 26 neighbours, else within two samples; kNone if none.
    std::uint32_t nearest(const glm::vec3& p) const {
        const auto s = sample_of(p);
        std::uint32_t found = kNone;
        for (int radius = 0; radius <= 2 && found == kNone; ++radius)
            for (int dz = -radius; dz <= radius; ++dz)
                for (int dy = -radius; dy <= radius; ++dy)
                    for (int dx = -radius; dx <= radius; ++dx) {
                        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != radius) continue;
                        found = std::min(found, at(key({s[0] + dx, s[1] + dy, s[2] + dz})));
                    }
        return found;
    }

private:
    static constexpr std::uint64_t kEmptyKey = ~std::uint64_t(0);
    std::array<std::int64_t, 3> sample_of(const glm::vec3& p) const {
        const glm::dvec3 x(inv_ * glm::dvec4(glm::dvec3(p), 1.0));
        std::array<std::int64_t, 3> s{};
        for (int a = 0; a < 3; ++a) s[a] = std::llround(std::clamp(x[a], -4.0, double(dims_[a]) + 3.0));
        return s;
    }
    std::uint64_t key(const std::array<std::int64_t, 3>& s) const {
        return std::uint64_t((s[0] + 8) + (dims_[0] + 16) * ((s[1] + 8) + (dims_[1] + 16) * (s[2] + 8)));
    }
    std::uint32_t at(std::uint64_t k) const {
        for (std::size_t s = mix64(k) & (keys_.size() - 1);; s = (s + 1) & (keys_.size() - 1)) {
            if (keys_[s] == k) return comps_[s];
            if (keys_[s] == kEmptyKey) return kNone;
        }
    }
    glm::dmat4 inv_;
    std::array<std::int64_t, 3> dims_;
    std::vector<std::uint64_t> keys_;
    std::vector<std::uint32_t> comps_;
};

// Matches each coarse component to the fine component that most of its
// vertices are nearest to (FineCells); kNone when none is near.
std::vector<std::uint32_t> match_components(const FineCells& cells, const Mesh& coarse,
                                            const std::vector<std::uint32_t>& coarse_comp, std::size_t coarse_count) {
    // Voters: the first 64 vertices of every component, then every 16th
    // (a majority needs no more, and each lookup is a few cache misses).
    std::vector<std::uint32_t> voters, seen(coarse_count, 0);
    for (std::size_t i = 0; i < coarse.positions.size(); ++i) {
        const std::uint32_t c = coarse_comp[i];
        if (c != kNone && (seen[c]++ < 64 || i % 16 == 0)) voters.push_back(std::uint32_t(i));
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> votes(voters.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voters.size(), 1024), [&](const auto& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n)
            votes[n] = {coarse_comp[voters[n]], cells.nearest(coarse.positions[voters[n]])};
    });
    tbb::parallel_sort(votes.begin(), votes.end());
    std::vector<std::uint32_t> match(coarse_count, kNone);
    std::vector<std::size_t> best(coarse_count, 0);
    for (std::size_t i = 0; i < votes.size();) {
        std::size_t j = i;
        while (j < votes.size() && votes[j] == votes[i]) ++j;
        const auto [c, f] = votes[i];
        if (c != kNone && f != kNone && j - i > best[c]) {
            best[c] = j - i;
            match[c] = f;
        }
        i = j;
    }
    return match;
}

// Samples per axis of the coarse grids: about half (ceil((n - 1) / 2) + 1), plus `extra`.
std::array<std::int64_t, 3> coarse_dims(const std::array<std::int64_t, 3>& dims, int extra) {
    std::array<std::int64_t, 3> m{};
    for (int a = 0; a < 3; ++a) m[a] = dims[a] >= 3 ? std::min(dims[a], dims[a] / 2 + 1 + extra) : dims[a];
    return m;
}

// SurfaceMeasures::edge_fraction_spread: 4 x the mean |t - 1/2| over the
// vertices that lie inside a grid edge (not on a sample).
double edge_fraction_spread(const Volume& v, const Mesh& mesh, const std::vector<std::uint32_t>& used) {
    const glm::dmat4 inv = glm::inverse(v.index_to_lps);
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        if (used[i] == kNone) continue;
        const glm::dvec3 x(inv * glm::dvec4(glm::dvec3(mesh.positions[i]), 1.0));
        double d = 0; // distance of the edge coordinate from the nearest sample, 0..1/2
        for (int a = 0; a < 3; ++a) d = std::max(d, std::abs(x[a] - std::round(x[a])));
        if (d < 1e-3) continue; // on a sample (a tie)
        sum += 0.5 - d;
        ++count;
    }
    return count ? 4.0 * sum / double(count) : kNaN;
}

// ---- uncertainty -------------------------------------------------------------------

// The Grid Convergence Index's running maxima over the coarse grids (SurfaceMeasures).
struct Uncertainty {
    explicit Uncertainty(std::size_t parts) : part_area(parts, 0.0), part_volume(parts, 0.0) {}
    double area = 0, volume = 0;                // the whole surface
    std::vector<double> part_area, part_volume; // per fine component
    int grids = 0;                              // coarse grids compared
};

// Coarse grid g (coarse_dims(dims, g)): its isosurface measured against
// `fine` (the measures of the fine surface), whole and per component (the
// coarse components matched through `cells`). The first grid compared also
// gives the Richardson extrapolation. A grid less than 1.3x coarser is skipped.
void compare_coarse_grid(const Volume& v, double iso, int g, const MeasureOptions& opt, const FineCells& cells,
                         SurfaceMeasures& fine, Uncertainty& u) {
    glm::dvec3 ratio;
    const auto dims = coarse_dims(v.dims, g);
    Volume coarse = resample_extent(v, dims, &ratio);
    // The representative cell size ratio (Celik et al. 2008): cube root of the cell volume ratio.
    const double r = std::cbrt(ratio.x * ratio.y * ratio.z);
    if (r < 1.3) return;
    ++u.grids;
    ExtractOptions eo;
    eo.normals = false;
    eo.threads = opt.threads;
    Mesh cm = extract_isosurface(coarse, iso, eo);
    if (opt.coarse_post) cm = opt.coarse_post(cm);
    const Analysis co = analyse(cm);
    const double k = 3.0 / (r * r - 1.0); // Fs / (r^p - 1), Fs = 3, p = 2
    const std::size_t nf = fine.components.size();
    const auto match = match_components(cells, cm, co.vertex_component, co.m.components.size());
    std::vector<double> area_c(nf, 0.0), vol_c(nf, 0.0);
    for (std::size_t c = 0; c < match.size(); ++c) {
        if (match[c] == kNone) continue;
        area_c[match[c]] += co.m.components[c].area_mm2;
        if (co.m.components[c].volume_kind != VolumeKind::Undefined) vol_c[match[c]] += co.m.components[c].volume_ml;
    }
    // The coarse surface's measures: all of it, or (the surface is some
    // components of the isosurface) those matched to them.
    double coarse_area = co.m.area_mm2, coarse_volume = co.m.volume_ml;
    if (opt.components_only) {
        coarse_area = coarse_volume = 0;
        for (std::size_t f = 0; f < nf; ++f) {
            coarse_area += area_c[f];
            coarse_volume += vol_c[f];
        }
    }
    if (u.grids == 1) { // Richardson, p = 2, from the first coarse grid
        fine.area_extrapolated_mm2 = fine.area_mm2 + (fine.area_mm2 - coarse_area) / (r * r - 1.0);
        if (fine.volume_kind != VolumeKind::Undefined)
            fine.volume_extrapolated_ml = fine.volume_ml + (fine.volume_ml - coarse_volume) / (r * r - 1.0);
    }
    u.area = std::max(u.area, k * std::abs(fine.area_mm2 - coarse_area));
    u.volume = std::max(u.volume, k * std::abs(fine.volume_ml - coarse_volume));
    for (std::size_t f = 0; f < nf; ++f) {
        const auto& s = fine.components[f];
        u.part_area[f] = std::max(u.part_area[f], k * std::abs(s.area_mm2 - area_c[f]));
        u.part_volume[f] = std::max(u.part_volume[f], k * std::abs(s.volume_ml - vol_c[f]));
    }
}

// SurfaceMeasures::edge_fraction_spread of `surface`, and its warning when the grid does not resolve the edge.
void add_edge_fraction_spread(const Volume& v, const Mesh& surface, const std::vector<std::uint32_t>& vertex_component,
                              SurfaceMeasures& result) {
    result.edge_fraction_spread = edge_fraction_spread(v, surface, vertex_component);
    if (result.edge_fraction_spread < kResolvedEdgeSpread) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.2f", result.edge_fraction_spread);
        result.warnings.push_back(
            std::string("the edge is sharper than the voxel grid resolves (edge fraction spread ") + buf +
            ", below 0.8): the area is biased upward by more than its uncertainty (balls: "
            "1.6 % at a blur of 0.25 voxel, 11 % for a binary mask)");
    }
}

} // namespace

// ---- public ------------------------------------------------------------------------

// The formulas are the markups' (io/markups.hpp: what a Slicer line or
// angle shows); here with the checks a measurement needs.
double distance_mm(const glm::dvec3& a, const glm::dvec3& b) {
    if (!finite(a) || !finite(b)) throw Error("distance", "a point is not finite");
    return line_length_mm(a, b);
}

double angle_deg(const glm::dvec3& a, const glm::dvec3& vertex, const glm::dvec3& c) {
    if (!finite(a) || !finite(vertex) || !finite(c)) throw Error("angle", "a point is not finite");
    const glm::dvec3 u = a - vertex, w = c - vertex;
    if (glm::length(u) < 1e-9 || glm::length(w) < 1e-9)
        throw Error("angle",
                    "an end point coincides with the vertex (the middle point), so the angle has no direction");
    return *angle_degrees(a, vertex, c);
}

std::optional<VolumeSample> sample_volume(const Volume& v, const glm::dvec3& lps) {
    if (!finite(lps)) throw Error("volume sample", "the point is not finite");
    if (v.voxel_count() <= 0) return std::nullopt;
    VolumeSample s;
    s.index = glm::dvec3(glm::inverse(v.index_to_lps) * glm::dvec4(lps, 1.0));
    constexpr double kEps = 1e-9; // voxels: rounding of the inverse affine at the grid's outer faces
    std::array<std::int64_t, 3> i0{}, i1{};
    std::array<double, 3> f{};
    for (int a = 0; a < 3; ++a) {
        const double n = double(v.dims[a]);
        // Within rounding of a voxel centre: exactly there (its value, not an interpolation off by 1e-12).
        const double x = std::abs(s.index[a] - std::round(s.index[a])) < kEps ? std::round(s.index[a]) : s.index[a];
        if (!(x >= -0.5 - kEps && x <= n - 0.5 + kEps)) return std::nullopt;
        const double c = std::clamp(x, 0.0, n - 1.0);
        if (std::abs(c - x) > kEps) s.clamped = true;
        s.voxel[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(x + 0.5)), 0, v.dims[a] - 1);
        i0[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(c)), 0, std::max<std::int64_t>(v.dims[a] - 2, 0));
        i1[a] = std::min(i0[a] + 1, v.dims[a] - 1);
        f[a] = i1[a] == i0[a] ? 0.0 : std::clamp(c - double(i0[a]), 0.0, 1.0);
    }
    auto at = [&](int di, int dj, int dk) {
        return v.value(di ? i1[0] : i0[0], dj ? i1[1] : i0[1], dk ? i1[2] : i0[2]);
    };
    // Only the samples with weight are read, so a NaN neighbour with zero weight does not spread.
    auto row = [&](int dj, int dk) { return f[0] == 0 ? at(0, dj, dk) : lerp(at(0, dj, dk), at(1, dj, dk), f[0]); };
    auto plane = [&](int dk) { return f[1] == 0 ? row(0, dk) : lerp(row(0, dk), row(1, dk), f[1]); };
    s.value = f[2] == 0 ? plane(0) : lerp(plane(0), plane(1), f[2]);
    s.voxel_lps = v.index_to_world(glm::dvec3(double(s.voxel[0]), double(s.voxel[1]), double(s.voxel[2])));
    s.voxel_value = v.value(s.voxel[0], s.voxel[1], s.voxel[2]);
    return s;
}

const char* volume_kind_name(VolumeKind k) {
    switch (k) {
    case VolumeKind::Enclosed: return "enclosed";
    case VolumeKind::LowerBound: return "lower bound";
    case VolumeKind::Undefined: return "undefined";
    }
    return "undefined";
}

SurfaceMeasures measure_surface(const Mesh& m, const MeasureOptions& opt) {
    SurfaceMeasures r;
    in_arena(opt.threads, [&] { r = analyse(m).m; });
    return r;
}

std::vector<std::uint32_t> triangle_components(const Mesh& m, const MeasureOptions& opt) {
    std::vector<std::uint32_t> out(m.triangles.size(), kNone);
    in_arena(opt.threads, [&] {
        const Analysis a = analyse(m);
        // Collapsed triangles join their vertices' components too (connected_components).
        for (std::size_t t = 0; t < m.triangles.size(); ++t) out[t] = a.vertex_component[m.triangles[t][0]];
    });
    return out;
}

Mesh component_mesh(const Mesh& m, const std::vector<std::uint32_t>& triangle_component, std::uint32_t component) {
    Mesh out;
    std::vector<std::uint32_t> remap(m.positions.size(), kNone);
    for (std::size_t t = 0; t < m.triangles.size() && t < triangle_component.size(); ++t) {
        if (triangle_component[t] != component) continue;
        std::array<std::uint32_t, 3> tri{};
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t v = m.triangles[t][std::size_t(k)];
            if (remap[v] == kNone) {
                remap[v] = std::uint32_t(out.positions.size());
                out.positions.push_back(m.positions[v]);
                if (!m.normals.empty()) out.normals.push_back(m.normals[v]);
                if (!m.colors.empty()) out.colors.push_back(m.colors[v]);
            }
            tri[std::size_t(k)] = remap[v];
        }
        out.triangles.push_back(tri);
    }
    return out;
}

Volume resample_extent(const Volume& v, std::array<std::int64_t, 3> m, glm::dvec3* ratio_out) {
    glm::dvec3 ratio(1.0);
    glm::dmat4 affine = v.index_to_lps;
    for (int a = 0; a < 3; ++a) {
        const std::int64_t n = v.dims[a];
        if (m[a] < 1 || (n > 1 && m[a] < 2) || (n <= 1 && m[a] != n))
            throw Error("resample", "cannot resample " + std::to_string(n) + " samples to " + std::to_string(m[a]));
        if (n > 1) ratio[a] = double(n - 1) / double(m[a] - 1);
        affine[a] *= ratio[a];
    }
    if (ratio_out) *ratio_out = ratio;
    Volume c = Volume::dense(m, VoxelType::F32, affine);
    c.meta.source = v.meta.source;
    if (v.voxel_count() == 0) return c;
    // NaN and Inf as extraction substitutes them (ChunkIndex): NaN below every
    // finite sample, Inf clamped to the finite range.
    const bool floating = v.is_sparse() || v.type == VoxelType::F32 || v.type == VoxelType::F64;
    const ValueRange r = floating ? v.value_range() : ValueRange{};
    const bool any_finite = r.min <= r.max && (r.nan_count + r.inf_count) < std::size_t(v.voxel_count());
    const double lowest = any_finite ? r.min : 0.0, highest = any_finite ? r.max : 0.0;
    const double nan_value = lowest - std::max(1.0, std::abs(lowest) * 1e-3);
    auto clean = [&](double s) { return std::isnan(s) ? nan_value : std::isinf(s) ? (s > 0 ? highest : lowest) : s; };
    // Per axis and coarse index: the two fine samples and the weight of the upper one.
    struct Axis {
        std::vector<std::int64_t> i0, i1;
        std::vector<double> f;
    };
    std::array<Axis, 3> ax;
    for (int a = 0; a < 3; ++a)
        for (std::int64_t I = 0; I < m[a]; ++I) {
            const double x = std::min(double(I) * ratio[a], double(v.dims[a] - 1));
            const std::int64_t i0 =
                std::min<std::int64_t>(std::int64_t(std::floor(x)), std::max<std::int64_t>(v.dims[a] - 2, 0));
            const std::int64_t i1 = std::min(i0 + 1, v.dims[a] - 1);
            ax[a].i0.push_back(i0);
            ax[a].i1.push_back(i1);
            ax[a].f.push_back(i1 == i0 ? 0.0 : std::clamp(x - double(i0), 0.0, 1.0));
        }
    auto out = c.as<float>();
    // make_get() gives a sampler (i, j, k) -> double per slice (a sparse
    // grid's accessor caches its path through the tree). Samples without
    // weight are not read (a ratio of exactly 2 reads one sample per point).
    auto resample = [&](auto&& make_get) {
        tbb::parallel_for(std::int64_t(0), m[2], [&](std::int64_t K) {
            auto get = make_get();
            const std::int64_t k0 = ax[2].i0[K], k1 = ax[2].i1[K];
            const double fz = ax[2].f[K];
            for (std::int64_t J = 0; J < m[1]; ++J) {
                const std::int64_t j0 = ax[1].i0[J], j1 = ax[1].i1[J];
                const double fy = ax[1].f[J];
                float* dst = out.data() + c.linear_index(0, J, K);
                for (std::int64_t I = 0; I < m[0]; ++I) {
                    const std::int64_t i0 = ax[0].i0[I], i1 = ax[0].i1[I];
                    const double fx = ax[0].f[I];
                    auto row = [&](std::int64_t j, std::int64_t k) {
                        return fx == 0 ? get(i0, j, k) : lerp(get(i0, j, k), get(i1, j, k), fx);
                    };
                    auto plane = [&](std::int64_t k) {
                        return fy == 0 ? row(j0, k) : lerp(row(j0, k), row(j1, k), fy);
                    };
                    dst[I] = float(fz == 0 ? plane(k0) : lerp(plane(k0), plane(k1), fz));
                }
            }
        });
    };
    if (v.is_sparse()) {
        const auto& g = *v.sparse_grid();
        resample([&] {
            return [&g, &clean, acc = g.grid->getConstAccessor()](std::int64_t i, std::int64_t j,
                                                                  std::int64_t k) mutable {
                return clean(double(
                    acc.getValue(openvdb::Coord(int(i) + g.offset.x(), int(j) + g.offset.y(), int(k) + g.offset.z()))));
            };
        });
    } else {
        dispatch_voxel_type(v.type, [&](auto tag) {
            using T = decltype(tag);
            const T* src = v.as<T>().data();
            const std::int64_t sx = v.dims[0], sxy = v.dims[0] * v.dims[1];
            resample([&] {
                return [&](std::int64_t i, std::int64_t j, std::int64_t k) {
                    const double x = double(src[i + sx * j + sxy * k]);
                    if constexpr (std::is_floating_point_v<T>)
                        return clean(x);
                    else
                        return x;
                };
            });
        });
    }
    return c;
}

Volume coarsen_2x(const Volume& v, glm::dvec3* ratio) { return resample_extent(v, coarse_dims(v.dims, 0), ratio); }

SurfaceMeasures measure_isosurface(const Volume& v, double iso, const Mesh& surface, const MeasureOptions& opt) {
    SurfaceMeasures result;
    in_arena(opt.threads, [&] {
        Analysis fine = analyse(surface);
        result = std::move(fine.m);
        Uncertainty u(result.components.size());
        const FineCells cells(v, surface, fine.vertex_component);
        for (int g = 0; g < std::max(opt.coarse_grids, 1); ++g) compare_coarse_grid(v, iso, g, opt, cells, result, u);
        add_edge_fraction_spread(v, surface, fine.vertex_component, result);
        if (u.grids == 0) {
            result.warnings.push_back("no uncertainty: the volume is too thin to coarsen (fewer than 3 samples along "
                                      "two axes)");
            return;
        }
        result.area_uncertainty_mm2 = u.area;
        result.volume_uncertainty_ml = result.volume_kind == VolumeKind::Undefined ? kNaN : u.volume;
        for (std::size_t f = 0; f < u.part_area.size(); ++f) {
            auto& s = result.components[f];
            s.area_uncertainty_mm2 = u.part_area[f];
            s.volume_uncertainty_ml = s.volume_kind == VolumeKind::Undefined ? kNaN : u.part_volume[f];
        }
    });
    return result;
}

SurfaceMeasures measure_isosurface(const Volume& v, double iso, const MeasureOptions& opt) {
    ExtractOptions eo;
    eo.normals = false;
    eo.threads = opt.threads;
    return measure_isosurface(v, iso, extract_isosurface(v, iso, eo), opt);
}

} // namespace iso
