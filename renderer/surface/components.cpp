// Piece summaries and their merge (components.hpp, docs/cluster.md).
#include "renderer/surface/components.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <numeric>
#include <tuple>
#include <unordered_map>

#include <glm/glm.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "io/error.hpp"
#include "renderer/surface/component_sums.hpp"
#include "renderer/surface/edges.hpp"
#include "renderer/surface/union_find.hpp"

namespace iso {

namespace {

constexpr std::uint32_t kNoComponent = 0xFFFFFFFFu;

std::array<int, 3> chunk_counts(const std::array<std::int64_t, 3>& dims, int C) {
    std::array<int, 3> n{};
    for (int a = 0; a < 3; ++a) n[a] = int((std::max<std::int64_t>(dims[a] - 1, 0) + C - 1) / C);
    return n;
}

void add_triangle(const glm::dvec3& o, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                  ComponentStats& c) {
    const TriangleTerms t = triangle_terms(o, p0, p1, p2);
    c.area += t.area;
    c.volume += t.det / 6.0;
    c.moment += t.moment;
}

// The signed volume of `c` (about `from`) about `to`.
double volume_about(const ComponentStats& c, const glm::dvec3& from, const glm::dvec3& to) {
    return volume_moved(c.volume, c.moment, from, to);
}

bool better(const ComponentStats& a, const ComponentStats& b) {
    return a.triangles != b.triangles ? a.triangles > b.triangles : a.area > b.area;
}

} // namespace

bool key_leaves_range(std::uint64_t key, ChunkRange range, const std::array<std::int64_t, 3>& dims, int C) {
    const int axis = int(key & 3u);
    std::uint64_t lin = key >> 2;
    const std::array<std::int64_t, 3> p{std::int64_t(lin % std::uint64_t(dims[0])),
                                        std::int64_t((lin / std::uint64_t(dims[0])) % std::uint64_t(dims[1])),
                                        std::int64_t(lin / (std::uint64_t(dims[0]) * std::uint64_t(dims[1])))};
    const auto counts = chunk_counts(dims, C);
    // The chunk coordinates along each axis that hold the vertex: one or two.
    std::array<std::array<int, 2>, 3> cand{};
    std::array<int, 3> ncand{};
    for (int a = 0; a < 3; ++a) {
        const int c = int(p[a] / C);
        if (a == axis) { // the edge [p, p + 1] lies in cell p, of one chunk
            cand[a][ncand[a]++] = std::min(c, counts[a] - 1);
            continue;
        }
        if (c < counts[a]) cand[a][ncand[a]++] = c;
        if (p[a] % C == 0 && c > 0) cand[a][ncand[a]++] = c - 1;
    }
    for (int i = 0; i < ncand[0]; ++i)
        for (int j = 0; j < ncand[1]; ++j)
            for (int k = 0; k < ncand[2]; ++k) {
                const std::size_t id =
                    std::size_t(cand[0][i]) +
                    std::size_t(counts[0]) * (std::size_t(cand[1][j]) + std::size_t(counts[1]) * cand[2][k]);
                if (id < range.first || id >= range.last) return true;
            }
    return false;
}

SurfacePiece weld_piece(const ChunkedSurface& s, ChunkRange range, const std::array<std::int64_t, 3>& dims, int C) {
    SurfacePiece out;
    Mesh& m = out.mesh;
    range.last = std::min(range.last, s.chunks.size());
    bool normals = false;
    for (std::size_t id = range.first; id < range.last; ++id)
        if (!s.chunks[id].positions.empty()) {
            normals = !s.chunks[id].normals.empty();
            break;
        }
    // Border vertices: the first chunk (lowest id) to hold a key keeps it, as weld() does.
    std::unordered_map<std::uint64_t, std::uint32_t> seen;
    std::vector<std::uint32_t> remap;
    for (std::size_t id = range.first; id < range.last; ++id) {
        const ChunkMesh& c = s.chunks[id];
        remap.assign(c.positions.size(), kNoComponent);
        for (const auto& [key, local] : c.border) {
            const auto [it, fresh] = seen.try_emplace(key, std::uint32_t(m.positions.size()));
            remap[local] = it->second;
            if (fresh) {
                m.positions.push_back(c.positions[local]);
                if (normals) m.normals.push_back(c.normals[local]);
                if (key_leaves_range(key, range, dims, C)) out.seam.emplace_back(key, it->second);
            }
        }
        for (std::size_t v = 0; v < c.positions.size(); ++v) {
            if (remap[v] != kNoComponent) continue;
            remap[v] = std::uint32_t(m.positions.size());
            m.positions.push_back(c.positions[v]);
            if (normals) m.normals.push_back(c.normals[v]);
        }
        for (const auto& t : c.triangles) m.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
    }
    std::sort(out.seam.begin(), out.seam.end());
    // Zero-gradient normals: the area-weighted normal of the piece's triangles
    // (a seam vertex's neighbours in other pieces are not seen: its normal can
    // differ from the whole mesh's there; positions never do).
    if (normals) {
        std::vector<glm::dvec3> acc;
        for (std::size_t v = 0; v < m.normals.size(); ++v)
            if (m.normals[v] == glm::vec3(0.0f)) {
                if (acc.empty()) {
                    acc.assign(m.positions.size(), glm::dvec3(0.0));
                    for (const auto& t : m.triangles) {
                        const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
                        const glm::dvec3 fn = glm::cross(b - a, c - a);
                        for (auto i : t) acc[i] += fn;
                    }
                }
                const double len = glm::length(acc[v]);
                if (len > 0.0) m.normals[v] = glm::vec3(acc[v] / len);
            }
    }
    return out;
}

std::pair<glm::dvec3, glm::dvec3> piece_bounds(const Mesh& m) {
    using Bounds = std::pair<glm::dvec3, glm::dvec3>;
    const Bounds none{glm::dvec3(std::numeric_limits<double>::infinity()),
                      glm::dvec3(-std::numeric_limits<double>::infinity())};
    // Minima and maxima are exact in any order: the same bounds from any split.
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, m.positions.size(), 1 << 16), none,
        [&](const tbb::blocked_range<std::size_t>& r, Bounds b) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                b.first = glm::min(b.first, glm::dvec3(m.positions[i]));
                b.second = glm::max(b.second, glm::dvec3(m.positions[i]));
            }
            return b;
        },
        [](const Bounds& x, const Bounds& y) {
            return Bounds{glm::min(x.first, y.first), glm::max(x.second, y.second)};
        });
}

