// Slice views' headless half (slices.hpp, docs/slices.md): planes, reslicing,
// window/level, pixel <-> LPS and surface outlines.
//
// Reslicing is written here rather than taken from VTK (vtkImageReslice):
// the values must be exactly what the core API's value at a point
// (sample_volume) reports for the same LPS point, including its inside test,
// its clamped outer half voxel and its NaN rule, and VTK's image data has no
// sheared (gantry-tilt) geometry.
#include "renderer/core/slices.hpp"
#include "renderer/core/scene.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "io/error.hpp"
#include "io/finite.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/surface/atomic.hpp"

namespace iso::core {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr int kMaxImageSide = 16384;
// Voxels: the rounding allowance of sample_volume (renderer/surface/analysis.cpp)
// at the grid's outer faces and at voxel centres; kept equal to it.
constexpr double kIndexEps = 1e-9;

struct Axes {
    glm::dvec3 right, up, normal;
};

// Slicer's vtkMRMLSliceNode orientations written in LPS (Slicer's RAS
// columns with x and y negated): axial L, A, normal S; coronal L, S, normal
// P; sagittal P, S, normal L. The normals are the positive LPS axes (Slicer
// uses S, A, R), so an offset reads as an LPS coordinate.
Axes orientation_axes(SliceOrientation o) {
    switch (o) {
    case SliceOrientation::Axial: return {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}};
    case SliceOrientation::Coronal: return {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}};
    case SliceOrientation::Sagittal: return {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
    }
    return {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}};
}

double lerp(double a, double b, double t) { return t == 0.0 ? a : t == 1.0 ? b : a + (b - a) * t; }

// sample_volume's rules from a continuous index, value only (the sparse path
// and the NaN fallback of the dense path). Kept in step with measure.cpp.
float sample_index(const Volume& v, const glm::dvec3& index, Interp interp) {
    std::array<std::int64_t, 3> i0{}, i1{}, voxel{};
    std::array<double, 3> f{};
    for (int a = 0; a < 3; ++a) {
        const double n = double(v.dims[a]);
        const double x = std::abs(index[a] - std::round(index[a])) < kIndexEps ? std::round(index[a]) : index[a];
        if (!(x >= -0.5 - kIndexEps && x <= n - 0.5 + kIndexEps)) return kNaN;
        const double c = std::clamp(x, 0.0, n - 1.0);
        voxel[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(x + 0.5)), 0, v.dims[a] - 1);
        i0[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(c)), 0, std::max<std::int64_t>(v.dims[a] - 2, 0));
        i1[a] = std::min(i0[a] + 1, v.dims[a] - 1);
        f[a] = i1[a] == i0[a] ? 0.0 : std::clamp(c - double(i0[a]), 0.0, 1.0);
    }
    if (interp == Interp::Nearest) return float(v.value(voxel[0], voxel[1], voxel[2]));
    auto at = [&](int di, int dj, int dk) {
        return v.value(di ? i1[0] : i0[0], dj ? i1[1] : i0[1], dk ? i1[2] : i0[2]);
    };
    // Only samples with weight are read, so a NaN neighbour with zero weight does not spread.
    auto row = [&](int dj, int dk) { return f[0] == 0 ? at(0, dj, dk) : lerp(at(0, dj, dk), at(1, dj, dk), f[0]); };
    auto plane = [&](int dk) { return f[1] == 0 ? row(0, dk) : lerp(row(0, dk), row(1, dk), f[1]); };
    return float(f[2] == 0 ? plane(0) : lerp(plane(0), plane(1), f[2]));
}

// The continuous index of pixel (0, 0)'s centre and the index steps per column and per row.
struct IndexSteps {
    glm::dvec3 first, per_column, per_row;
};
IndexSteps index_steps(const Volume& v, const SliceGrid& g) {
    const glm::dmat4 inv = glm::inverse(v.index_to_lps);
    return {glm::dvec3(inv * glm::dvec4(pixel_to_lps(g, {0.5, 0.5}), 1.0)), glm::dvec3(inv * glm::dvec4(g.dx, 0.0)),
            glm::dvec3(inv * glm::dvec4(g.dy, 0.0))};
}

