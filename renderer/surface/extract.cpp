#include "renderer/surface/arena.hpp"
#include "renderer/surface/extract.hpp"

#include <algorithm>
#include <chrono>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <set>

#include <glm/glm.hpp>
#include <sys/mman.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "io/sparse.hpp"
#include "renderer/surface/mc_tables.hpp"

namespace iso {

namespace {

constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

// Large output arrays are backed by transparent huge pages where the kernel
// offers them on request ("madvise" mode): one fault per 2 MiB instead of one
// per 4 KiB, which on virtual machines is most of the cost of filling fresh
// memory. Call after reserve() and before the memory is first written.
template <class V> void advise_huge_pages(V& v) {
    constexpr std::uintptr_t huge = std::uintptr_t(2) << 20;
    const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
    const auto end = begin + v.capacity() * sizeof(typename V::value_type);
    const std::uintptr_t lo = (begin + huge - 1) & ~(huge - 1), hi = end & ~(huge - 1);
    if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
}

struct ChunkGeom {
    std::array<std::int64_t, 3> p0, p1; // first and last sample (inclusive) of the chunk
};

ChunkGeom chunk_geom(const std::array<std::int64_t, 3>& dims, int C, const std::array<int, 3>& c) {
    ChunkGeom g;
    for (int a = 0; a < 3; ++a) {
        g.p0[a] = std::int64_t(c[a]) * C;
        g.p1[a] = std::min<std::int64_t>(g.p0[a] + C, dims[a] - 1);
    }
    return g;
}

// Case index from the "column" codes of two neighbouring x positions. A
// column code packs the inside bits of (y,z), (y+1,z), (y,z+1), (y+1,z+1).
struct CaseFromColumns {
    std::array<std::array<std::uint8_t, 16>, 16> t{};
    CaseFromColumns() {
        for (int a = 0; a < 16; ++a)
            for (int b = 0; b < 16; ++b) {
                // corners: 0 (0,0,0) a0; 1 (1,0,0) b0; 2 (1,1,0) b1; 3 (0,1,0) a1;
                //          4 (0,0,1) a2; 5 (1,0,1) b2; 6 (1,1,1) b3; 7 (0,1,1) a3
                int c = ((a >> 0) & 1) | (((b >> 0) & 1) << 1) | (((b >> 1) & 1) << 2) | (((a >> 1) & 1) << 3) |
                        (((a >> 2) & 1) << 4) | (((b >> 2) & 1) << 5) | (((b >> 3) & 1) << 6) | (((a >> 3) & 1) << 7);
                t[a][b] = std::uint8_t(c);
            }
    }
};
const CaseFromColumns kCases;

// Per-thread scratch.
struct Scratch {
    std::vector<std::byte> block;       // samples of the chunk plus a one-sample halo
    std::vector<std::uint8_t> inside;   // per chunk sample
    std::vector<std::uint8_t> cols;     // column codes of one cell row
    std::vector<std::uint32_t> slots;   // per chunk sample x 3: vertex on the +x/+y/+z edge
    std::vector<std::uint32_t> touched; // slots written for the current chunk (reset afterwards)
    ChunkMesh staging;                  // grows once per thread; chunks get exact-size copies
    std::size_t bytes() const {
        return block.capacity() + inside.capacity() + cols.capacity() +
               (slots.capacity() + touched.capacity()) * sizeof(std::uint32_t) +
               staging.positions.capacity() * 2 * sizeof(glm::vec3) +
               staging.triangles.capacity() * sizeof(staging.triangles[0]) +
               staging.border.capacity() * sizeof(staging.border[0]);
    }
};

// The geometry every kernel needs.
struct Frame {
    std::array<std::int64_t, 3> dims;
    int C;
    glm::dmat4 m;        // index -> LPS
    glm::dmat3 normal_m; // inverse transpose of the linear part
    bool flip;           // affine mirrors space: reverse the winding
    bool normals;
    bool keep_keys;
};

// A block of samples: the chunk's samples plus a halo, with substitutions for
// NaN and Inf already made.
template <class T> struct Block {
    const T* data;
    std::array<std::int64_t, 3> lo, n; // first sample and extent of the block
    T at(std::int64_t x, std::int64_t y, std::int64_t z) const {
        return data[(x - lo[0]) + n[0] * ((y - lo[1]) + n[1] * (z - lo[2]))];
    }
};

template <class T> T substitute(T v, const ChunkIndex& idx) {
    if constexpr (std::is_floating_point_v<T>) {
        if (std::isnan(v)) return T(idx.nan_value());
        if (std::isinf(v)) return v > 0 ? T(idx.highest()) : T(idx.lowest());
    }
    return v;
}

// Copies the samples of [lo, lo+n) (whole-volume indices) into scratch
// (dense or sparse source; the window's slab starts at k = w.k0).
template <class T>
Block<T> load_block(const VolumeWindow& w, const ChunkIndex& idx, const std::array<std::int64_t, 3>& lo,
                    const std::array<std::int64_t, 3>& n, Scratch& s) {
    const Volume& v = *w.slab;
    const std::size_t count = std::size_t(n[0] * n[1] * n[2]);
    s.block.resize(count * sizeof(T));
    T* out = reinterpret_cast<T*>(s.block.data());
    if (v.is_sparse()) {
        const auto& g = *v.sparse_grid();
        auto acc = g.grid->getConstAccessor();
        std::size_t o = 0;
        for (std::int64_t z = 0; z < n[2]; ++z)
            for (std::int64_t y = 0; y < n[1]; ++y)
                for (std::int64_t x = 0; x < n[0]; ++x) {
                    openvdb::Coord c(int(lo[0] + x) + g.offset.x(), int(lo[1] + y) + g.offset.y(),
                                     int(lo[2] + z - w.k0) + g.offset.z());
                    out[o++] = substitute(T(acc.getValue(c)), idx);
                }
    } else {
        const T* src = v.as<T>().data();
        std::size_t o = 0;
        for (std::int64_t z = 0; z < n[2]; ++z)
            for (std::int64_t y = 0; y < n[1]; ++y) {
                const T* row = src + v.linear_index(lo[0], lo[1] + y, lo[2] + z - w.k0);
                if constexpr (std::is_floating_point_v<T>) {
                    for (std::int64_t x = 0; x < n[0]; ++x) out[o++] = substitute(row[x], idx);
                } else {
                    std::memcpy(out + o, row, std::size_t(n[0]) * sizeof(T));
                    o += std::size_t(n[0]);
                }
            }
    }
    return Block<T>{out, lo, n};
}

// Gradient in index space at sample (x,y,z): central differences inside the
// volume, one-sided at its border (as vtkFlyingEdges3D).
template <class T, class Cls>
glm::dvec3 gradient(const Block<T>& b, const Frame& f, const Cls& cls, std::int64_t x, std::int64_t y, std::int64_t z) {
    glm::dvec3 g;
    const std::int64_t p[3] = {x, y, z};
    for (int a = 0; a < 3; ++a) {
        std::int64_t lo[3] = {x, y, z}, hi[3] = {x, y, z};
        double scale = 0.5;
        if (p[a] == 0) {
            hi[a] += 1;
            scale = 1.0;
        } else if (p[a] >= f.dims[a] - 1) {
            lo[a] -= 1;
            scale = 1.0;
        } else {
            lo[a] -= 1;
            hi[a] += 1;
        }
        if (f.dims[a] < 2) {
            g[a] = 0;
            continue;
        }
        g[a] = scale * (cls.value(double(b.at(hi[0], hi[1], hi[2]))) - cls.value(double(b.at(lo[0], lo[1], lo[2]))));
    }
    return g;
}

bool on_border(const Frame& f, std::int64_t p, int a) { return p % f.C == 0 && p > 0 && p < f.dims[a] - 1; }

// What makes a sample inside, where a cut edge's vertex goes, and the field
// whose gradient gives the normals.
struct IsoClassifier {
    double iso;
    bool inside(double s) const { return s >= iso; }
    double t(double s0, double s1) const { return (iso - s0) / (s1 - s0); }
    double value(double s) const { return s; }
};
// Discrete (label map) surfaces: the boundary of {sample == label}, vertices
// at edge midpoints as vtkDiscreteFlyingEdges3D places them, normals from the
// gradient of the label's indicator function.
struct LabelClassifier {
    double label;
    bool inside(double s) const { return s == label; }
    double t(double, double) const { return 0.5; }
    double value(double s) const { return s == label ? 1.0 : 0.0; }
};

// Marching cubes over one chunk for one surface.
template <class T, class Cls>
void run_chunk(const Block<T>& b, const ChunkGeom& g, const Frame& f, const Cls& cls, Scratch& s, ChunkMesh& result) {
    const auto& tab = mc::tables();
    const std::int64_t nx = g.p1[0] - g.p0[0] + 1, ny = g.p1[1] - g.p0[1] + 1, nz = g.p1[2] - g.p0[2] + 1;
    const std::size_t npts = std::size_t(nx * ny * nz);
    ChunkMesh& out = s.staging;
    out.positions.clear();
    out.normals.clear();
    out.triangles.clear();
    out.border.clear();
    out.keys.clear();

    s.inside.resize(npts);
    for (std::int64_t z = 0; z < nz; ++z)
        for (std::int64_t y = 0; y < ny; ++y) {
            std::uint8_t* in = s.inside.data() + nx * (y + ny * z);
            const T* row =
                b.data + (g.p0[0] - b.lo[0]) + b.n[0] * ((g.p0[1] + y - b.lo[1]) + b.n[1] * (g.p0[2] + z - b.lo[2]));
            for (std::int64_t x = 0; x < nx; ++x) in[x] = cls.inside(double(row[x])) ? 1 : 0;
        }
    // Slots stay kNoSlot between chunks: only the ones written are reset.
    if (s.slots.size() < npts * 3) s.slots.assign(npts * 3, kNoSlot);
    s.touched.clear();
    s.cols.resize(std::size_t(nx));

    auto lin = [&](std::int64_t x, std::int64_t y, std::int64_t z) { return std::size_t(x + nx * (y + ny * z)); };

    // One vertex per cut edge (also where the edge ends on a tied
    // sample), at t clamped to [kEdgeMargin, 1 - kEdgeMargin] (extract.hpp).
    auto make_vertex = [&](std::int64_t lx, std::int64_t ly, std::int64_t lz, int axis) -> std::uint32_t {
        const std::size_t sp = lin(lx, ly, lz);
        std::uint32_t& slot = s.slots[sp * 3 + std::size_t(axis)];
        if (slot != kNoSlot) return slot;
        s.touched.push_back(std::uint32_t(sp * 3 + std::size_t(axis)));
        const std::int64_t gx = g.p0[0] + lx, gy = g.p0[1] + ly, gz = g.p0[2] + lz;
        const double s0 = double(b.at(gx, gy, gz));
        const double s1 = double(b.at(gx + (axis == 0), gy + (axis == 1), gz + (axis == 2)));
        // The edge is cut, so s0 != s1 and t is finite; it is 0 or 1 at a tie.
        const double t = std::clamp(cls.t(s0, s1), kEdgeMargin, 1.0 - kEdgeMargin);
        const std::uint32_t id = std::uint32_t(out.positions.size());
        glm::dvec3 ip(gx, gy, gz), n(0.0);
        ip[axis] += t;
        const std::uint64_t key = 4 * std::uint64_t(gx + f.dims[0] * (gy + f.dims[1] * gz)) + std::uint64_t(axis);
        const std::int64_t gp[3] = {gx, gy, gz};
        bool border = false;
        for (int a = 0; a < 3; ++a)
            if (a != axis && on_border(f, gp[a], a)) border = true;
        if (f.normals) {
            const glm::dvec3 g0 = gradient(b, f, cls, gx, gy, gz);
            const glm::dvec3 g1 = gradient(b, f, cls, gx + (axis == 0), gy + (axis == 1), gz + (axis == 2));
            n = g0 + t * (g1 - g0);
        }
        const glm::dvec3 w = glm::dvec3(f.m * glm::dvec4(ip, 1.0));
        out.positions.emplace_back(w);
        if (f.normals) {
            glm::dvec3 wn = -(f.normal_m * n);
            const double len = glm::length(wn);
            out.normals.emplace_back(len > 0.0 ? glm::vec3(wn / len) : glm::vec3(0.0f));
        }
        if (border) out.border.emplace_back(key, id);
        if (f.keep_keys) out.keys.push_back(key);
        return slot = id;
    };

    for (std::int64_t z = 0; z + 1 < nz; ++z)
        for (std::int64_t y = 0; y + 1 < ny; ++y) {
            const std::uint8_t* r00 = s.inside.data() + lin(0, y, z);
            const std::uint8_t* r10 = s.inside.data() + lin(0, y + 1, z);
            const std::uint8_t* r01 = s.inside.data() + lin(0, y, z + 1);
            const std::uint8_t* r11 = s.inside.data() + lin(0, y + 1, z + 1);
            std::uint8_t any = 0, all = 15;
            for (std::int64_t x = 0; x < nx; ++x) {
                const std::uint8_t c = std::uint8_t(r00[x] | (r10[x] << 1) | (r01[x] << 2) | (r11[x] << 3));
                s.cols[std::size_t(x)] = c;
                any |= c;
                all &= c;
            }
            if (any == 0 || all == 15) continue; // the whole cell row is outside, or inside
            for (std::int64_t x = 0; x + 1 < nx; ++x) {
                const std::uint8_t cs = kCases.t[s.cols[std::size_t(x)]][s.cols[std::size_t(x + 1)]];
                const int ntri = tab.tri_count[cs];
                if (ntri == 0) continue;
                const auto& te = tab.tri_edges[cs];
                for (int t = 0; t < ntri; ++t) {
                    std::uint32_t v[3];
                    for (int k = 0; k < 3; ++k) {
                        const auto& e = tab.edges[std::size_t(te[std::size_t(3 * t + k)])];
                        v[k] = make_vertex(x + e.dx, y + e.dy, z + e.dz, e.axis);
                    }
                    if (f.flip) std::swap(v[1], v[2]);
                    out.triangles.push_back({v[0], v[1], v[2]});
                }
            }
        }
    for (auto t : s.touched) s.slots[t] = kNoSlot;
    result.positions.assign(out.positions.begin(), out.positions.end());
    result.normals.assign(out.normals.begin(), out.normals.end());
    result.triangles.assign(out.triangles.begin(), out.triangles.end());
    result.border.assign(out.border.begin(), out.border.end());
    result.keys.assign(out.keys.begin(), out.keys.end());
}

Frame make_frame(const VolumeWindow& w, int C, bool normals, bool keep_keys = false) {
    Frame f;
    f.dims = w.dims;
    f.C = C;
    f.m = w.index_to_lps;
    const glm::dmat3 lin(w.index_to_lps);
    f.normal_m = glm::transpose(glm::inverse(lin));
    f.flip = glm::determinant(lin) < 0.0;
    f.normals = normals;
    f.keep_keys = keep_keys;
    return f;
}

} // namespace

// ---- ChunkIndex ------------------------------------------------------------

ChunkIndex::ChunkIndex(const Volume& v, int chunk_size, int threads) : chunk_size_(chunk_size), dims_(v.dims) {
    if (chunk_size < 1) throw Error("ChunkIndex", "chunk size must be at least 1");
    for (int a = 0; a < 3; ++a) {
        const std::int64_t cells = std::max<std::int64_t>(v.dims[a] - 1, 0);
        counts_[a] = int((cells + chunk_size - 1) / chunk_size);
    }
    const std::size_t n = std::size_t(counts_[0]) * counts_[1] * counts_[2];
    min_.assign(n, 0.0);
    max_.assign(n, 0.0);
    // Only floating-point samples can be NaN or Inf; skip the scan otherwise.
    const bool floating = v.is_sparse() || v.type == VoxelType::F32 || v.type == VoxelType::F64;
    const auto r = floating ? v.value_range() : ValueRange{};
    const bool any_finite =
        r.min <= r.max && (r.nan_count + r.inf_count) < std::size_t(std::max<std::int64_t>(v.voxel_count(), 1));
    lowest_ = any_finite ? r.min : 0.0;
    highest_ = any_finite ? r.max : 0.0;
    nan_value_ = lowest_ - std::max(1.0, std::abs(lowest_) * 1e-3);
    if (n == 0) return;
    in_arena(threads, [&] { tbb::parallel_for(std::size_t(0), n, [&](std::size_t id) { summarize(v, id); }); });
}

void ChunkIndex::summarize(const Volume& v, std::size_t id) {
    const auto g = chunk_geom(dims_, chunk_size_, coords(id));
    double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
    if (v.is_sparse()) {
        const auto& sg = *v.sparse_grid();
        auto acc = sg.grid->getConstAccessor();
        for (std::int64_t z = g.p0[2]; z <= g.p1[2]; ++z)
            for (std::int64_t y = g.p0[1]; y <= g.p1[1]; ++y)
                for (std::int64_t x = g.p0[0]; x <= g.p1[0]; ++x) {
                    const double s =
                        substitute(double(acc.getValue(openvdb::Coord(int(x) + sg.offset.x(), int(y) + sg.offset.y(),
                                                                      int(z) + sg.offset.z()))),
                                   *this);
                    lo = std::min(lo, s);
                    hi = std::max(hi, s);
                }
    } else {
        dispatch_voxel_type(v.type, [&](auto tag) {
            using T = decltype(tag);
            const T* src = v.as<T>().data();
            T tlo = std::numeric_limits<T>::max(), thi = std::numeric_limits<T>::lowest();
            for (std::int64_t z = g.p0[2]; z <= g.p1[2]; ++z)
                for (std::int64_t y = g.p0[1]; y <= g.p1[1]; ++y) {
                    const T* row = src + v.linear_index(g.p0[0], y, z);
                    const std::int64_t n = g.p1[0] - g.p0[0] + 1;
                    if constexpr (std::is_floating_point_v<T>) {
                        for (std::int64_t x = 0; x < n; ++x) {
                            const T s = substitute(row[x], *this);
                            tlo = std::min(tlo, s);
                            thi = std::max(thi, s);
                        }
                    } else {
                        for (std::int64_t x = 0; x < n; ++x) {
                            tlo = std::min(tlo, row[x]);
                            thi = std::max(thi, row[x]);
                        }
                    }
                }
            lo = double(tlo);
            hi = double(thi);
            return 0;
        });
    }
    min_[id] = lo;
    max_[id] = hi;
}

std::vector<std::size_t> ChunkIndex::chunks_touching(const IndexBox& box) const {
    std::vector<std::size_t> ids;
    if (box.empty() || min_.empty()) return ids;
    // A changed sample alters the samples of the chunks holding it and, through
    // the gradient stencil, vertices on edges that end one sample away.
    std::array<int, 3> c0, c1;
    for (int a = 0; a < 3; ++a) {
        const std::int64_t lo = std::max<std::int64_t>(box.lo[a] - 1, 0);
        const std::int64_t hi = std::min<std::int64_t>(box.hi[a] + 1, dims_[a] - 1);
        if (hi < lo) return ids;
        // Chunk c holds samples [c*C, c*C + C]: sample p is in chunks (p-1)/C .. p/C.
        c0[a] = int(std::max<std::int64_t>(lo - 1, 0) / chunk_size_);
        c1[a] = int(std::min<std::int64_t>(hi / chunk_size_, counts_[a] - 1));
    }
    for (int z = c0[2]; z <= c1[2]; ++z)
        for (int y = c0[1]; y <= c1[1]; ++y)
            for (int x = c0[0]; x <= c1[0]; ++x)
                ids.push_back(std::size_t(x) +
                              std::size_t(counts_[0]) * (std::size_t(y) + std::size_t(counts_[1]) * z));
    return ids;
}

void ChunkIndex::refresh(const Volume& v, std::span<const std::size_t> ids) {
    // The value range may have grown; NaN substitution keeps the old bounds,
    // which is enough for classification (only "below every iso" matters).
    for (auto id : ids) summarize(v, id);
}

ChunkIndex::ChunkIndex(std::array<std::int64_t, 3> dims, int chunk_size, std::vector<double> min,
                       std::vector<double> max, double lowest, double highest)
    : chunk_size_(chunk_size), dims_(dims), min_(std::move(min)), max_(std::move(max)), lowest_(lowest),
      highest_(highest) {
    if (chunk_size < 1) throw Error("ChunkIndex", "chunk size must be at least 1");
    for (int a = 0; a < 3; ++a) {
        if (dims[a] < 1) throw Error("ChunkIndex", "dimensions must be positive");
        counts_[a] = int((std::max<std::int64_t>(dims[a] - 1, 0) + chunk_size - 1) / chunk_size);
    }
    const std::size_t n = std::size_t(counts_[0]) * counts_[1] * counts_[2];
    if (min_.size() != n || max_.size() != n)
        throw Error("ChunkIndex", "expected " + std::to_string(n) + " chunk minima and maxima, got " +
                                      std::to_string(min_.size()) + " and " + std::to_string(max_.size()));
    // As the in-memory constructor: the NaN substitute lies below every finite sample.
    nan_value_ = lowest_ - std::max(1.0, std::abs(lowest_) * 1e-3);
}

// ---- ChunkSummaries (slab by slab) ---------------------------------------------

ChunkSummaries::ChunkSummaries(std::array<std::int64_t, 3> d, int C, VoxelType t) : dims(d), chunk_size(C), type(t) {
    if (C < 1) throw Error("ChunkIndex", "chunk size must be at least 1");
    for (int a = 0; a < 3; ++a) counts[a] = int((std::max<std::int64_t>(d[a] - 1, 0) + C - 1) / C);
    const std::size_t n = std::size_t(counts[0]) * counts[1] * counts[2];
    finite_min.assign(n, std::numeric_limits<double>::max());
    finite_max.assign(n, std::numeric_limits<double>::lowest());
    flags.assign(n, 0);
    lowest = std::numeric_limits<double>::max();
    highest = std::numeric_limits<double>::lowest();
}

void ChunkSummaries::add(const VolumeWindow& w) {
    if (w.dims != dims) throw Error("ChunkIndex", "slab of another volume");
    const Volume& v = *w.slab;
    const int C = chunk_size;
    // Chunk c along an axis holds samples [c*C, c*C + C]: sample p is in chunks (p-1)/C .. p/C (clamped).
    auto chunk_range = [&](std::int64_t p, int a) {
        const int hi = int(std::min<std::int64_t>(p / C, counts[a] - 1));
        const int lo = int(std::max<std::int64_t>(p - 1, 0) / C);
        return std::array<int, 2>{std::min(lo, hi), hi};
    };
    const std::int64_t nx = dims[0];
    // In parallel over chunk rows (cy): the task of chunk row cy reads the
    // rows of samples it holds (cy*C .. cy*C + C; the shared rows are read by
    // both neighbours) and writes only its own entries, so no two tasks write
    // the same chunk; min and max do not depend on the order.
    std::mutex range_mutex;
    if (counts[0] == 0 || counts[1] == 0 || counts[2] == 0) {
        // No cells (a dimension of one sample): only the finite range.
        for (std::int64_t k = 0; k < v.dims[2]; ++k)
            for (std::int64_t j = 0; j < v.dims[1]; ++j)
                for (std::int64_t i = 0; i < v.dims[0]; ++i) {
                    const double s = v.value(i, j, k);
                    if (std::isfinite(s)) {
                        lowest = std::min(lowest, s);
                        highest = std::max(highest, s);
                    }
                }
        return;
    }
    tbb::parallel_for(0, counts[1], [&](int cy) {
        std::vector<double> rmin(std::size_t(std::max(counts[0], 1))), rmax(rmin.size());
        std::vector<std::uint8_t> rflag(rmin.size());
        double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
        auto row_values = [&](auto get) {
            // Min/max per chunk column along x of one row.
            std::fill(rmin.begin(), rmin.end(), std::numeric_limits<double>::max());
            std::fill(rmax.begin(), rmax.end(), std::numeric_limits<double>::lowest());
            std::fill(rflag.begin(), rflag.end(), 0);
            for (std::int64_t x = 0; x < nx; ++x) {
                const double s = get(x);
                const auto cr = chunk_range(x, 0);
                std::uint8_t fl = 0;
                if (std::isnan(s))
                    fl = kNaN;
                else if (std::isinf(s))
                    fl = s > 0 ? kPosInf : kNegInf;
                else {
                    lo = std::min(lo, s);
                    hi = std::max(hi, s);
                }
                for (int c = cr[0]; c <= cr[1]; ++c) {
                    if (fl)
                        rflag[std::size_t(c)] |= fl;
                    else {
                        rmin[std::size_t(c)] = std::min(rmin[std::size_t(c)], s);
                        rmax[std::size_t(c)] = std::max(rmax[std::size_t(c)], s);
                    }
                }
            }
        };
        const std::int64_t y0 = std::int64_t(cy) * C, y1 = std::min<std::int64_t>(y0 + C, dims[1] - 1);
        for (std::int64_t lz = 0; lz < v.dims[2]; ++lz) {
            const std::int64_t z = w.k0 + lz;
            const auto zr = chunk_range(z, 2);
            // Every row y0..y1 is in chunk row cy (chunk_range(y, 1) holds cy).
            for (std::int64_t y = y0; y <= y1; ++y) {
                if (v.is_sparse()) {
                    row_values([&](std::int64_t x) { return v.value(x, y, lz); });
                } else {
                    dispatch_voxel_type(v.type, [&](auto tag) {
                        using T = decltype(tag);
                        const T* row = v.as<T>().data() + v.linear_index(0, y, lz);
                        row_values([&](std::int64_t x) { return double(row[x]); });
                        return 0;
                    });
                }
                for (int cz = zr[0]; cz <= zr[1]; ++cz) {
                    const std::size_t base =
                        std::size_t(counts[0]) * (std::size_t(cy) + std::size_t(counts[1]) * std::size_t(cz));
                    for (int cx = 0; cx < counts[0]; ++cx) {
                        finite_min[base + cx] = std::min(finite_min[base + cx], rmin[std::size_t(cx)]);
                        finite_max[base + cx] = std::max(finite_max[base + cx], rmax[std::size_t(cx)]);
                        flags[base + cx] |= rflag[std::size_t(cx)];
                    }
                }
            }
        }
        std::lock_guard<std::mutex> lock(range_mutex);
        lowest = std::min(lowest, lo);
        highest = std::max(highest, hi);
    });
}

void ChunkSummaries::merge(const ChunkSummaries& o) {
    if (o.dims != dims || o.chunk_size != chunk_size)
        throw Error("ChunkIndex", "summaries of another volume or chunk size");
    for (std::size_t i = 0; i < flags.size(); ++i) {
        finite_min[i] = std::min(finite_min[i], o.finite_min[i]);
        finite_max[i] = std::max(finite_max[i], o.finite_max[i]);
        flags[i] |= o.flags[i];
    }
    lowest = std::min(lowest, o.lowest);
    highest = std::max(highest, o.highest);
}

ChunkIndex ChunkSummaries::finish() const {
    // As ChunkIndex(const Volume&): integer data has no substitutes (range 0, 0);
    // floating-point data's finite range gives the NaN substitute and the Inf clamps.
    const bool floating = type == VoxelType::F32 || type == VoxelType::F64;
    const bool any_finite = lowest <= highest;
    const double lo = floating && any_finite ? lowest : 0.0, hi = floating && any_finite ? highest : 0.0;
    const double nan_value = lo - std::max(1.0, std::abs(lo) * 1e-3);
    std::vector<double> mn(flags.size()), mx(flags.size());
    for (std::size_t i = 0; i < flags.size(); ++i) {
        double a = finite_min[i], b = finite_max[i];
        if (flags[i] & kNaN) {
            a = std::min(a, nan_value);
            b = std::max(b, nan_value);
        }
        if (flags[i] & kNegInf) {
            a = std::min(a, lo);
            b = std::max(b, lo);
        }
        if (flags[i] & kPosInf) {
            a = std::min(a, hi);
            b = std::max(b, hi);
        }
        // The in-memory summary substitutes in the sample type: round as it does.
        dispatch_voxel_type(type, [&](auto tag) {
            using T = decltype(tag);
            if constexpr (std::is_floating_point_v<T>) {
                a = double(T(a));
                b = double(T(b));
            }
            return 0;
        });
        mn[i] = a;
        mx[i] = b;
    }
    return ChunkIndex(dims, chunk_size, std::move(mn), std::move(mx), lo, hi);
}

// ---- ChunkedSurface -----------------------------------------------------------

std::size_t ChunkedSurface::triangle_count() const {
    std::size_t n = 0;
    for (const auto& c : chunks) n += c.triangles.size();
    return n;
}

std::size_t ChunkedSurface::memory_bytes() const {
    std::size_t n = chunks.capacity() * sizeof(ChunkMesh);
    for (const auto& c : chunks)
        n += c.positions.capacity() * sizeof(glm::vec3) + c.normals.capacity() * sizeof(glm::vec3) +
             c.triangles.capacity() * sizeof(c.triangles[0]) + c.border.capacity() * sizeof(c.border[0]);
    return n;
}

// ---- Extractor -----------------------------------------------------------------

namespace {
std::size_t scratch_estimate(int C, std::size_t sample_bytes) {
    const std::size_t n = std::size_t(C + 1), h = std::size_t(C + 3);
    return h * h * h * sample_bytes + n * n * n * (1 + 4 * sizeof(std::uint32_t)) + n;
}
} // namespace

Extractor::Extractor(const Volume& volume, ExtractOptions opt) : Extractor(volume, std::move(opt), nullptr) {}

Extractor::Extractor(const VolumeWindow& w, ExtractOptions opt, std::shared_ptr<const ChunkIndex> index)
    : volume_(w.slab), window_(w), opt_(std::move(opt)) {
    if (!w.slab) throw Error("extract", "window without samples");
    if (!index || index->dims() != w.dims) throw Error("extract", "a window needs the whole volume's chunk index");
    if (w.slab->dims[0] != w.dims[0] || w.slab->dims[1] != w.dims[1] || w.k0 < 0 || w.k0 + w.slab->dims[2] > w.dims[2])
        throw Error("extract", "the window's slab does not fit the volume's dimensions");
    opt_.chunk_size = index->chunk_size();
    const std::size_t sample = w.slab->is_sparse() ? sizeof(float) : voxel_size(w.slab->type);
    int threads = effective_threads(opt_.threads);
    while (threads > 1 && std::size_t(threads) * scratch_estimate(opt_.chunk_size, sample) > opt_.memory_budget)
        --threads;
    opt_.threads = threads;
    index_ = std::move(index);
}

Extractor::Extractor(const Volume& volume, ExtractOptions opt, std::shared_ptr<const ChunkIndex> index)
    : volume_(&volume), window_(VolumeWindow::whole(volume)), opt_(std::move(opt)) {
    if (opt_.chunk_size < 2) throw Error("extract", "chunk size must be at least 2 cells");
    const std::size_t sample = volume.is_sparse() ? sizeof(float) : voxel_size(volume.type);
    // Fit the per-thread scratch into the budget: fewer threads first, then smaller chunks.
    int threads = effective_threads(opt_.threads);
    while (threads > 1 && std::size_t(threads) * scratch_estimate(opt_.chunk_size, sample) > opt_.memory_budget)
        --threads;
    while (opt_.chunk_size > 4 && scratch_estimate(opt_.chunk_size, sample) > opt_.memory_budget) opt_.chunk_size /= 2;
    opt_.threads = threads;
    if (index && index->chunk_size() == opt_.chunk_size && index->dims() == volume.dims)
        index_ = std::move(index);
    else
        index_ = std::make_shared<const ChunkIndex>(volume, opt_.chunk_size, opt_.threads);
}

namespace {

// Extracts `ids` for every surface in `out` (one per iso).
void run_chunks(const VolumeWindow& w, const ChunkIndex& idx, const ExtractOptions& opt,
                std::span<const std::size_t> ids, std::span<ChunkedSurface> out, ExtractStats* stats) {
    const Volume& v = *w.slab;
    const Frame f = make_frame(w, idx.chunk_size(), opt.normals, opt.keep_keys);
    tbb::enumerable_thread_specific<Scratch> scratch;
    std::atomic<std::size_t> done{0};
    std::atomic<bool> cancelled{false};
    std::mutex progress_mutex;
    const VoxelType type = v.is_sparse() ? VoxelType::F32 : v.type;

    in_arena(opt.threads, [&] {
        tbb::parallel_for(std::size_t(0), ids.size(), [&](std::size_t n) {
            if (cancelled.load(std::memory_order_relaxed)) return;
            const std::size_t id = ids[n];
            bool any = false;
            for (auto& s : out) any |= idx.active(id, s.iso);
            if (any) {
                auto& sc = scratch.local();
                const auto g = chunk_geom(w.dims, idx.chunk_size(), idx.coords(id));
                std::array<std::int64_t, 3> lo, cnt;
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::max<std::int64_t>(g.p0[a] - 1, 0);
                    cnt[a] = std::min<std::int64_t>(g.p1[a] + 1, w.dims[a] - 1) - lo[a] + 1;
                }
                dispatch_voxel_type(type, [&](auto tag) {
                    using T = decltype(tag);
                    const Block<T> b = load_block<T>(w, idx, lo, cnt, sc);
                    for (auto& s : out) {
                        if (idx.active(id, s.iso))
                            run_chunk(b, g, f, IsoClassifier{s.iso}, sc, s.chunks[id]);
                        else
                            s.chunks[id] = ChunkMesh{};
                    }
                    return 0;
                });
            } else {
                for (auto& s : out) s.chunks[id] = ChunkMesh{};
            }
            const std::size_t d = ++done;
            if (opt.progress && (d % 64 == 0 || d == ids.size())) {
                std::lock_guard lock(progress_mutex);
                if (!opt.progress(double(d) / double(ids.size()), "extracting isosurface")) cancelled = true;
            }
        });
    });
    if (cancelled) throw Cancelled("extract");
    if (stats) {
        std::size_t bytes = 0;
        for (const auto& s : scratch) bytes += s.bytes();
        stats->peak_scratch_bytes = std::max(stats->peak_scratch_bytes, bytes);
        stats->threads = effective_threads(opt.threads);
        stats->chunk_size = idx.chunk_size();
        stats->chunks_total = idx.chunk_count();
        for (auto id : ids)
            for (auto& s : out)
                if (idx.active(id, s.iso)) {
                    ++stats->chunks_visited;
                    break;
                }
    }
}

} // namespace