glm::dvec3 volume_origin(const glm::dvec3& lo, const glm::dvec3& hi) {
    if (!(lo.x <= hi.x)) return glm::dvec3(0.0); // no vertex anywhere
    return 0.5 * (lo + hi);
}

namespace {

// The piece's edges used by one triangle (PieceSummary::boundary_edges and
// seam_boundary): the edges bucketed by their lower vertex (edges.hpp) and
// each bucket's runs read in parallel; every triangle's edges count, also
// those of a triangle with a repeated vertex.
void summarize_boundary(const SurfacePiece& p, PieceSummary& s) {
    constexpr std::uint64_t kOffSeam = ~std::uint64_t(0);
    const std::size_t nv = p.mesh.positions.size();
    std::vector<std::uint64_t> key(nv, kOffSeam);
    for (const auto& [k, v] : p.seam) key[v] = k;
    EdgeBuckets edges = bucket_edges(p.mesh.triangles, nv, false);
    struct Local {
        std::size_t boundary = 0;
        std::vector<std::pair<std::uint64_t, std::uint64_t>> seam;
    };
    tbb::enumerable_thread_specific<Local> locals;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const auto& r) {
        Local& L = locals.local();
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
            std::uint32_t* b = edges.entries.data() + edges.offset[l];
            std::uint32_t* const e = edges.entries.data() + edges.offset[l + 1];
            std::sort(b, e);
            while (b != e) {
                const std::uint32_t upper = *b >> 1;
                std::uint32_t* run = b + 1;
                while (run != e && (*run >> 1) == upper) ++run;
                if (run - b == 1) {
                    if (key[l] == kOffSeam || key[upper] == kOffSeam)
                        ++L.boundary;
                    else
                        L.seam.push_back(std::minmax(key[l], key[upper]));
                }
                b = run;
            }
        }
    });
    for (auto& L : locals) {
        s.boundary_edges += L.boundary;
        s.seam_boundary.insert(s.seam_boundary.end(), L.seam.begin(), L.seam.end());
    }
    std::sort(s.seam_boundary.begin(), s.seam_boundary.end());
}