// Rows [r0, r1) of a dense volume of type T. The inner loop is the index by
// two multiply-adds per axis, the inside test, and the 8 (or 1) fetches.
template <class T>
void reslice_dense_rows(const Volume& v, const IndexSteps& s, int width, int r0, int r1, Interp interp, float* out) {
    const T* data = v.as<T>().data();
    const std::int64_t nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
    const std::int64_t sy = nx, sz = nx * ny;
    // Neighbour offsets; 0 on an axis of one sample (its weight is 0 then).
    const std::int64_t ox = nx > 1 ? 1 : 0, oy = ny > 1 ? sy : 0, oz = nz > 1 ? sz : 0;
    const double lo = -0.5 - kIndexEps;
    const double hx = double(nx) - 0.5 + kIndexEps, hy = double(ny) - 0.5 + kIndexEps,
                 hz = double(nz) - 0.5 + kIndexEps;
    const double mx = double(nx - 1), my = double(ny - 1), mz = double(nz - 1);
    const std::int64_t lx = std::max<std::int64_t>(nx - 2, 0), ly = std::max<std::int64_t>(ny - 2, 0),
                       lz = std::max<std::int64_t>(nz - 2, 0);
    for (int r = r0; r < r1; ++r) {
        const glm::dvec3 base = s.first + double(r) * s.per_row;
        float* o = out + std::size_t(r) * std::size_t(width);
        for (int c = 0; c < width; ++c) {
            const double x = base.x + double(c) * s.per_column.x;
            const double y = base.y + double(c) * s.per_column.y;
            const double z = base.z + double(c) * s.per_column.z;
            if (!(x >= lo && x <= hx && y >= lo && y <= hy && z >= lo && z <= hz)) {
                o[c] = kNaN;
                continue;
            }
            if (interp == Interp::Nearest) {
                const std::int64_t i = std::clamp<std::int64_t>(std::int64_t(std::floor(x + 0.5)), 0, nx - 1);
                const std::int64_t j = std::clamp<std::int64_t>(std::int64_t(std::floor(y + 0.5)), 0, ny - 1);
                const std::int64_t k = std::clamp<std::int64_t>(std::int64_t(std::floor(z + 0.5)), 0, nz - 1);
                o[c] = float(data[i + sy * j + sz * k]);
                continue;
            }
            const double cx = std::clamp(x, 0.0, mx), cy = std::clamp(y, 0.0, my), cz = std::clamp(z, 0.0, mz);
            const std::int64_t i = std::min(std::int64_t(cx), lx), j = std::min(std::int64_t(cy), ly),
                               k = std::min(std::int64_t(cz), lz);
            const double fx = cx - double(i), fy = cy - double(j), fz = cz - double(k);
            const T* p = data + i + sy * j + sz * k;
            const double c00 = double(p[0]) + (double(p[ox]) - double(p[0])) * fx;
            const double c10 = double(p[oy]) + (double(p[oy + ox]) - double(p[oy])) * fx;
            const double c01 = double(p[oz]) + (double(p[oz + ox]) - double(p[oz])) * fx;
            const double c11 = double(p[oz + oy]) + (double(p[oz + oy + ox]) - double(p[oz + oy])) * fx;
            const double c0 = c00 + (c10 - c00) * fy, c1 = c01 + (c11 - c01) * fy;
            double value = c0 + (c1 - c0) * fz;
            if constexpr (std::is_floating_point_v<T>) {
                // A NaN sample read with zero weight must not spread (sample_volume reads only weighted ones).
                if (std::isnan(value)) value = sample_index(v, {x, y, z}, Interp::Linear);
            }
            o[c] = float(value);
        }
    }
}

// One crossing point per edge, computed from (below, above) in that order
// whichever triangle asks, in one function (no inlined copies that a
// compiler could contract differently), so neighbours agree bitwise.
[[gnu::noinline]] glm::dvec3 crossing(const glm::vec3& below, double d_below, const glm::vec3& above, double d_above) {
    if (d_above == 0.0) return glm::dvec3(above);
    const double t = d_below / (d_below - d_above);
    const glm::dvec3 a(below), b(above);
    return a + t * (b - a);
}

} // namespace

// ---- Planes ------------------------------------------------------------------