namespace {
// One empty chunked surface per iso value; throws for a value that is not finite.
std::vector<ChunkedSurface> empty_surfaces(std::span<const double> isos) {
    std::vector<ChunkedSurface> out(isos.size());
    for (std::size_t i = 0; i < isos.size(); ++i) {
        if (!std::isfinite(isos[i])) throw Error("extract", "iso value is not a finite number");
        out[i].iso = isos[i];
    }
    return out;
}
} // namespace

std::vector<ChunkedSurface> Extractor::extract(std::span<const double> isos, ExtractStats* stats) const {
    std::vector<ChunkedSurface> out = empty_surfaces(isos);
    const ChunkIndex& idx = *index_;
    if (window_.slab->dims[2] != window_.dims[2]) {
        // A window: the chunk layers it holds whole, with their halo.
        std::vector<std::size_t> ids;
        for (int layer = 0; layer < idx.counts()[2]; ++layer) {
            const auto ks = layer_samples(window_.dims, idx.chunk_size(), layer);
            if (ks[0] < window_.k0 || ks[1] > window_.k0 + window_.slab->dims[2] - 1) continue;
            for (std::size_t i = 0; i < idx.layer_size(); ++i) ids.push_back(std::size_t(layer) * idx.layer_size() + i);
        }
        return extract_chunks(isos, ids, stats);
    }
    for (auto& s : out) s.chunks.resize(idx.chunk_count());
    std::vector<std::size_t> ids;
    ids.reserve(idx.chunk_count());
    for (std::size_t id = 0; id < idx.chunk_count(); ++id)
        for (double iso : isos)
            if (idx.active(id, iso)) {
                ids.push_back(id);
                break;
            }
    run_chunks(window_, idx, opt_, ids, out, stats);
    if (stats) stats->chunks_total = idx.chunk_count();
    return out;
}