// Per triangle, its component: the triangles' vertices united in parallel
// (roots are smallest members: the same sets in any order), the roots
// numbered in the order of their first triangle. Returns the count;
// `vertex_component` gets each root's number (kNoComponent elsewhere).
std::uint32_t triangle_components(const Mesh& m, ConcurrentUnionFind& sets, std::vector<std::uint32_t>& tri_comp,
                                  std::vector<std::uint32_t>& vertex_component) {
    const auto& T = m.triangles;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, T.size(), 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            sets.unite(T[t][0], T[t][1]);
            sets.unite(T[t][0], T[t][2]);
        }
    });
    tri_comp.resize(T.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, T.size(), 1 << 14), [&](const auto& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) tri_comp[t] = sets.find(T[t][0]);
    });
    vertex_component.assign(m.positions.size(), kNoComponent);
    std::uint32_t n = 0;
    for (auto& c : tri_comp) {
        auto& number = vertex_component[c];
        if (number == kNoComponent) number = n++;
        c = number;
    }
    return n;
}

// Each component's triangles, area, volume and moment about `origin`,
// summed in a way that does not depend on the thread count (sum_by_component).
std::vector<ComponentStats> component_sums(const Mesh& m, const std::vector<std::uint32_t>& tri_comp,
                                           std::uint32_t ncomp, const glm::dvec3& origin) {
    const auto add = [&](ComponentStats& c, std::size_t t) {
        const auto& tri = m.triangles[t];
        ++c.triangles;
        add_triangle(origin, m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]], c);
    };
    const auto merge = [](ComponentStats& c, const ComponentStats& part) {
        c.triangles += part.triangles;
        c.area += part.area;
        c.volume += part.volume;
        c.moment += part.moment;
    };
    return sum_by_component<ComponentStats>(
        tri_comp.size(), ncomp, [&](std::size_t t) { return tri_comp[t]; }, add, merge);
}

} // namespace

PieceSummary summarize_piece(const SurfacePiece& p, const glm::dvec3& origin) {
    const Mesh& m = p.mesh;
    if (!EdgeBuckets::fits(m.positions.size(), m.triangles.size()))
        throw Error("piece summary", "a piece of 2^31 vertices or 2^30 triangles or more: lower the memory budget");
    PieceSummary s;
    s.triangles = m.triangles.size();
    s.vertices = m.positions.size();
    ConcurrentUnionFind sets(m.positions.size());
    std::vector<std::uint32_t> tri_comp, comp;
    const std::uint32_t ncomp = triangle_components(m, sets, tri_comp, comp);
    s.components = component_sums(m, tri_comp, ncomp, origin);
    tri_comp = {};
    s.origin = origin;
    std::tie(s.bounds_min, s.bounds_max) = piece_bounds(m);
    for (const auto& c : s.components) {
        s.area += c.area;
        s.volume += c.volume;
    }
    s.seam.reserve(p.seam.size());
    for (const auto& [key, v] : p.seam) s.seam.emplace_back(key, comp[sets.find(v)]);
    summarize_boundary(p, s);
    return s;
}