const char* slice_orientation_name(SliceOrientation o) {
    switch (o) {
    case SliceOrientation::Axial: return "axial";
    case SliceOrientation::Coronal: return "coronal";
    case SliceOrientation::Sagittal: return "sagittal";
    }
    return "axial";
}

namespace {
// The LPS bounding box of the voxels' extent (volume_corners).
std::pair<glm::dvec3, glm::dvec3> lps_box(const Volume& v) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::dvec3& p : volume_corners(v)) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    return {lo, hi};
}
} // namespace

double SlicePlane::offset_mm() const { return glm::dot(origin, normal); }

double slice_step_mm(const Volume& v, const glm::dvec3& normal) {
    const glm::dvec3 d = glm::inverse(glm::dmat3(v.index_to_lps)) * normal;
    const double m = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    return m > 0 ? 1.0 / m : 1.0;
}

SlicePlane default_plane(const Volume& v, SliceOrientation o) {
    if (v.voxel_count() <= 0) throw Error("slice views", "there is no volume to slice (no voxels)");
    const auto [lo, hi] = lps_box(v);
    const Axes ax = orientation_axes(o);
    const glm::dvec3 extent = hi - lo;
    SlicePlane p;
    p.orientation = o;
    p.origin = p.center = 0.5 * (lo + hi);
    p.right = ax.right;
    p.up = ax.up;
    p.normal = ax.normal;
    p.fov_mm = {glm::dot(glm::abs(ax.right), extent), glm::dot(glm::abs(ax.up), extent)};
    const glm::dvec3 sp = v.spacing();
    p.pixel_mm = std::min({sp.x, sp.y, sp.z});
    p.step_mm = slice_step_mm(v, ax.normal);
    return p;
}

std::array<SlicePlane, 3> default_planes(const Volume& v) {
    return {default_plane(v, SliceOrientation::Axial), default_plane(v, SliceOrientation::Coronal),
            default_plane(v, SliceOrientation::Sagittal)};
}

void scroll_slices(SlicePlane& p, double steps) {
    const glm::dvec3 d = steps * p.step_mm * p.normal;
    p.origin += d;
    p.center += d;
}

void set_offset(SlicePlane& p, double offset_mm) {
    p.origin += (offset_mm - glm::dot(p.origin, p.normal)) * p.normal;
    p.center += (offset_mm - glm::dot(p.center, p.normal)) * p.normal;
}

void set_crosshair(std::span<SlicePlane> planes, const glm::dvec3& lps) {
    for (auto& p : planes) {
        p.origin = lps;
        p.center += glm::dot(lps - p.center, p.normal) * p.normal;
    }
}

void zoom_to_fit(SlicePlane& p, int width, int height) {
    if (width < 1 || height < 1) return;
    const double s = std::max(p.fov_mm.x / double(width), p.fov_mm.y / double(height));
    if (s > 0 && std::isfinite(s)) p.pixel_mm = s;
}

std::array<int, 2> native_size(const SlicePlane& p) {
    auto side = [&](double fov) {
        const double n = p.pixel_mm > 0 ? std::ceil(fov / p.pixel_mm - 1e-9) : 1.0;
        return std::isfinite(n) ? int(std::clamp(n, 1.0, double(kMaxImageSide))) : 1;
    };
    return {side(p.fov_mm.x), side(p.fov_mm.y)};
}

void pan_pixels(SlicePlane& p, const glm::dvec2& delta) {
    if (!finite(glm::dvec3(delta, 0.0))) return;
    // The grid's corner moves by -(delta.x * dx + delta.y * dy), dx = pixel_mm * right, dy = -pixel_mm * up.
    p.center -= p.pixel_mm * (delta.x * p.right - delta.y * p.up);
}

void zoom_about(SlicePlane& p, int width, int height, const glm::dvec2& fixed, double factor) {
    if (!(factor > 0) || !std::isfinite(factor) || !(p.pixel_mm > 0) || !finite(glm::dvec3(fixed, 0.0))) return;
    constexpr double kMinPixelMm = 1e-4, kMaxPixelMm = 1e4;
    const double s = p.pixel_mm, s2 = std::clamp(s / factor, kMinPixelMm, kMaxPixelMm);
    // The point under `fixed` is centre + (fixed - half) . (s * right, -s * up); keep it at s2.
    const glm::dvec2 off = fixed - 0.5 * glm::dvec2(double(width), double(height));
    p.center += (s - s2) * (off.x * p.right - off.y * p.up);
    p.pixel_mm = s2;
}