std::array<std::int64_t, 2> Extractor::layer_samples(std::array<std::int64_t, 3> dims, int chunk_size, int layer) {
    const std::int64_t p0 = std::int64_t(layer) * chunk_size;
    const std::int64_t p1 = std::min<std::int64_t>(p0 + chunk_size, dims[2] - 1);
    return {std::max<std::int64_t>(p0 - 1, 0), std::min<std::int64_t>(p1 + 1, dims[2] - 1)};
}

std::vector<ChunkedSurface> Extractor::extract_chunks(std::span<const double> isos, std::span<const std::size_t> ids,
                                                      ExtractStats* stats) const {
    std::vector<ChunkedSurface> out = empty_surfaces(isos);
    const ChunkIndex& idx = *index_;
    for (auto& s : out) s.chunks.resize(idx.chunk_count());
    const std::int64_t k_last = window_.k0 + window_.slab->dims[2] - 1;
    std::vector<std::size_t> active;
    active.reserve(ids.size());
    for (auto id : ids) {
        if (id >= idx.chunk_count())
            throw Error("extract", "chunk id " + std::to_string(id) + " is outside the volume");
        const auto ks = layer_samples(window_.dims, idx.chunk_size(), idx.coords(id)[2]);
        if (ks[0] < window_.k0 || ks[1] > k_last)
            throw Error("extract", "chunk " + std::to_string(id) + " needs slices " + std::to_string(ks[0]) + ".." +
                                       std::to_string(ks[1]) + ", the window holds " + std::to_string(window_.k0) +
                                       ".." + std::to_string(k_last));
        for (double iso : isos)
            if (idx.active(id, iso)) {
                active.push_back(id);
                break;
            }
    }
    run_chunks(window_, idx, opt_, active, out, stats);
    if (stats) stats->chunks_total = idx.chunk_count();
    return out;
}

