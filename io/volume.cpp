#include "io/volume.hpp"

#include "io/error.hpp"
#include "io/process.hpp"
#include "io/sparse.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <sstream>

#include <unistd.h>

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace iso {

std::size_t voxel_size(VoxelType t) {
    return dispatch_voxel_type(t, [](auto v) { return sizeof(v); });
}

const char* voxel_type_name(VoxelType t) {
    switch (t) {
    case VoxelType::U8: return "uint8";
    case VoxelType::I8: return "int8";
    case VoxelType::U16: return "uint16";
    case VoxelType::I16: return "int16";
    case VoxelType::U32: return "uint32";
    case VoxelType::I32: return "int32";
    case VoxelType::F32: return "float32";
    case VoxelType::F64: return "float64";
    }
    return "unknown";
}

void Volume::FreeDeleter::operator()(std::byte* p) const { std::free(p); }

namespace {
// The most a single dense volume may take: physical memory, or
// ISOSCOPE_MAX_VOLUME_BYTES when set (tests use it to exercise the check).
std::size_t max_volume_bytes() {
    if (const char* env = std::getenv("ISOSCOPE_MAX_VOLUME_BYTES")) {
        char* end = nullptr;
        unsigned long long v = std::strtoull(env, &end, 10);
        if (end != env && v > 0) return static_cast<std::size_t>(v);
    }
    const std::size_t phys = physical_memory_bytes();
    return phys ? phys : std::numeric_limits<std::size_t>::max();
}

std::string human_bytes(double b) {
    const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int u = 0;
    while (b >= 1024.0 && u < 6) {
        b /= 1024.0;
        ++u;
    }
    std::ostringstream os;
    os.precision(3);
    os << b << ' ' << unit[u];
    return os.str();
}
} // namespace

std::size_t checked_byte_size(const std::string& file, std::array<std::int64_t, 3> dims, VoxelType type) {
    for (int a = 0; a < 3; ++a)
        if (dims[a] <= 0)
            throw Error(file,
                        "dimension " + std::to_string(a) + " is " + std::to_string(dims[a]) + " (must be positive)");
    // Multiply in unsigned 128 bits so a product that overflows 64 bits is
    // reported as such rather than wrapping.
    unsigned __int128 n = 1;
    for (auto d : dims) n *= static_cast<unsigned __int128>(d);
    n *= voxel_size(type);
    if (n > std::numeric_limits<std::size_t>::max() / 2)
        throw Error(file, "dimensions " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                              std::to_string(dims[2]) + " overflow the addressable size");
    const auto bytes = static_cast<std::size_t>(n);
    const auto limit = max_volume_bytes();
    if (bytes > limit)
        throw Error(file, "volume of " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                              std::to_string(dims[2]) + " " + voxel_type_name(type) + " needs " +
                              human_bytes(double(bytes)) + ", more than the " + human_bytes(double(limit)) +
                              " allowed on this machine");
    return bytes;
}

void check_affine(const std::string& file, const glm::dmat4& m, bool allow_shear) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) throw Error(file, "index-to-world matrix has a non-finite entry");
    glm::dvec3 col[3] = {glm::dvec3(m[0]), glm::dvec3(m[1]), glm::dvec3(m[2])};
    const char* axis = "ijk";
    for (int a = 0; a < 3; ++a) {
        double len = glm::length(col[a]);
        if (!(len > 0.0)) throw Error(file, std::string("spacing along ") + axis[a] + " is zero or negative");
    }
    const double det = glm::determinant(glm::dmat3(col[0], col[1], col[2]));
    if (!(std::abs(det) > 0.0)) throw Error(file, "direction cosines are degenerate (zero determinant)");
    if (allow_shear) return;
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            double c = glm::dot(col[a], col[b]) / (glm::length(col[a]) * glm::length(col[b]));
            if (std::abs(c) > 1e-4) {
                std::ostringstream os;
                os << "direction cosines are not orthogonal (axes " << axis[a] << " and " << axis[b] << " at "
                   << std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI << " degrees)";
                throw Error(file, os.str());
            }
        }
}

Volume Volume::dense(std::array<std::int64_t, 3> dims, VoxelType type, const glm::dmat4& index_to_lps) {
    Volume v;
    const auto bytes = checked_byte_size("Volume::dense", dims, type);
    auto* p = static_cast<std::byte*>(std::calloc(bytes, 1));
    if (!p) throw Error("Volume::dense", "cannot allocate " + human_bytes(double(bytes)));
    v.data_.reset(p);
    v.byte_size_ = bytes;
    v.dims = dims;
    v.type = type;
    v.index_to_lps = index_to_lps;
    return v;
}