double drag_zoom_factor(double dy_up, int height) {
    if (height < 1 || !std::isfinite(dy_up)) return 1.0;
    return std::exp2(dy_up / (0.5 * double(height)));
}

void fit_view(SlicePlane& p, const Volume& v, int width, int height) {
    if (v.voxel_count() <= 0) return;
    const auto [lo, hi] = lps_box(v);
    const glm::dvec3 c = 0.5 * (lo + hi);
    p.center = c + (glm::dot(p.origin - c, p.normal)) * p.normal;
    zoom_to_fit(p, width, height);
}

SliceRange slice_range(const Volume& v, const SlicePlane& p) {
    SliceRange r;
    r.step_mm = p.step_mm > 0 && std::isfinite(p.step_mm) ? p.step_mm : 1.0;
    if (v.voxel_count() <= 0) {
        r.first_mm = p.offset_mm();
        return r;
    }
    const auto [lo, hi] = lps_box(v);
    double a = std::numeric_limits<double>::max(), b = -a;
    for (int corner = 0; corner < 8; ++corner) {
        const double d = glm::dot(
            glm::dvec3(corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z), p.normal);
        a = std::min(a, d);
        b = std::max(b, d);
    }
    // Slices a step apart from half a step inside the box's near face: one per voxel along a grid axis.
    const double n = std::floor((b - a) / r.step_mm + 1e-6);
    r.count = int(std::clamp(n, 1.0, 1e6));
    r.first_mm = n >= 1 ? a + 0.5 * r.step_mm : 0.5 * (a + b);
    return r;
}

int slice_index(const SliceRange& r, double offset_mm) {
    // Half-way between two slices rounds up, whatever the rounding of the division.
    const double t = std::floor((offset_mm - r.first_mm) / r.step_mm + 0.5 + 1e-6);
    return std::isfinite(t) ? int(std::clamp(t, 0.0, double(r.count - 1))) : 0;
}

std::string slice_edge_letter(const SlicePlane& p, SliceEdge e) {
    switch (e) {
    case SliceEdge::Left: return orientation_letter(-p.right);
    case SliceEdge::Right: return orientation_letter(p.right);
    case SliceEdge::Top: return orientation_letter(p.up);
    case SliceEdge::Bottom: return orientation_letter(-p.up);
    }
    return {};
}

double slice_scale_bar_mm(const SlicePlane& p, int width) {
    if (width < 1 || !(p.pixel_mm > 0) || !std::isfinite(p.pixel_mm)) return 0;
    return round_length_mm(0.2 * double(width) * p.pixel_mm);
}

// ---- Pixels <-> LPS --------------------------------------------------------------

SliceGrid slice_grid(const SlicePlane& p, int width, int height) {
    if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
        throw Error("slice image", "size " + std::to_string(width) + " x " + std::to_string(height) +
                                       " is outside 1 .. " + std::to_string(kMaxImageSide) + " pixels per side");
    if (!(p.pixel_mm > 0) || !std::isfinite(p.pixel_mm))
        throw Error("slice image", "pixel size " + std::to_string(p.pixel_mm) + " mm is not a positive number");
    constexpr double kTol = 1e-6;
    const bool unit = std::abs(glm::length(p.right) - 1) < kTol && std::abs(glm::length(p.up) - 1) < kTol &&
                      std::abs(glm::length(p.normal) - 1) < kTol;
    const bool orthogonal = std::abs(glm::dot(p.right, p.up)) < kTol && std::abs(glm::dot(p.right, p.normal)) < kTol &&
                            std::abs(glm::dot(p.up, p.normal)) < kTol;
    if (!unit || !orthogonal || !finite(p.origin) || !finite(p.center))
        throw Error("slice image", std::string("the ") + slice_orientation_name(p.orientation) +
                                       " plane's axes are not orthonormal or its points are not finite");
    SliceGrid g;
    g.width = width;
    g.height = height;
    g.normal = p.normal;
    g.offset_mm = p.offset_mm();
    g.pixel_mm = p.pixel_mm;
    g.dx = p.pixel_mm * p.right;
    g.dy = -p.pixel_mm * p.up;
    // The centre is put on the plane through the crosshair, whatever the caller left in it.
    const glm::dvec3 c = p.center - glm::dot(p.center - p.origin, p.normal) * p.normal;
    g.corner = c - 0.5 * double(width) * g.dx - 0.5 * double(height) * g.dy;
    return g;
}