ChunkedSurface Extractor::extract(double iso, ExtractStats* stats) const {
    const double isos[1] = {iso};
    return std::move(extract(std::span<const double>(isos, 1), stats)[0]);
}

std::vector<std::size_t> Extractor::update(const IndexBox& box, std::span<ChunkedSurface> surfaces,
                                           ExtractStats* stats) {
    if (window_.slab->dims != window_.dims) throw Error("extract", "update() needs the whole volume, not a window");
    auto ids = index_->chunks_touching(box);
    // Copy on write: extractors sharing the old index keep it as it was.
    auto fresh = std::make_shared<ChunkIndex>(*index_);
    fresh->refresh(*volume_, ids);
    index_ = std::move(fresh);
    for (auto& s : surfaces)
        if (s.chunks.size() != index_->chunk_count())
            throw Error("extract", "surface does not belong to this extractor");
    run_chunks(window_, *index_, opt_, ids, surfaces, stats);
    return ids;
}

// ---- weld ------------------------------------------------------------------------

Mesh weld(const ChunkedSurface& s, int threads, WeldMap* map) {
    Mesh m;
    const std::size_t n = s.chunks.size();
    // 1. Border vertices, sorted by key: the first of each run is kept.
    struct Entry {
        std::uint64_t key;
        std::uint32_t chunk, local;
        bool operator<(const Entry& o) const { return key != o.key ? key < o.key : chunk < o.chunk; }
    };
    std::vector<Entry> border;
    {
        std::size_t total = 0;
        for (const auto& c : s.chunks) total += c.border.size();
        border.reserve(total);
        for (std::size_t id = 0; id < n; ++id)
            for (const auto& [key, local] : s.chunks[id].border) border.push_back({key, std::uint32_t(id), local});
    }
    in_arena(threads, [&] { tbb::parallel_sort(border.begin(), border.end()); });

    // 2. Global numbering: every vertex but the border duplicates.
    constexpr std::uint32_t kAlias = 0xFFFFFFFEu;
    std::vector<std::vector<std::uint32_t>> remap(n);
    for (std::size_t id = 0; id < n; ++id) remap[id].assign(s.chunks[id].positions.size(), kNoSlot);
    for (std::size_t i = 1; i < border.size(); ++i)
        if (border[i].key == border[i - 1].key) remap[border[i].chunk][border[i].local] = kAlias;
    std::vector<std::size_t> vbase(n + 1, 0), tbase(n + 1, 0);
    for (std::size_t id = 0; id < n; ++id) {
        std::size_t kept = 0;
        for (auto r : remap[id]) kept += (r != kAlias);
        vbase[id + 1] = vbase[id] + kept;
        tbase[id + 1] = tbase[id] + s.chunks[id].triangles.size();
    }
    if (vbase[n] >= kNoSlot) throw Error("weld", "the surface has more than 4 billion vertices");
    const bool normals = [&] {
        for (const auto& c : s.chunks)
            if (!c.positions.empty()) return !c.normals.empty();
        return false;
    }();
    m.positions.reserve(vbase[n]);
    advise_huge_pages(m.positions);
    m.positions.resize(vbase[n]);
    if (normals) {
        m.normals.reserve(vbase[n]);
        advise_huge_pages(m.normals);
        m.normals.resize(vbase[n]);
    }
    m.triangles.reserve(tbase[n]);
    advise_huge_pages(m.triangles);
    m.triangles.resize(tbase[n]);

    in_arena(threads, [&] {
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t id) {
            const auto& c = s.chunks[id];
            std::uint32_t next = std::uint32_t(vbase[id]);
            for (std::size_t v = 0; v < c.positions.size(); ++v) {
                if (remap[id][v] == kAlias) continue;
                remap[id][v] = next;
                m.positions[next] = c.positions[v];
                if (normals) m.normals[next] = c.normals[v];
                ++next;
            }
        });
    });
    // 3. Duplicates take the index of the first of their run.
    for (std::size_t i = 1, first = 0; i < border.size(); ++i) {
        if (border[i].key != border[first].key) {
            first = i;
            continue;
        }
        remap[border[i].chunk][border[i].local] = remap[border[first].chunk][border[first].local];
    }
    in_arena(threads, [&] {
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t id) {
            const auto& c = s.chunks[id];
            auto* out = m.triangles.data() + tbase[id];
            for (const auto& t : c.triangles) *out++ = {remap[id][t[0]], remap[id][t[1]], remap[id][t[2]]};
        });
    });

    // 4. Vertices where the gradient vanished take the area-weighted normal of their triangles.
    if (normals) {
        std::vector<std::uint32_t> flat;
        for (std::size_t v = 0; v < m.normals.size(); ++v)
            if (m.normals[v] == glm::vec3(0.0f)) flat.push_back(std::uint32_t(v));
        if (!flat.empty()) {
            std::vector<glm::dvec3> acc(m.positions.size(), glm::dvec3(0.0));
            std::vector<std::uint8_t> want(m.positions.size(), 0);
            for (auto v : flat) want[v] = 1;
            for (const auto& t : m.triangles) {
                if (!(want[t[0]] | want[t[1]] | want[t[2]])) continue;
                const glm::dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
                const glm::dvec3 fn = glm::cross(b - a, c - a);
                for (auto v : t)
                    if (want[v]) acc[v] += fn;
            }
            for (auto v : flat) {
                const double len = glm::length(acc[v]);
                if (len > 0.0) m.normals[v] = glm::vec3(acc[v] / len);
            }
        }
    }
    if (map) map->remap = std::move(remap);
    return m;
}