SurfaceSummary merge_summaries(std::span<const PieceSummary> pieces) {
    SurfaceSummary out;
    std::vector<std::size_t> base(pieces.size() + 1, 0);
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& p : pieces) {
        lo = glm::min(lo, p.bounds_min);
        hi = glm::max(hi, p.bounds_max);
    }
    const glm::dvec3 origin = volume_origin(lo, hi);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        base[i + 1] = base[i] + pieces[i].components.size();
        out.triangles += pieces[i].triangles;
        out.vertices += pieces[i].vertices;
        out.area += pieces[i].area;
        for (const auto& c : pieces[i].components) out.volume += volume_about(c, pieces[i].origin, origin);
    }
    if (base.back() >= kNoComponent) throw Error("merge_summaries", "more than 4 billion components");
    // Every seam entry as (key, global component); runs of one key are one vertex.
    struct Entry {
        std::uint64_t key;
        std::uint32_t comp;
        bool operator<(const Entry& o) const { return key != o.key ? key < o.key : comp < o.comp; }
    };
    std::vector<Entry> seam;
    for (std::size_t i = 0; i < pieces.size(); ++i)
        for (const auto& [key, c] : pieces[i].seam)
            seam.push_back({key, c == kNoComponent ? kNoComponent : std::uint32_t(base[i] + c)});
    std::sort(seam.begin(), seam.end());
    UnionFind sets(base.back());
    for (std::size_t i = 1; i < seam.size(); ++i) {
        if (seam[i].key != seam[i - 1].key) continue;
        --out.vertices; // held by one more piece
        if (seam[i].comp != kNoComponent && seam[i - 1].comp != kNoComponent)
            sets.unite(seam[i].comp, seam[i - 1].comp);
    }
    std::vector<ComponentStats> merged(base.back());
    for (std::size_t i = 0; i < pieces.size(); ++i)
        for (std::size_t c = 0; c < pieces[i].components.size(); ++c) {
            auto& r = merged[sets.find(std::uint32_t(base[i] + c))];
            const auto& pc = pieces[i].components[c];
            r.triangles += pc.triangles;
            r.area += pc.area;
            r.volume += volume_about(pc, pieces[i].origin, origin);
        }
    // A seam edge that one piece alone uses once is on the surface's boundary.
    std::vector<std::pair<std::uint64_t, std::uint64_t>> seam_edges;
    for (const auto& p : pieces) {
        out.boundary_edges += p.boundary_edges;
        seam_edges.insert(seam_edges.end(), p.seam_boundary.begin(), p.seam_boundary.end());
    }
    std::sort(seam_edges.begin(), seam_edges.end());
    for (std::size_t i = 0; i < seam_edges.size();) {
        std::size_t j = i + 1;
        while (j < seam_edges.size() && seam_edges[j] == seam_edges[i]) ++j;
        out.boundary_edges += j - i == 1;
        i = j;
    }
    for (std::uint32_t n = 0; n < merged.size(); ++n) {
        if (sets.find(n) != n) continue;
        ++out.components;
        if (out.components == 1 || better(merged[n], out.largest)) out.largest = merged[n];
    }
    return out;
}

SurfaceSummary summarize_mesh(const Mesh& m) {
    SurfacePiece p;
    p.mesh = m;
    const auto [lo, hi] = piece_bounds(m);
    const PieceSummary s = summarize_piece(p, volume_origin(lo, hi));
    return merge_summaries(std::span<const PieceSummary>(&s, 1));
}

void SummarizingSink::begin(std::size_t surfaces, std::size_t pieces, bool normals) {
    pieces_.assign(surfaces, {});
    next_.begin(surfaces, pieces, normals);
}

void SummarizingSink::piece(MeshPiece&& p) {
    if (p.surface >= pieces_.size()) throw Error("SummarizingSink", "piece of an unknown surface");
    SurfacePiece sp;
    sp.mesh = std::move(p.mesh);
    sp.seam = p.lower;
    sp.seam.insert(sp.seam.end(), p.upper.begin(), p.upper.end());
    const auto t = std::chrono::steady_clock::now();
    std::sort(sp.seam.begin(), sp.seam.end());
    sp.seam.erase(std::unique(sp.seam.begin(), sp.seam.end()), sp.seam.end());
    pieces_[p.surface].push_back(summarize_piece(sp, origin_));
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    p.mesh = std::move(sp.mesh);
    next_.piece(std::move(p));
}

std::size_t SummarizingSink::memory_bytes() const {
    std::size_t n = 0;
    for (const auto& s : pieces_)
        for (const auto& p : s)
            n += p.components.capacity() * sizeof(ComponentStats) + p.seam.capacity() * sizeof(p.seam[0]) +
                 p.seam_boundary.capacity() * sizeof(p.seam_boundary[0]);
    return n + next_.memory_bytes();
}

std::vector<SurfaceSummary> SummarizingSink::summaries() const {
    std::vector<SurfaceSummary> out;
    for (const auto& s : pieces_) out.push_back(merge_summaries(s));
    return out;
}