glm::dvec3 pixel_to_lps(const SliceGrid& g, const glm::dvec2& pixel) {
    return g.corner + pixel.x * g.dx + pixel.y * g.dy;
}

SlicePoint lps_to_pixel(const SliceGrid& g, const glm::dvec3& lps) {
    const glm::dvec3 rel = lps - g.corner;
    const double s2 = g.pixel_mm * g.pixel_mm;
    return {{glm::dot(rel, g.dx) / s2, glm::dot(rel, g.dy) / s2}, glm::dot(lps, g.normal) - g.offset_mm};
}

std::optional<VolumeSample> sample_at_pixel(const Volume& v, const SliceGrid& g, const glm::dvec2& pixel) {
    return sample_volume(v, pixel_to_lps(g, pixel));
}

// ---- Reslicing ---------------------------------------------------------------------

void reslice(const Volume& v, const SliceGrid& g, Interp interp, SliceImage& out) {
    out.width = g.width;
    out.height = g.height;
    out.values.resize(std::size_t(g.width) * std::size_t(g.height));
    if (v.voxel_count() <= 0) {
        std::fill(out.values.begin(), out.values.end(), kNaN);
        return;
    }
    const IndexSteps s = index_steps(v, g);
    float* dst = out.values.data();
    const int width = g.width;
    // A few rows per task: a 512-pixel row is a few microseconds of work.
    const tbb::blocked_range<int> rows(0, g.height, 8);
    if (v.is_sparse()) {
        tbb::parallel_for(rows, [&](const tbb::blocked_range<int>& r) {
            for (int row = r.begin(); row < r.end(); ++row)
                for (int c = 0; c < width; ++c)
                    dst[std::size_t(row) * std::size_t(width) + std::size_t(c)] =
                        sample_index(v, s.first + double(row) * s.per_row + double(c) * s.per_column, interp);
        });
        return;
    }
    dispatch_voxel_type(v.type, [&](auto t) {
        using T = decltype(t);
        tbb::parallel_for(rows, [&](const tbb::blocked_range<int>& r) {
            reslice_dense_rows<T>(v, s, width, r.begin(), r.end(), interp, dst);
        });
    });
}

void reslice_here(const Volume& v, const SliceGrid& g, Interp interp, SliceImage& out) {
    thread_local tbb::task_arena alone(1);
    alone.execute([&] { reslice(v, g, interp, out); });
}

SliceImage reslice(const Volume& v, const SlicePlane& p, int width, int height, Interp interp) {
    SliceImage img;
    reslice(v, slice_grid(p, width, height), interp, img);
    return img;
}

// ---- Window / level ------------------------------------------------------------------

namespace {

// Radiopaedia, "Windowing (CT)" (https://radiopaedia.org/articles/windowing-ct):
// brain W:80 L:40; soft tissues W:350-400 L:20-60 (W:400 L:40 taken); lungs
// W:1500 L:-600; bone W:1800 L:400. Angio: W:600 L:170, the CTA preset some
// open viewers use (e.g. the ctviewer project's); neither Radiopaedia's table
// nor Slicer's presets have one.
constexpr WindowPreset kCtPresets[] = {
    {"brain", {40.0, 80.0}},   {"soft tissue", {40.0, 400.0}}, {"lung", {-600.0, 1500.0}},
    {"bone", {400.0, 1800.0}}, {"angio", {170.0, 600.0}},
};

constexpr double kMinWidth = 1e-9;

} // namespace

std::span<const WindowPreset> ct_window_presets() { return kCtPresets; }

std::optional<WindowLevel> ct_window_preset(std::string_view name) {
    for (const auto& p : kCtPresets)
        if (p.name == name) return p.window;
    return std::nullopt;
}