std::vector<double> distinct_labels(const Volume& v, std::size_t limit) {
    if (v.is_sparse()) throw Error(v.meta.source, "label maps must be dense volumes");
    std::vector<double> out;
    dispatch_voxel_type(v.type, [&](auto tag) {
        using T = decltype(tag);
        if constexpr (std::is_integral_v<T> && sizeof(T) <= 2) {
            // Small integer types: a histogram.
            std::vector<std::uint8_t> seen(std::size_t(1) << (8 * sizeof(T)), 0);
            using U = std::make_unsigned_t<T>;
            for (T x : v.as<T>()) seen[U(x)] = 1;
            for (std::size_t u = 0; u < seen.size(); ++u)
                if (seen[u]) {
                    const double value = double(T(U(u)));
                    if (value != 0.0) out.push_back(value);
                }
        } else {
            std::set<T> seen;
            for (T x : v.as<T>()) {
                if constexpr (std::is_floating_point_v<T>)
                    if (std::isnan(x)) continue;
                if (x != T(0) && seen.insert(x).second && seen.size() > limit) break;
            }
            for (T x : seen) out.push_back(double(x));
        }
        return 0;
    });
    std::sort(out.begin(), out.end());
    if (out.size() > limit)
        throw Error(v.meta.source,
                    "has more than " + std::to_string(limit) + " distinct values: it does not look like a label map");
    return out;
}