// ---- serialization: plain little-endian-as-the-host bytes (ranks of one job
// run the same binary on the same architecture) -----------------------------

namespace {
template <class T> void put(std::string& out, const T& x) { out.append(reinterpret_cast<const char*>(&x), sizeof(T)); }
template <class T> T get(std::string_view& in) {
    if (in.size() < sizeof(T)) throw Error("deserialize_piece_summary", "truncated summary");
    T x;
    std::memcpy(static_cast<void*>(&x), in.data(), sizeof(T)); // T: trivially copyable numbers and glm vectors
    in.remove_prefix(sizeof(T));
    return x;
}
} // namespace

std::string serialize(const PieceSummary& s) {
    std::string out;
    out.reserve(136 + s.components.size() * 48 + s.seam.size() * 12);
    put<std::uint64_t>(out, s.triangles);
    put<std::uint64_t>(out, s.vertices);
    put(out, s.area);
    put(out, s.volume);
    for (const auto& v : {s.origin, s.bounds_min, s.bounds_max}) put(out, v);
    put<std::uint64_t>(out, s.components.size());
    for (const auto& c : s.components) {
        put<std::uint64_t>(out, c.triangles);
        put(out, c.area);
        put(out, c.volume);
        put(out, c.moment);
    }
    put<std::uint64_t>(out, s.seam.size());
    for (const auto& [k, c] : s.seam) {
        put(out, k);
        put(out, c);
    }
    put<std::uint64_t>(out, s.boundary_edges);
    put<std::uint64_t>(out, s.seam_boundary.size());
    for (const auto& [a, b] : s.seam_boundary) {
        put(out, a);
        put(out, b);
    }
    return out;
}

PieceSummary deserialize_piece_summary(std::string_view in) {
    PieceSummary s;
    s.triangles = get<std::uint64_t>(in);
    s.vertices = get<std::uint64_t>(in);
    s.area = get<double>(in);
    s.volume = get<double>(in);
    s.origin = get<glm::dvec3>(in);
    s.bounds_min = get<glm::dvec3>(in);
    s.bounds_max = get<glm::dvec3>(in);
    const auto nc = get<std::uint64_t>(in);
    if (nc > in.size() / 48) throw Error("deserialize_piece_summary", "truncated summary");
    s.components.resize(nc);
    for (auto& c : s.components) {
        c.triangles = get<std::uint64_t>(in);
        c.area = get<double>(in);
        c.volume = get<double>(in);
        c.moment = get<glm::dvec3>(in);
    }
    const auto ns = get<std::uint64_t>(in);
    if (ns > in.size() / 12) throw Error("deserialize_piece_summary", "truncated summary");
    s.seam.resize(ns);
    for (auto& [k, c] : s.seam) {
        k = get<std::uint64_t>(in);
        c = get<std::uint32_t>(in);
    }
    s.boundary_edges = get<std::uint64_t>(in);
    const auto nb = get<std::uint64_t>(in);
    if (nb > in.size() / 16) throw Error("deserialize_piece_summary", "truncated summary");
    s.seam_boundary.resize(nb);
    for (auto& [a, b] : s.seam_boundary) {
        a = get<std::uint64_t>(in);
        b = get<std::uint64_t>(in);
    }
    return s;
}

std::string serialize(std::span<const PieceSummary> all) {
    std::string out;
    put<std::uint64_t>(out, all.size());
    for (const auto& s : all) {
        const std::string one = serialize(s);
        put<std::uint64_t>(out, one.size());
        out += one;
    }
    return out;
}

std::vector<PieceSummary> deserialize_piece_summaries(std::string_view in) {
    const auto n = get<std::uint64_t>(in);
    if (n > in.size() / 8) throw Error("deserialize_piece_summaries", "truncated summaries");
    std::vector<PieceSummary> out;
    out.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) {
        const auto len = get<std::uint64_t>(in);
        if (len > in.size()) throw Error("deserialize_piece_summaries", "truncated summaries");
        out.push_back(deserialize_piece_summary(in.substr(0, len)));
        in.remove_prefix(len);
    }
    return out;
}

} // namespace iso