WindowLevel default_window(std::string_view modality, const ValueRange& range) {
    if (modality == "CT") return *ct_window_preset("soft tissue");
    if (!(range.max > range.min)) return {range.min, 1.0};
    return {0.5 * (range.min + range.max), range.max - range.min};
}

WindowLevel default_window(const Volume& v) {
    if (v.meta.modality == "CT") return default_window("CT", ValueRange{});
    return default_window(v.meta.modality, v.value_range());
}

WindowLevel default_window(const Scene& s) {
    const Volume& v = s.volume();
    if (v.meta.modality == "CT") return default_window("CT", ValueRange{});
    return default_window(v.meta.modality, s.value_range());
}

WindowLevel drag_window(const WindowLevel& start, const glm::dvec2& drag, const ValueRange& range) {
    // vtkSliceViewInteractorStyle (3D Slicer): gain = (range high - low) / 500 per pixel.
    const double span = range.max - range.min;
    const double gain = (span > 0 && std::isfinite(span) ? span : 1.0) / 500.0;
    if (!std::isfinite(drag.x) || !std::isfinite(drag.y)) return start;
    return {start.center + gain * drag.y, std::max(0.0, start.width + gain * drag.x)};
}

std::uint8_t window_grey(double value, const WindowLevel& w) {
    if (std::isnan(value)) return 0;
    if (!(w.width >= kMinWidth)) return value >= w.center ? 255 : 0;
    // Divided, not multiplied by 255 / width: the centre then lands on 127.5 exactly (rounds to 128).
    const double t = (value - (w.center - 0.5 * w.width)) / w.width * 255.0;
    return std::uint8_t(std::clamp(t, 0.0, 255.0) + 0.5);
}

std::vector<std::uint8_t> apply_window(const SliceImage& img, const WindowLevel& w, PixelFormat format) {
    const std::size_t n = std::size_t(img.width) * std::size_t(img.height);
    const std::size_t bpp = format == PixelFormat::Rgba8 ? 4 : 1;
    std::vector<std::uint8_t> out(n * bpp);
    for (std::size_t i = 0; i < n; ++i) {
        const float v = img.values[i];
        const std::uint8_t g = window_grey(v, w);
        if (bpp == 1) {
            out[i] = g;
        } else {
            const std::uint8_t a = std::isnan(v) ? 0 : 255;
            const std::uint8_t c = std::isnan(v) ? 0 : g;
            out[4 * i] = out[4 * i + 1] = out[4 * i + 2] = c;
            out[4 * i + 3] = a;
        }
    }
    return out;
}

// ---- Surface outlines ------------------------------------------------------------------