namespace {
std::vector<ChunkedSurface> label_chunks(const VolumeWindow& w, const ChunkIndex& idx, const ExtractOptions& opt,
                                         std::span<const double> labels, std::span<const std::size_t> ids) {
    const Volume& v = *w.slab;
    const Frame f = make_frame(w, idx.chunk_size(), opt.normals);
    std::vector<ChunkedSurface> surfaces(labels.size());
    for (std::size_t l = 0; l < labels.size(); ++l) {
        surfaces[l].iso = labels[l];
        surfaces[l].chunks.resize(idx.chunk_count());
    }
    // A label's surface can only cross a chunk holding values on both sides of
    // it... or equal to it: the chunk's range must include the label and not
    // be that label alone.
    tbb::enumerable_thread_specific<Scratch> scratch;
    std::atomic<std::size_t> done{0};
    std::atomic<bool> cancelled{false};
    std::mutex progress_mutex;
    in_arena(opt.threads, [&] {
        tbb::parallel_for(std::size_t(0), ids.size(), [&](std::size_t n) {
            if (cancelled.load(std::memory_order_relaxed)) return;
            const std::size_t id = ids[n];
            const auto g = chunk_geom(w.dims, idx.chunk_size(), idx.coords(id));
            // Labels whose range test passes (cheap), then the exact set present.
            std::vector<std::size_t> candidates;
            for (std::size_t l = 0; l < labels.size(); ++l)
                if (idx.active(id, labels[l]) || idx.active(id, std::nextafter(labels[l], HUGE_VAL)))
                    candidates.push_back(l);
            if (!candidates.empty()) {
                auto& sc = scratch.local();
                std::array<std::int64_t, 3> lo, cnt;
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::max<std::int64_t>(g.p0[a] - 1, 0);
                    cnt[a] = std::min<std::int64_t>(g.p1[a] + 1, w.dims[a] - 1) - lo[a] + 1;
                }
                dispatch_voxel_type(v.type, [&](auto tag) {
                    using T = decltype(tag);
                    const Block<T> b = load_block<T>(w, idx, lo, cnt, sc);
                    std::set<double> present;
                    for (std::int64_t z = g.p0[2]; z <= g.p1[2]; ++z)
                        for (std::int64_t y = g.p0[1]; y <= g.p1[1]; ++y)
                            for (std::int64_t xx = g.p0[0]; xx <= g.p1[0]; ++xx) present.insert(double(b.at(xx, y, z)));
                    if (present.size() < 2) return 0; // uniform chunk: no boundary inside it
                    for (auto l : candidates)
                        if (present.count(labels[l]))
                            run_chunk(b, g, f, LabelClassifier{labels[l]}, sc, surfaces[l].chunks[id]);
                    return 0;
                });
            }
            const std::size_t d = ++done;
            if (opt.progress && (d % 64 == 0 || d == ids.size())) {
                std::lock_guard lock(progress_mutex);
                if (!opt.progress(double(d) / double(ids.size()), "extracting label surfaces")) cancelled = true;
            }
        });
    });
    if (cancelled) throw Cancelled("extract_labels");
    return surfaces;
}
} // namespace