Volume Volume::sparse(std::shared_ptr<const SparseGrid> grid, std::array<std::int64_t, 3> dims,
                      const glm::dmat4& index_to_lps) {
    Volume v;
    v.sparse_ = std::move(grid);
    v.dims = dims;
    v.type = VoxelType::F32;
    v.index_to_lps = index_to_lps;
    return v;
}

std::size_t Volume::memory_bytes() const {
    if (sparse_) return sparse_memory_bytes(*sparse_);
    return byte_size_;
}

double Volume::value(std::int64_t i, std::int64_t j, std::int64_t k) const {
    if (sparse_) return sparse_value(*sparse_, i, j, k);
    const auto idx = linear_index(i, j, k);
    return dispatch_voxel_type(type, [&](auto t) {
        using T = decltype(t);
        return static_cast<double>(as<T>()[idx]);
    });
}

glm::dvec3 Volume::spacing() const {
    return {glm::length(glm::dvec3(index_to_lps[0])), glm::length(glm::dvec3(index_to_lps[1])),
            glm::length(glm::dvec3(index_to_lps[2]))};
}

glm::dvec3 Volume::index_to_world(const glm::dvec3& ijk) const {
    return glm::dvec3(index_to_lps * glm::dvec4(ijk, 1.0));
}

namespace {

// Minimum and maximum of the finite samples [b, e) into `lo`/`hi`, NaN and
// infinite ones counted. Integers in runs of 64: a fixed trip count that the
// compiler vectorizes at -O2 (a 2 GiB volume's range took ~1 s of CPU).
template <class T> void range_of(const T* b, const T* e, T& lo, T& hi, std::size_t& nan, std::size_t& inf) {
    if constexpr (std::is_floating_point_v<T>) {
        for (; b != e; ++b) {
            const T x = *b;
            if (std::isnan(x)) {
                ++nan;
            } else if (std::isinf(x)) {
                ++inf;
            } else {
                lo = x < lo ? x : lo;
                hi = x > hi ? x : hi;
            }
        }
    } else {
        T l = lo, h = hi;
        for (; e - b >= 64; b += 64)
            for (int k = 0; k < 64; ++k) {
                l = b[k] < l ? b[k] : l;
                h = b[k] > h ? b[k] : h;
            }
        for (; b != e; ++b) {
            l = *b < l ? *b : l;
            h = *b > h ? *b : h;
        }
        lo = l;
        hi = h;
    }
}

} // namespace

ValueRange Volume::value_range() const {
    if (sparse_) return sparse_value_range(*sparse_);
    ValueRange r;
    dispatch_voxel_type(type, [&](auto t) {
        using T = decltype(t);
        auto s = as<T>();
        // In parallel: minima, maxima and counts are exact in any order.
        struct Part {
            T lo = std::numeric_limits<T>::max(), hi = std::numeric_limits<T>::lowest();
            std::size_t nan = 0, inf = 0, samples = 0;
        };
        const Part p = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, s.size(), std::size_t(1) << 20), Part{},
            [&](const tbb::blocked_range<std::size_t>& range, Part q) {
                range_of(s.data() + range.begin(), s.data() + range.end(), q.lo, q.hi, q.nan, q.inf);
                q.samples += range.size();
                return q;
            },
            [](Part a, const Part& b) {
                a.lo = b.lo < a.lo ? b.lo : a.lo;
                a.hi = b.hi > a.hi ? b.hi : a.hi;
                a.nan += b.nan;
                a.inf += b.inf;
                a.samples += b.samples;
                return a;
            });
        r.nan_count = p.nan;
        r.inf_count = p.inf;
        if (p.samples > p.nan + p.inf) { // some finite sample
            r.min = double(p.lo);
            r.max = double(p.hi);
        }
        return 0;
    });
    return r;
}

void warn_non_finite(Volume& v) {
    if (v.type != VoxelType::F32 && v.type != VoxelType::F64 && !v.is_sparse()) return;
    const auto r = v.value_range();
    if (r.nan_count || r.inf_count)
        v.meta.warnings.push_back(std::to_string(r.nan_count) + " NaN and " + std::to_string(r.inf_count) +
                                  " infinite voxels (of " + std::to_string(v.voxel_count()) +
                                  "); they are excluded from the value range and treated as outside surfaces");
}

glm::dmat4 make_affine(const glm::dvec3& spacing, const glm::dvec3& origin, const glm::dmat3& dir) {
    glm::dmat4 m(1.0);
    for (int a = 0; a < 3; ++a) m[a] = glm::dvec4(dir[a] * spacing[a], 0.0);
    m[3] = glm::dvec4(origin, 1.0);
    return m;
}

glm::dmat4 ras_to_lps(const glm::dmat4& index_to_ras) {
    glm::dmat4 flip(1.0);
    flip[0][0] = -1.0;
    flip[1][1] = -1.0;
    return flip * index_to_ras;
}

} // namespace iso