namespace {

// The segment of triangle t on the plane (distances d of its vertices), in
// the grid's pixels; false when the plane misses it.
bool triangle_segment(const Mesh& m, const std::array<std::uint32_t, 3>& tri, const double dd[3], const SliceGrid& g,
                      SliceSegment& s) {
    // Vertices on the plane (d == 0) and NaN count as above.
    const bool below[3] = {dd[0] < 0, dd[1] < 0, dd[2] < 0};
    const int nb = int(below[0]) + int(below[1]) + int(below[2]);
    if (nb == 0 || nb == 3) return false;
    // Walking the triangle's edges in winding order, one goes down through
    // the plane (above -> below) and one up: the segment runs from the down
    // crossing to the up crossing, so a neighbour (which walks the shared
    // edge the other way) starts where this ends.
    glm::dvec3 down{0.0}, up{0.0};
    for (int k = 0; k < 3; ++k) {
        const int k1 = (k + 1) % 3;
        if (below[k] == below[k1]) continue;
        const int lo = below[k] ? k : k1, hi = below[k] ? k1 : k;
        const glm::dvec3 p =
            crossing(m.positions[tri[std::size_t(lo)]], dd[lo], m.positions[tri[std::size_t(hi)]], dd[hi]);
        (below[k] ? up : down) = p;
    }
    const double s2 = g.pixel_mm * g.pixel_mm;
    const auto to_pixel = [&](const glm::dvec3& p) {
        const glm::dvec3 rel = p - g.corner;
        return glm::vec2(float(glm::dot(rel, g.dx) / s2), float(glm::dot(rel, g.dy) / s2));
    };
    s = SliceSegment{to_pixel(down), to_pixel(up)};
    return !(s.a == s.b || !std::isfinite(s.a.x) || !std::isfinite(s.a.y) || !std::isfinite(s.b.x) ||
             !std::isfinite(s.b.y));
}

// The outline from the blocks `take` keeps, kOutlineBlock triangles each.
template <class Take> std::vector<SliceSegment> outline_blocks(const Mesh& m, const SliceGrid& g, Take take) {
    const std::size_t nv = m.positions.size(), nt = m.triangles.size();
    const std::size_t blocks = (nt + kOutlineBlock - 1) / kOutlineBlock;
    std::vector<std::vector<SliceSegment>> parts(blocks);
    std::atomic<std::size_t> bad{std::numeric_limits<std::size_t>::max()};
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
        if (!take(b)) return;
        const std::size_t end = std::min(nt, (b + 1) * kOutlineBlock);
        for (std::size_t t = b * kOutlineBlock; t < end; ++t) {
            const auto& tri = m.triangles[t];
            if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) {
                atomic_min(bad, t);
                continue;
            }
            const double dd[3] = {glm::dot(glm::dvec3(m.positions[tri[0]]), g.normal) - g.offset_mm,
                                  glm::dot(glm::dvec3(m.positions[tri[1]]), g.normal) - g.offset_mm,
                                  glm::dot(glm::dvec3(m.positions[tri[2]]), g.normal) - g.offset_mm};
            SliceSegment s;
            if (triangle_segment(m, tri, dd, g, s)) parts[b].push_back(s);
        }
    });
    if (const std::size_t t = bad.load(); t != std::numeric_limits<std::size_t>::max())
        throw Error("slice outline", "triangle " + std::to_string(t) + " names a vertex beyond the mesh's " +
                                         std::to_string(nv) + " vertices");
    std::size_t total = 0;
    for (const auto& p : parts) total += p.size();
    std::vector<SliceSegment> out;
    out.reserve(total);
    for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
    return out;
}

} // namespace

std::vector<SliceSegment> mesh_outline(const Mesh& m, const SliceGrid& g) {
    return outline_blocks(m, g, [](std::size_t) { return true; });
}

OutlineIndex outline_index(const Mesh& m) {
    const std::size_t nv = m.positions.size(), nt = m.triangles.size();
    const std::size_t blocks = (nt + kOutlineBlock - 1) / kOutlineBlock;
    OutlineIndex index;
    index.lo.assign(blocks, glm::vec3(std::numeric_limits<float>::max()));
    index.hi.assign(blocks, glm::vec3(std::numeric_limits<float>::lowest()));
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
        const std::size_t end = std::min(nt, (b + 1) * kOutlineBlock);
        for (std::size_t t = b * kOutlineBlock; t < end; ++t)
            for (const std::uint32_t v : m.triangles[t])
                if (v < nv) {
                    index.lo[b] = glm::min(index.lo[b], m.positions[v]);
                    index.hi[b] = glm::max(index.hi[b], m.positions[v]);
                }
    });
    return index;
}

std::vector<SliceSegment> mesh_outline(const Mesh& m, const SliceGrid& g, const OutlineIndex& index) {
    if (index.lo.size() != (m.triangles.size() + kOutlineBlock - 1) / kOutlineBlock) return mesh_outline(m, g);
    const glm::dvec3 n = g.normal, an = glm::abs(n);
    return outline_blocks(m, g, [&](std::size_t b) {
        // The box's distances to the plane span centre +- half extent along |n|.
        const glm::dvec3 lo(index.lo[b]), hi(index.hi[b]);
        const double centre = glm::dot(0.5 * (lo + hi), n) - g.offset_mm, half = glm::dot(0.5 * (hi - lo), an);
        // A margin for rounding: a triangle touching the box's face still counts.
        const double margin = 1e-6 * (1.0 + std::abs(centre) + half);
        return !(centre - half > margin || centre + half < -margin);
    });
}

// ---- The planes in the 3D view ------------------------------------------------------