std::vector<ChunkedSurface> extract_label_chunks(const VolumeWindow& w, const ChunkIndex& index,
                                                 std::span<const double> labels, std::span<const std::size_t> ids,
                                                 const ExtractOptions& opt) {
    ExtractOptions o = opt;
    o.threads = effective_threads(opt.threads);
    return label_chunks(w, index, o, labels, ids);
}

std::vector<LabelSurface> extract_labels(const Volume& v, std::span<const double> wanted, const ExtractOptions& opt_in,
                                         ExtractSeconds* seconds) {
    using Clock = std::chrono::steady_clock;
    const auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    ExtractSeconds took;
    auto t = Clock::now();
    std::vector<double> labels(wanted.begin(), wanted.end());
    if (labels.empty()) labels = distinct_labels(v);
    std::sort(labels.begin(), labels.end());
    labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
    Extractor x(v, opt_in);
    const auto& idx = x.index();
    took.index = since(t);
    t = Clock::now();
    std::vector<std::size_t> ids;
    for (std::size_t id = 0; id < idx.chunk_count(); ++id) ids.push_back(id);
    auto surfaces = label_chunks(VolumeWindow::whole(v), idx, x.options(), labels, ids);
    took.extract = since(t);
    t = Clock::now();
    std::vector<LabelSurface> out;
    for (std::size_t l = 0; l < labels.size(); ++l) {
        out.push_back({labels[l], weld(surfaces[l], x.options().threads)});
        surfaces[l] = ChunkedSurface{};
    }
    took.weld = since(t);
    if (seconds) {
        seconds->index += took.index;
        seconds->extract += took.extract;
        seconds->weld += took.weld;
    }
    return out;
}

Mesh extract_isosurface(const Volume& v, double iso, const ExtractOptions& opt) {
    Extractor x(v, opt);
    return weld(x.extract(iso), x.options().threads);
}

std::vector<Mesh> extract_isosurfaces(const Volume& v, std::span<const double> isos, const ExtractOptions& opt) {
    Extractor x(v, opt);
    auto surfaces = x.extract(isos);
    std::vector<Mesh> out;
    out.reserve(surfaces.size());
    for (auto& s : surfaces) {
        out.push_back(weld(s, x.options().threads));
        s = ChunkedSurface{}; // free the chunks as soon as they are welded
    }
    return out;
}

} // namespace iso