glm::vec3 slice_color(SliceOrientation o) {
    // vtkMRMLSliceNode's default colours (Red, Green, Yellow slice views).
    switch (o) {
    case SliceOrientation::Axial: return {0.952941f, 0.290196f, 0.2f};
    case SliceOrientation::Coronal: return {0.431373f, 0.690196f, 0.290196f};
    case SliceOrientation::Sagittal: return {0.929412f, 0.835294f, 0.298039f};
    }
    return {1.0f, 1.0f, 1.0f};
}

std::array<glm::dvec3, 8> volume_corners(const Volume& v) {
    std::array<glm::dvec3, 8> c{};
    for (int i = 0; i < 8; ++i)
        c[std::size_t(i)] =
            v.index_to_world({i & 1 ? double(v.dims[0]) - 0.5 : -0.5, i & 2 ? double(v.dims[1]) - 0.5 : -0.5,
                              i & 4 ? double(v.dims[2]) - 0.5 : -0.5});
    return c;
}

std::array<glm::dvec3, 8> box_corners(const std::pair<glm::dvec3, glm::dvec3>& b) {
    std::array<glm::dvec3, 8> c{};
    for (int i = 0; i < 8; ++i)
        c[std::size_t(i)] = {i & 1 ? b.second.x : b.first.x, i & 2 ? b.second.y : b.first.y,
                             i & 4 ? b.second.z : b.first.z};
    return c;
}

std::vector<glm::dvec3> plane_box_section(const std::array<glm::dvec3, 8>& corners, const glm::dvec3& normal,
                                          double offset_mm) {
    std::array<double, 8> d{};
    double size = 0;
    for (std::size_t i = 0; i < 8; ++i) {
        d[i] = glm::dot(corners[i], normal) - offset_mm;
        size = std::max(size, glm::length(corners[i] - corners[0]));
    }
    // Corners on the plane, then the edges (corners one bit apart) it crosses.
    std::vector<glm::dvec3> pts;
    for (std::size_t i = 0; i < 8; ++i)
        if (d[i] == 0.0) pts.push_back(corners[i]);
    for (std::size_t i = 0; i < 8; ++i)
        for (std::size_t bit = 1; bit < 8; bit <<= 1) {
            const std::size_t j = i | bit;
            if (j == i || !((d[i] < 0.0 && d[j] > 0.0) || (d[i] > 0.0 && d[j] < 0.0))) continue;
            const double t = d[i] / (d[i] - d[j]);
            glm::dvec3 p = corners[i] + t * (corners[j] - corners[i]);
            p -= (glm::dot(p, normal) - offset_mm) * normal; // onto the plane despite rounding
            pts.push_back(p);
        }
    // A corner where edges cross the plane next to it can come twice.
    const double eps = 1e-12 * std::max(size, 1.0);
    std::vector<glm::dvec3> unique;
    for (const auto& p : pts)
        if (std::none_of(unique.begin(), unique.end(), [&](const glm::dvec3& q) { return glm::length(p - q) <= eps; }))
            unique.push_back(p);
    if (unique.size() < 3) return {};
    // Counter-clockwise about the normal: by angle about the centroid.
    glm::dvec3 c(0.0);
    for (const auto& p : unique) c += p;
    c /= double(unique.size());
    const glm::dvec3 u = glm::normalize(unique[0] - c), w = glm::cross(normal, u);
    std::sort(unique.begin(), unique.end(), [&](const glm::dvec3& a, const glm::dvec3& b) {
        return std::atan2(glm::dot(a - c, w), glm::dot(a - c, u)) < std::atan2(glm::dot(b - c, w), glm::dot(b - c, u));
    });
    return unique;
}

std::vector<glm::dvec3> slice_outline_3d(const Volume& v, const SlicePlane& p) {
    if (v.voxel_count() <= 0) return {};
    return plane_box_section(volume_corners(v), p.normal, p.offset_mm());
}

glm::dvec3 crosshair_point(const std::array<SlicePlane, 3>& planes) {
    glm::dvec3 c(0.0);
    for (std::size_t i = 0; i < 3; ++i) c += glm::dot(planes[(i + 1) % 3].origin, planes[i].normal) * planes[i].normal;
    return c;
}

} // namespace iso::core
