// Slice views (renderer/core/slices.hpp): planes, reslicing, clicks, window
// and level, surface outlines. The volumes are sampled on an oblique,
// anisotropic grid (measure_phantoms.hpp: 0.7 x 1.0 x 1.3 mm, rotated 25
// degrees) from a field that is linear in LPS, so trilinear reslicing is
// exact and every pixel's expected value is the field at the pixel's LPS
// centre. The expected pixel positions come from the conventions written out
// here as patient directions, not from slice_grid; the expected values at a
// click from the core API (core::value_at on a Scene that opened the volume
// from a file).
#include "renderer/core/slices.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <random>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <openvdb/openvdb.h>

#include "io/error.hpp"
#include "io/sparse.hpp"
#include "io/volume_io.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/scene.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using namespace iso::core;
using namespace iso::test;

namespace {

// The oblique grid's centre: not round, far from the origin.
const glm::dvec3 kCentre(12.3, -45.6, 78.9);

// A field linear in LPS (about -120..220 on the phantom: float32 keeps 1e-5).
double field(const glm::dvec3& p) {
    return 50.0 + 2.0 * (p.x - kCentre.x) - 1.5 * (p.y - kCentre.y) + 0.75 * (p.z - kCentre.z);
}

Volume oblique_linear(std::array<std::int64_t, 3> dims = {40, 34, 28}) {
    return sample_field(dims, oblique_affine(dims, 1.0, kCentre), field);
}

// The conventions as patient directions in LPS (x left, y posterior, z superior):
// what lies to the image's right and what is up.
struct Convention {
    glm::dvec3 image_right, image_up;
};
Convention convention(SliceOrientation o) {
    const glm::dvec3 left(1, 0, 0), anterior(0, -1, 0), posterior(0, 1, 0), superior(0, 0, 1);
    switch (o) {
    case SliceOrientation::Axial: return {left, anterior};   // from the feet: patient's right on the image's left
    case SliceOrientation::Coronal: return {left, superior}; // from the front
    case SliceOrientation::Sagittal:
        return {posterior, superior}; // from the patient's left: anterior on the image's left
    }
    return {};
}

// The LPS centre of pixel (c, r) of a w x h image whose centre is `centre`.
glm::dvec3 expected_lps(SliceOrientation o, const glm::dvec3& centre, double s, int w, int h, double c, double r) {
    const Convention cv = convention(o);
    return centre + (c + 0.5 - 0.5 * w) * s * cv.image_right - (r + 0.5 - 0.5 * h) * s * cv.image_up;
}

// Continuous index of an LPS point, computed here.
glm::dvec3 index_of(const Volume& v, const glm::dvec3& p) {
    return glm::dvec3(glm::inverse(v.index_to_lps) * glm::dvec4(p, 1.0));
}

enum class Where { Outside, Rim, Interior, Edge };
// Interior: within the voxel centres' hull (the field is exact there); Rim:
// in the outer half voxel (values clamped); Outside; Edge: within 1e-6 voxel
// of a boundary, where rounding decides (not checked).
Where where(const Volume& v, const glm::dvec3& idx) {
    bool rim = false;
    for (int a = 0; a < 3; ++a) {
        const double n = double(v.dims[a]), x = idx[a];
        if (std::abs(x + 0.5) < 1e-6 || std::abs(x - (n - 0.5)) < 1e-6) return Where::Edge;
        if (x < -0.5 || x > n - 0.5) return Where::Outside;
        if (x < 0 || x > n - 1) rim = true;
    }
    return rim ? Where::Rim : Where::Interior;
}

// An axis-aligned box [lo, hi] as 8 vertices and 12 outward triangles.
Mesh box(glm::dvec3 lo, glm::dvec3 hi) { return test::box_mesh(lo, hi); }

// Follows b -> next a by exact equality; returns the loops' lengths (empty
// and `ok` false when an endpoint does not chain exactly once).
struct Loops {
    bool ok = true;
    std::vector<std::size_t> lengths;
};
Loops chain(const std::vector<SliceSegment>& s) {
    Loops out;
    auto key = [](glm::vec2 p) { return std::pair<float, float>(p.x, p.y); };
    std::map<std::pair<float, float>, std::size_t> starts;
    for (std::size_t i = 0; i < s.size(); ++i)
        if (!starts.emplace(key(s[i].a), i).second) out.ok = false; // two segments start at one point
    std::vector<bool> used(s.size(), false);
    for (std::size_t first = 0; first < s.size(); ++first) {
        if (used[first]) continue;
        std::size_t n = 0, i = first;
        while (!used[i]) {
            used[i] = true;
            ++n;
            const auto next = starts.find(key(s[i].b));
            if (next == starts.end()) {
                out.ok = false;
                return out;
            }
            i = next->second;
        }
        if (i != first) out.ok = false; // ran into another loop's middle
        out.lengths.push_back(n);
    }
    return out;
}

} // namespace

// ---- planes ------------------------------------------------------------------

TEST(SlicePlanes, DefaultPlanesFitTheObliqueVolumesBoundingBox) {
    const Volume v = oblique_linear();
    // The box of the voxels' extent, from the 8 corners, here.
    glm::dvec3 lo(1e300), hi(-1e300);
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 p = v.index_to_world(
            {c & 1 ? v.dims[0] - 0.5 : -0.5, c & 2 ? v.dims[1] - 0.5 : -0.5, c & 4 ? v.dims[2] - 0.5 : -0.5});
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const auto planes = default_planes(v);
    const glm::dvec2 fov[3] = {{hi.x - lo.x, hi.y - lo.y}, {hi.x - lo.x, hi.z - lo.z}, {hi.y - lo.y, hi.z - lo.z}};
    const char* names[3] = {"axial", "coronal", "sagittal"};
    for (int i = 0; i < 3; ++i) {
        const SlicePlane& p = planes[std::size_t(i)];
        EXPECT_STREQ(slice_orientation_name(p.orientation), names[i]);
        for (int a = 0; a < 3; ++a) {
            EXPECT_NEAR(p.origin[a], 0.5 * (lo[a] + hi[a]), 1e-9);
            EXPECT_NEAR(p.center[a], 0.5 * (lo[a] + hi[a]), 1e-9);
        }
        EXPECT_NEAR(p.fov_mm.x, fov[i].x, 1e-9) << names[i];
        EXPECT_NEAR(p.fov_mm.y, fov[i].y, 1e-9) << names[i];
        EXPECT_NEAR(p.pixel_mm, 0.7, 1e-12);
        const Convention cv = convention(p.orientation);
        EXPECT_EQ(p.right, cv.image_right);
        EXPECT_EQ(p.up, cv.image_up);
    }
    // The normals: offset_mm reads as the slice's LPS coordinate.
    EXPECT_EQ(planes[0].normal, glm::dvec3(0, 0, 1));
    EXPECT_EQ(planes[1].normal, glm::dvec3(0, 1, 0));
    EXPECT_EQ(planes[2].normal, glm::dvec3(1, 0, 0));
    EXPECT_NEAR(planes[0].offset_mm(), 0.5 * (lo.z + hi.z), 1e-9);
    EXPECT_THROW(default_planes(Volume{}), Error);
}

TEST(SlicePlanes, OneScrollStepIsOneVoxelAlongTheNormal) {
    // Axis-aligned: the spacing along each normal.
    const std::array<std::int64_t, 3> dims{8, 9, 10};
    const Volume straight = Volume::dense(dims, VoxelType::I16, make_affine({0.7, 1.0, 1.3}, {5, 6, 7}));
    const auto sp = default_planes(straight);
    EXPECT_NEAR(sp[0].step_mm, 1.3, 1e-12);
    EXPECT_NEAR(sp[1].step_mm, 1.0, 1e-12);
    EXPECT_NEAR(sp[2].step_mm, 0.7, 1e-12);
    // Oblique: one step changes the continuous index by exactly one voxel on some axis, and by no more on any.
    const Volume v = oblique_linear();
    for (auto p : default_planes(v)) {
        const glm::dvec3 i0 = index_of(v, p.origin);
        const double offset = p.offset_mm();
        scroll_slices(p, 1);
        EXPECT_NEAR(p.offset_mm() - offset, p.step_mm, 1e-9);
        const glm::dvec3 d = glm::abs(index_of(v, p.origin) - i0);
        EXPECT_NEAR(std::max({d.x, d.y, d.z}), 1.0, 1e-9) << slice_orientation_name(p.orientation);
        // The centre moves with it (no in-plane drift).
        EXPECT_NEAR(glm::dot(p.center - p.origin, p.normal), 0.0, 1e-9);
        scroll_slices(p, -3);
        EXPECT_NEAR(p.offset_mm() - offset, -2 * p.step_mm, 1e-9);
        set_offset(p, offset + 4.25);
        EXPECT_NEAR(p.offset_mm(), offset + 4.25, 1e-9);
        EXPECT_NEAR(glm::dot(p.center, p.normal), offset + 4.25, 1e-9);
    }
}

TEST(SlicePlanes, TheCrosshairMovesEveryPlaneThroughTheSamePoint) {
    const Volume v = oblique_linear();
    auto planes = default_planes(v);
    const auto before = planes;
    const glm::dvec3 pick = kCentre + glm::dvec3(3.3, -4.4, 5.5);
    set_crosshair(planes, pick);
    for (std::size_t i = 0; i < 3; ++i) {
        const SlicePlane& p = planes[i];
        EXPECT_EQ(p.origin, pick);
        EXPECT_NEAR(glm::dot(p.center - pick, p.normal), 0.0, 1e-9);
        // No pan: the centre keeps its in-plane coordinates.
        EXPECT_NEAR(glm::dot(p.center - before[i].center, p.right), 0.0, 1e-9);
        EXPECT_NEAR(glm::dot(p.center - before[i].center, p.up), 0.0, 1e-9);
        // The crosshair's pixel in each view is where the pick is, on the plane.
        const SliceGrid g = slice_grid(p, 300, 200);
        const SlicePoint sp = lps_to_pixel(g, pick);
        EXPECT_NEAR(sp.distance_mm, 0.0, 1e-9);
        const glm::dvec3 back = pixel_to_lps(g, sp.pixel);
        EXPECT_NEAR(glm::length(back - pick), 0.0, 1e-9);
    }
}

TEST(SlicePlanes, ZoomAndNativeSize) {
    SlicePlane p = default_planes(oblique_linear())[0];
    const auto n = native_size(p);
    EXPECT_EQ(n[0], int(std::ceil(p.fov_mm.x / 0.7 - 1e-9)));
    EXPECT_EQ(n[1], int(std::ceil(p.fov_mm.y / 0.7 - 1e-9)));
    zoom_to_fit(p, 512, 256);
    EXPECT_NEAR(p.pixel_mm, std::max(p.fov_mm.x / 512, p.fov_mm.y / 256), 1e-12);
    EXPECT_THROW(slice_grid(p, 0, 10), Error);
    EXPECT_THROW(slice_grid(p, 10, 20000), Error);
    SlicePlane bad = p;
    bad.pixel_mm = 0;
    EXPECT_THROW(slice_grid(bad, 10, 10), Error);
    bad = p;
    bad.up = bad.right;
    EXPECT_THROW(slice_grid(bad, 10, 10), Error);
}

// The letters at the view's edges: radiological for the LPS planes (the
// table of docs/slices.md, written out here), the nearest LPS axis for a
// plane turned in-plane, and opposite letters on opposite edges.
TEST(SliceAnnotations, EdgeLettersAreTheNearestPatientDirections) {
    const auto planes = default_planes(oblique_linear());
    // left, right, top, bottom
    const char* want[3][4] = {{"R", "L", "A", "P"}, {"R", "L", "S", "I"}, {"A", "P", "S", "I"}};
    const SliceEdge edges[4] = {SliceEdge::Left, SliceEdge::Right, SliceEdge::Top, SliceEdge::Bottom};
    for (std::size_t i = 0; i < 3; ++i)
        for (int e = 0; e < 4; ++e)
            EXPECT_EQ(slice_edge_letter(planes[i], edges[e]), want[i][e])
                << slice_orientation_name(planes[i].orientation) << " edge " << e;
    // An axial plane turned by t about S: right = (cos t, sin t, 0), up =
    // (sin t, -cos t, 0). At 30 degrees right is nearer L than P and up
    // nearer A; at 60 degrees right is nearer P and up nearer L.
    const char* turned[2][4] = {{"R", "L", "A", "P"}, {"A", "P", "L", "R"}};
    const double angles[2] = {30.0, 60.0};
    for (int k = 0; k < 2; ++k) {
        SlicePlane p = planes[0];
        const double t = angles[k] * std::numbers::pi / 180.0;
        p.right = {std::cos(t), std::sin(t), 0.0};
        p.up = {std::sin(t), -std::cos(t), 0.0};
        for (int e = 0; e < 4; ++e) EXPECT_EQ(slice_edge_letter(p, edges[e]), turned[k][e]) << angles[k] << " deg";
    }
    // A coronal plane tilted 20 degrees about L: up = S tilted towards P stays S.
    SlicePlane c = planes[1];
    const double t = 20.0 * std::numbers::pi / 180.0;
    c.up = {0.0, std::sin(t), std::cos(t)};
    EXPECT_EQ(slice_edge_letter(c, SliceEdge::Top), "S");
    EXPECT_EQ(slice_edge_letter(c, SliceEdge::Bottom), "I");
}

// The bar: the longest of 1, 2, 5 x 10^k mm not above a fifth of the view.
TEST(SliceAnnotations, ScaleBarIsARoundLengthNearAFifthOfTheView) {
    SlicePlane p;
    struct Case {
        double pixel_mm;
        int width;
        double want;
    };
    // A fifth of the width in mm: 0.2 * width * pixel_mm.
    const Case cases[] = {
        {1.0, 500, 100},  // exactly 100
        {0.5, 500, 50},   // exactly 50
        {0.7, 500, 50},   // 70 -> 50
        {0.9, 600, 100},  // 108 -> 100
        {0.3, 300, 10},   // 18 -> 10
        {0.45, 300, 20},  // 27 -> 20
        {0.01, 400, 0.5}, // 0.8 -> 0.5
        {3.0, 1000, 500}, // 600 -> 500
    };
    for (const auto& c : cases) {
        p.pixel_mm = c.pixel_mm;
        const double mm = slice_scale_bar_mm(p, c.width);
        EXPECT_NEAR(mm, c.want, 1e-9 * c.want) << c.pixel_mm << " mm/px, " << c.width << " px";
        // Between 2/5 of a fifth (1 -> 2 -> 5 -> 10 steps) and a fifth of the width.
        const double px = mm / c.pixel_mm;
        EXPECT_LE(px, 0.2 * c.width + 1e-9);
        EXPECT_GT(px, 0.08 * c.width);
    }
    p.pixel_mm = 0;
    EXPECT_EQ(slice_scale_bar_mm(p, 500), 0.0);
    p.pixel_mm = 1;
    EXPECT_EQ(slice_scale_bar_mm(p, 0), 0.0);
}

// The slider's slices: one per voxel along a grid axis, a scroll step apart,
// so one scroll step moves the nearest slice by one.
TEST(SlicePlanes, TheSliceRangeSpansTheVolumeOneStepPerSlice) {
    const std::array<std::int64_t, 3> dims{8, 9, 10};
    const glm::dvec3 origin(5, 6, 7), sp(0.7, 1.0, 1.3);
    const Volume v = Volume::dense(dims, VoxelType::I16, make_affine(sp, origin));
    const auto planes = default_planes(v);
    for (std::size_t i = 0; i < 3; ++i) {
        // The normals: z (axial), y (coronal), x (sagittal): the voxel centres along it.
        const int axis = i == 0 ? 2 : i == 1 ? 1 : 0;
        const SliceRange r = slice_range(v, planes[i]);
        EXPECT_EQ(r.count, int(dims[std::size_t(axis)]));
        EXPECT_NEAR(r.step_mm, sp[axis], 1e-12);
        EXPECT_NEAR(r.first_mm, origin[axis], 1e-9);
        SlicePlane p = planes[i];
        set_offset(p, origin[axis] + 3 * sp[axis]); // voxel 3's centre
        EXPECT_EQ(slice_index(r, p.offset_mm()), 3);
        scroll_slices(p, 1);
        EXPECT_EQ(slice_index(r, p.offset_mm()), 4);
        scroll_slices(p, -2);
        EXPECT_EQ(slice_index(r, p.offset_mm()), 2);
        // Clamped at both ends; half-way rounds up.
        EXPECT_EQ(slice_index(r, origin[axis] - 50), 0);
        EXPECT_EQ(slice_index(r, origin[axis] + 500), r.count - 1);
        EXPECT_EQ(slice_index(r, origin[axis] + 1.5 * sp[axis]), 2);
    }
    // The default plane of an even count lies half-way: each step still moves the index by one.
    SlicePlane a = planes[0]; // 10 slices: between 4 and 5
    const SliceRange r = slice_range(v, a);
    const int i0 = slice_index(r, a.offset_mm());
    EXPECT_EQ(i0, 5);
    for (int k = 1; k <= 3; ++k) {
        scroll_slices(a, -1);
        EXPECT_EQ(slice_index(r, a.offset_mm()), i0 - k);
    }
    // Oblique: the box's extent along the normal in steps.
    const Volume o = oblique_linear();
    for (const auto& p : default_planes(o)) {
        const SliceRange ro = slice_range(o, p);
        EXPECT_NEAR(ro.step_mm, p.step_mm, 1e-12);
        EXPECT_GE(ro.count, 2);
        EXPECT_EQ(slice_index(ro, p.offset_mm()), ro.count / 2) << slice_orientation_name(p.orientation);
    }
}

// Fit: the centre back on the volume's centre, on the same slice, zoomed to fit.
TEST(SlicePlanes, FitRecentresAndZoomsOnTheSameSlice) {
    const Volume v = oblique_linear();
    for (const auto& start : default_planes(v)) {
        SlicePlane p = start;
        scroll_slices(p, 3);
        pan_pixels(p, {40, -25});
        zoom_about(p, 300, 200, {10, 20}, 3.0);
        const double offset = p.offset_mm();
        const glm::dvec3 cross = p.origin;
        fit_view(p, v, 300, 200);
        EXPECT_NEAR(p.offset_mm(), offset, 1e-9);
        EXPECT_EQ(p.origin, cross);
        const glm::dvec3 want = start.center + 3 * start.step_mm * start.normal;
        EXPECT_NEAR(glm::length(p.center - want), 0.0, 1e-9) << slice_orientation_name(p.orientation);
        EXPECT_NEAR(p.pixel_mm, std::max(start.fov_mm.x / 300, start.fov_mm.y / 200), 1e-12);
    }
}

// Panning and zooming change the framing only: what the new grid maps a
// pixel to is checked against the old grid's LPS points (the drag's
// invariant: the content follows the pointer; a zoom keeps the point under
// the pointer), for each orientation of the oblique volume.
TEST(SlicePlanes, PanMovesTheContentWithThePointer) {
    const Volume v = oblique_linear();
    for (auto p : default_planes(v)) {
        zoom_to_fit(p, 300, 200);
        const double offset = p.offset_mm();
        const glm::dvec3 origin = p.origin;
        const SliceGrid before = slice_grid(p, 300, 200);
        const glm::dvec2 delta(17.25, -9.5); // right and up
        pan_pixels(p, delta);
        const SliceGrid after = slice_grid(p, 300, 200);
        for (const glm::dvec2& q : {glm::dvec2(0.5, 0.5), glm::dvec2(150, 100), glm::dvec2(299.5, 12.25)}) {
            // What was under q is now under q + delta.
            EXPECT_NEAR(glm::length(pixel_to_lps(after, q + delta) - pixel_to_lps(before, q)), 0.0, 1e-9)
                << slice_orientation_name(p.orientation);
        }
        // The slice and the crosshair stay.
        EXPECT_NEAR(p.offset_mm(), offset, 1e-12);
        EXPECT_EQ(p.origin, origin);
        EXPECT_EQ(p.pixel_mm, before.pixel_mm);
        // The crosshair's pixel moved by delta too.
        const auto c0 = lps_to_pixel(before, origin).pixel, c1 = lps_to_pixel(after, origin).pixel;
        EXPECT_NEAR(c1.x - c0.x, delta.x, 1e-9);
        EXPECT_NEAR(c1.y - c0.y, delta.y, 1e-9);
        // Nothing for a non-finite drag.
        const glm::dvec3 centre = p.center;
        pan_pixels(p, {NAN, 1.0});
        EXPECT_EQ(p.center, centre);
    }
}

TEST(SlicePlanes, ZoomKeepsThePointUnderThePointer) {
    const Volume v = oblique_linear();
    for (auto p : default_planes(v)) {
        const int w = 321, h = 240;
        zoom_to_fit(p, w, h);
        const double s = p.pixel_mm;
        const SliceGrid before = slice_grid(p, w, h);
        const glm::dvec2 fixed(40.5, 200.25);
        zoom_about(p, w, h, fixed, 2.5);
        EXPECT_NEAR(p.pixel_mm, s / 2.5, 1e-12);
        const SliceGrid after = slice_grid(p, w, h);
        EXPECT_NEAR(glm::length(pixel_to_lps(after, fixed) - pixel_to_lps(before, fixed)), 0.0, 1e-9);
        // Another pixel: 2.5 times closer to the fixed one (in before's pixels).
        const glm::dvec2 q(300, 10);
        const glm::dvec2 back = lps_to_pixel(before, pixel_to_lps(after, q)).pixel;
        EXPECT_NEAR(glm::length(back - (fixed + (q - fixed) / 2.5)), 0.0, 1e-9);
        EXPECT_NEAR(after.offset_mm, before.offset_mm, 1e-12);
        // Zooming out again restores the framing.
        zoom_about(p, w, h, fixed, 1 / 2.5);
        const SliceGrid again = slice_grid(p, w, h);
        EXPECT_NEAR(glm::length(again.corner - before.corner), 0.0, 1e-9);
        EXPECT_NEAR(again.pixel_mm, before.pixel_mm, 1e-12);
        // Clamped and refused factors.
        zoom_about(p, w, h, fixed, 1e12);
        EXPECT_EQ(p.pixel_mm, 1e-4);
        const double kept = p.pixel_mm;
        for (double bad : {0.0, -2.0, double(NAN), double(INFINITY)}) {
            zoom_about(p, w, h, fixed, bad);
            EXPECT_EQ(p.pixel_mm, kept);
        }
    }
    EXPECT_NEAR(drag_zoom_factor(100, 200), 2.0, 1e-12); // half the height up: twice as large
    EXPECT_NEAR(drag_zoom_factor(-100, 200), 0.5, 1e-12);
    EXPECT_EQ(drag_zoom_factor(0, 200), 1.0);
    EXPECT_EQ(drag_zoom_factor(10, 0), 1.0);
}

// ---- pixels <-> LPS ------------------------------------------------------------

TEST(SlicePixels, PixelsFollowTheRadiologicalConventionAndRoundTrip) {
    const Volume v = oblique_linear();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-20, 420);
    for (auto p : default_planes(v)) {
        set_crosshair(std::span<SlicePlane>(&p, 1), kCentre + glm::dvec3(1.1, 2.2, -3.3));
        p.center += 4.0 * p.right - 2.5 * p.up; // panned
        p.pixel_mm = 0.55;
        const int w = 401, h = 333;
        const SliceGrid g = slice_grid(p, w, h);
        for (int n = 0; n < 200; ++n) {
            const glm::dvec2 px(u(rng), u(rng));
            const glm::dvec3 lps = pixel_to_lps(g, px);
            const glm::dvec3 want = expected_lps(p.orientation, p.center, 0.55, w, h, px.x - 0.5, px.y - 0.5);
            ASSERT_NEAR(glm::length(lps - want), 0.0, 1e-9) << slice_orientation_name(p.orientation);
            EXPECT_NEAR(glm::dot(lps, p.normal), p.offset_mm(), 1e-9);
            const SlicePoint back = lps_to_pixel(g, lps);
            EXPECT_NEAR(back.pixel.x, px.x, 1e-9);
            EXPECT_NEAR(back.pixel.y, px.y, 1e-9);
            EXPECT_NEAR(back.distance_mm, 0.0, 1e-9);
            // Off the plane: the projection's pixel and the signed distance rebuild the point.
            const glm::dvec3 off = lps + 2.75 * p.normal;
            const SlicePoint o = lps_to_pixel(g, off);
            EXPECT_NEAR(o.distance_mm, 2.75, 1e-9);
            EXPECT_NEAR(glm::length(pixel_to_lps(g, o.pixel) + o.distance_mm * p.normal - off), 0.0, 1e-9);
        }
    }
}

TEST(SlicePixels, PatientLeftIsOnTheImagesRightInAxialAndCoronal) {
    // A ball at the patient's left, anterior and superior of the centre, on the oblique grid.
    const glm::dvec3 ball = kCentre + glm::dvec3(8, -7, 6);
    const std::array<std::int64_t, 3> dims{40, 34, 28};
    const Volume v = sample_field(dims, oblique_affine(dims, 1.0, kCentre),
                                  [&](const glm::dvec3& p) { return glm::length(p - ball) < 3.0 ? 1000.0 : 0.0; });
    auto planes = default_planes(v);
    set_crosshair(planes, ball);
    // Where the brightest pixel lies, relative to the image centre: (+1, +1) = right and up.
    auto quadrant = [&](const SlicePlane& p) {
        const SliceImage img = reslice(v, p, 101, 101, Interp::Nearest);
        double sx = 0, sy = 0, sw = 0;
        for (int r = 0; r < img.height; ++r)
            for (int c = 0; c < img.width; ++c)
                if (img.at(c, r) > 500) {
                    sx += c + 0.5 - 50.5;
                    sy += 50.5 - (r + 0.5);
                    sw += 1;
                }
        EXPECT_GT(sw, 10) << slice_orientation_name(p.orientation);
        return glm::ivec2(sx > 0 ? 1 : -1, sy > 0 ? 1 : -1);
    };
    for (auto& p : planes)
        p.center = kCentre + glm::dot(ball - kCentre, p.normal) * p.normal; // view centred on the grid
    EXPECT_EQ(quadrant(planes[0]), glm::ivec2(1, 1));                       // axial: left on the right, anterior up
    EXPECT_EQ(quadrant(planes[1]), glm::ivec2(1, 1));                       // coronal: left on the right, superior up
    EXPECT_EQ(quadrant(planes[2]), glm::ivec2(-1, 1)); // sagittal: anterior on the left, superior up
}

// The issue's check: the voxel under a slice-view click has the LPS position
// and HU the core API gives for it, on an oblique volume.
TEST(SlicePixels, AClickGivesTheCoreApisPointValueAndVoxel) {
    TempDir dir;
    const Volume original = oblique_linear();
    save_volume(original, dir / "oblique.nrrd");
    Scene scene;
    scene.open(dir / "oblique.nrrd");
    const Volume& v = scene.volume();
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) ASSERT_NEAR(v.index_to_lps[c][r], original.index_to_lps[c][r], 1e-9);
    std::mt19937 rng(11);
    int inside = 0;
    for (auto p : default_planes(v)) {
        set_crosshair(std::span<SlicePlane>(&p, 1), kCentre + glm::dvec3(-2.1, 1.7, 0.9));
        const int w = 256, h = 200;
        zoom_to_fit(p, w, h);
        const SliceGrid g = slice_grid(p, w, h);
        std::uniform_real_distribution<double> ux(0, w), uy(0, h);
        for (int n = 0; n < 300; ++n) {
            const glm::dvec2 click(ux(rng), uy(rng));
            const glm::dvec3 lps = pixel_to_lps(g, click);
            ASSERT_NEAR(glm::length(lps - expected_lps(p.orientation, p.center, p.pixel_mm, w, h, click.x - 0.5,
                                                       click.y - 0.5)),
                        0.0, 1e-9);
            const auto mine = sample_at_pixel(v, g, click);
            const auto core = value_at(scene, lps);
            ASSERT_EQ(mine.has_value(), core.has_value());
            if (!mine) {
                EXPECT_NE(where(v, index_of(v, lps)), Where::Interior);
                continue;
            }
            ++inside;
            EXPECT_EQ(mine->value, core->value);
            EXPECT_EQ(mine->voxel, core->voxel);
            EXPECT_EQ(mine->voxel_lps, core->voxel_lps);
            EXPECT_EQ(mine->voxel_value, core->voxel_value);
            // And what the field says: at the point (interior), at the voxel's centre.
            if (where(v, index_of(v, lps)) == Where::Interior) {
                EXPECT_NEAR(mine->value, field(lps), 1e-4);
            }
            EXPECT_NEAR(mine->voxel_value, field(mine->voxel_lps), 1e-4);
            // The voxel is the nearest one: its centre is within half a voxel on every axis.
            const glm::dvec3 d =
                glm::abs(index_of(v, lps) - glm::dvec3(mine->voxel[0], mine->voxel[1], mine->voxel[2]));
            EXPECT_LE(std::max({d.x, d.y, d.z}), 0.5 + 1e-9);
        }
    }
    EXPECT_GT(inside, 300); // of 900 clicks: the fitted view of an oblique grid has empty corners
}

// ---- reslicing ------------------------------------------------------------------------

TEST(SliceReslice, EveryPixelIsTheFieldAtItsCentreOnTheObliqueGrid) {
    const Volume v = oblique_linear();
    std::size_t interior = 0, rim = 0, outside = 0;
    for (auto p : default_planes(v)) {
        // Off-centre slices, so the plane cuts the oblique grid unevenly.
        set_crosshair(std::span<SlicePlane>(&p, 1), kCentre + glm::dvec3(2.3, -3.1, 4.7));
        p.pixel_mm = 0.45;
        const auto [w, h] = native_size(p);
        const SliceImage img = reslice(v, p, w + 10, h + 6, Interp::Linear);
        ASSERT_EQ(img.width, w + 10);
        ASSERT_EQ(img.height, h + 6);
        for (int r = 0; r < img.height; ++r)
            for (int c = 0; c < img.width; ++c) {
                const glm::dvec3 lps = expected_lps(p.orientation, p.center, 0.45, img.width, img.height, c, r);
                const glm::dvec3 idx = index_of(v, lps);
                const float got = img.at(c, r);
                switch (where(v, idx)) {
                case Where::Outside:
                    ++outside;
                    ASSERT_TRUE(std::isnan(got)) << c << "," << r;
                    break;
                case Where::Interior:
                    ++interior;
                    ASSERT_NEAR(got, field(lps), 1e-4) << slice_orientation_name(p.orientation) << " " << c << "," << r;
                    break;
                case Where::Rim: {
                    // The outer half voxel: the border samples extend as constants, i.e. the field at the clamped index.
                    ++rim;
                    const glm::dvec3 clamped =
                        glm::clamp(idx, glm::dvec3(0.0), glm::dvec3(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1));
                    ASSERT_NEAR(got, field(v.index_to_world(clamped)), 1e-4) << c << "," << r;
                    break;
                }
                case Where::Edge: break;
                }
            }
    }
    EXPECT_GT(interior, 10000u);
    EXPECT_GT(rim, 300u);
    EXPECT_GT(outside, 1000u);
}

TEST(SliceReslice, PixelsEqualSampleVolumeAtTheirCentresLinearAndNearest) {
    const Volume v = oblique_linear({23, 19, 17});
    for (auto p : default_planes(v)) {
        p.pixel_mm = 0.37;
        const int w = 97, h = 83;
        const SliceGrid g = slice_grid(p, w, h);
        SliceImage lin, near;
        reslice(v, g, Interp::Linear, lin);
        reslice(v, g, Interp::Nearest, near);
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) {
                const auto s = sample_volume(v, pixel_to_lps(g, {c + 0.5, r + 0.5}));
                if (!s) {
                    EXPECT_TRUE(std::isnan(lin.at(c, r)) && std::isnan(near.at(c, r)));
                    continue;
                }
                EXPECT_NEAR(lin.at(c, r), s->value, 1e-4);
                EXPECT_EQ(near.at(c, r), float(s->voxel_value));
            }
    }
}

// reslice_here (the GUI thread's: no worker) gives reslice's pixels, bit for
// bit (NaN where it has NaN), on a grid large enough to split into tasks.
TEST(SliceReslice, OnTheCallingThreadAloneItIsTheSameSlice) {
    const Volume v = oblique_linear({23, 19, 17});
    for (auto p : default_planes(v)) {
        p.pixel_mm = 0.11;
        const SliceGrid g = slice_grid(p, 301, 257);
        SliceImage everywhere, here;
        reslice(v, g, Interp::Linear, everywhere);
        reslice_here(v, g, Interp::Linear, here);
        ASSERT_EQ(here.width, everywhere.width);
        ASSERT_EQ(here.height, everywhere.height);
        ASSERT_EQ(here.values.size(), everywhere.values.size());
        std::size_t nan = 0;
        for (std::size_t i = 0; i < here.values.size(); ++i) {
            const float a = everywhere.values[i], b = here.values[i];
            nan += std::isnan(a);
            EXPECT_TRUE(std::isnan(a) ? std::isnan(b) : a == b) << i;
        }
        EXPECT_LT(nan, here.values.size()); // the slice crosses the volume
    }
}

TEST(SliceReslice, ShearedGridsAndEveryVoxelType) {
    // A gantry-tilted grid: the slice step has a y component (shear), spacing anisotropic.
    glm::dmat4 a(1.0);
    a[0] = {0.6, 0.0, 0.0, 0.0};
    a[1] = {0.0, 0.8, 0.0, 0.0};
    a[2] = {0.0, 0.9, 2.0, 0.0}; // 24 degree tilt
    a[3] = {-5.0, 3.0, 11.0, 1.0};
    const std::array<std::int64_t, 3> dims{21, 18, 9};
    for (VoxelType t :
         {VoxelType::U8, VoxelType::I16, VoxelType::U16, VoxelType::I32, VoxelType::F32, VoxelType::F64}) {
        Volume v = Volume::dense(dims, t, a);
        // Integer-valued linear field in the index (so every type stores it exactly).
        dispatch_voxel_type(t, [&](auto z) {
            using T = decltype(z);
            auto s = v.as<T>();
            for (std::int64_t k = 0; k < dims[2]; ++k)
                for (std::int64_t j = 0; j < dims[1]; ++j)
                    for (std::int64_t i = 0; i < dims[0]; ++i) s[v.linear_index(i, j, k)] = T(i + 2 * j + 3 * k);
        });
        for (auto p : default_planes(v)) {
            const auto [w, h] = native_size(p);
            const SliceGrid g = slice_grid(p, w, h);
            SliceImage img;
            reslice(v, g, Interp::Linear, img);
            int checked = 0;
            for (int r = 0; r < h; ++r)
                for (int c = 0; c < w; ++c) {
                    const glm::dvec3 idx = index_of(v, pixel_to_lps(g, {c + 0.5, r + 0.5}));
                    const Where at = where(v, idx);
                    if (at == Where::Outside) {
                        ASSERT_TRUE(std::isnan(img.at(c, r)));
                    }
                    if (at != Where::Interior) continue;
                    ASSERT_NEAR(img.at(c, r), idx.x + 2 * idx.y + 3 * idx.z, 1e-4) << voxel_type_name(t);
                    ++checked;
                }
            EXPECT_GT(checked, 100) << voxel_type_name(t) << " " << slice_orientation_name(p.orientation);
        }
    }
}

TEST(SliceReslice, NanVoxelsSpreadOnlyWhereTheyHaveWeight) {
    // As sample_volume: a NaN neighbour with zero weight does not spread.
    const std::array<std::int64_t, 3> dims{4, 4, 4};
    Volume v = Volume::dense(dims, VoxelType::F32, make_affine({1, 1, 1}, {0, 0, 0}));
    for (auto& x : v.as<float>()) x = 10.0f;
    v.as<float>()[v.linear_index(2, 1, 1)] = NAN;
    SlicePlane p = default_planes(v)[0];
    set_offset(p, 1.0); // the plane k = 1 exactly: z weight 0
    p.pixel_mm = 0.5;
    p.center = {1.75, 1.75, 1.0};
    const SliceGrid g = slice_grid(p, 8, 8); // pixel centres at x, y = 0, 0.5, ..., 3.5
    const SliceImage img = reslice(v, p, 8, 8);
    for (int r = 0; r < 8; ++r)
        for (int c = 0; c < 8; ++c) {
            const auto s = sample_volume(v, pixel_to_lps(g, {c + 0.5, r + 0.5}));
            ASSERT_TRUE(s);
            if (std::isnan(s->value)) {
                EXPECT_TRUE(std::isnan(img.at(c, r))) << c << "," << r;
            } else {
                EXPECT_EQ(img.at(c, r), float(s->value)) << c << "," << r;
            }
        }
    // The NaN voxel's own centre and the pixels between it and its neighbours are NaN; one voxel away is not.
    EXPECT_TRUE(std::isnan(img.at(4, 2))); // (2, 1)
    EXPECT_TRUE(std::isnan(img.at(5, 2))); // (2.5, 1)
    EXPECT_EQ(img.at(6, 2), 10.0f);        // (3, 1): the NaN has weight 0
    EXPECT_EQ(img.at(2, 2), 10.0f);        // (1, 1)
}

TEST(SliceReslice, SparseVolumesResliceAsDense) {
    const Volume dense = oblique_linear({15, 13, 11});
    auto grid = openvdb::FloatGrid::create(-1000.0f);
    auto acc = grid->getAccessor();
    const openvdb::Coord offset(100, -50, 7);
    for (int k = 0; k < 11; ++k)
        for (int j = 0; j < 13; ++j)
            for (int i = 0; i < 15; ++i) acc.setValue(openvdb::Coord(i, j, k) + offset, float(dense.value(i, j, k)));
    auto sg = std::make_shared<SparseGrid>();
    sg->grid = grid;
    sg->offset = offset;
    const Volume sparse = Volume::sparse(sg, dense.dims, dense.index_to_lps);
    for (auto p : default_planes(dense)) {
        p.pixel_mm = 0.4;
        for (Interp interp : {Interp::Linear, Interp::Nearest}) {
            const SliceImage a = reslice(dense, p, 70, 60, interp), b = reslice(sparse, p, 70, 60, interp);
            for (std::size_t i = 0; i < a.values.size(); ++i) {
                if (std::isnan(a.values[i])) {
                    EXPECT_TRUE(std::isnan(b.values[i]));
                } else {
                    EXPECT_NEAR(a.values[i], b.values[i], 1e-4);
                }
            }
        }
    }
}

// ---- window / level --------------------------------------------------------------------------

TEST(SliceWindow, EndsOfTheWindowAreBlackAndWhite) {
    for (const WindowLevel w : {WindowLevel{40, 400}, WindowLevel{-600, 1500}, WindowLevel{0.5, 0.25}}) {
        EXPECT_EQ(window_grey(w.center - w.width / 2, w), 0);
        EXPECT_EQ(window_grey(w.center + w.width / 2, w), 255);
        EXPECT_EQ(window_grey(w.center - w.width, w), 0);
        EXPECT_EQ(window_grey(w.center + w.width, w), 255);
        EXPECT_EQ(window_grey(w.center, w), 128); // 127.5 rounds up
        EXPECT_EQ(window_grey(w.center - w.width / 2 + w.width / 255.0, w), 1);
        EXPECT_EQ(window_grey(w.center + w.width / 4, w), 191); // 191.25
    }
    EXPECT_EQ(window_grey(NAN, {40, 400}), 0);
    EXPECT_EQ(window_grey(39.9, {40, 0}), 0); // zero width: a threshold
    EXPECT_EQ(window_grey(40, {40, 0}), 255);

    SliceImage img{3, 1, {-160.0f, NAN, 240.0f}};
    EXPECT_EQ(apply_window(img, {40, 400}), (std::vector<std::uint8_t>{0, 0, 255}));
    EXPECT_EQ(apply_window(img, {40, 400}, PixelFormat::Rgba8),
              (std::vector<std::uint8_t>{0, 0, 0, 255, 0, 0, 0, 0, 255, 255, 255, 255}));
}

TEST(SliceWindow, PresetsAndDefaults) {
    ASSERT_EQ(ct_window_presets().size(), 5u);
    auto is = [](std::string_view name, double c, double w) {
        const auto p = ct_window_preset(name);
        ASSERT_TRUE(p) << name;
        EXPECT_EQ(p->center, c) << name;
        EXPECT_EQ(p->width, w) << name;
    };
    is("brain", 40, 80);
    is("soft tissue", 40, 400);
    is("lung", -600, 1500);
    is("bone", 400, 1800);
    is("angio", 170, 600);
    EXPECT_FALSE(ct_window_preset("liver"));

    Volume v = oblique_linear({9, 8, 7});
    const ValueRange r = v.value_range();
    WindowLevel w = default_window(v);
    EXPECT_NEAR(w.center, 0.5 * (r.min + r.max), 1e-9);
    EXPECT_NEAR(w.width, r.max - r.min, 1e-9);
    v.meta.modality = "CT";
    w = default_window(v);
    EXPECT_EQ(w.center, 40);
    EXPECT_EQ(w.width, 400);
    w = default_window("MR", ValueRange{5, 5});
    EXPECT_EQ(w.center, 5);
    EXPECT_EQ(w.width, 1);
}

// Slicer's window/level drag: (range high - low) / 500 per pixel, right
// widens the window, up raises the level; the width never goes negative.
TEST(SliceWindow, DragChangesWidthHorizontallyAndLevelVertically) {
    const ValueRange r{-1000, 1500}; // 5 per pixel
    const WindowLevel start{40, 400};
    WindowLevel w = drag_window(start, {10, 0}, r);
    EXPECT_DOUBLE_EQ(w.width, 450);
    EXPECT_DOUBLE_EQ(w.center, 40);
    w = drag_window(start, {0, -4}, r);
    EXPECT_DOUBLE_EQ(w.width, 400);
    EXPECT_DOUBLE_EQ(w.center, 20);
    w = drag_window(start, {-200, 3}, r);
    EXPECT_EQ(w.width, 0);
    EXPECT_DOUBLE_EQ(w.center, 55);
    w = drag_window(start, {500, 0}, ValueRange{7, 7}); // flat: 1/500 per pixel
    EXPECT_DOUBLE_EQ(w.width, 401);
    w = drag_window(start, {NAN, 0}, r);
    EXPECT_EQ(w.width, start.width);
}

// ---- outlines -------------------------------------------------------------------------------

TEST(SliceOutline, ASpheresOutlineThroughItsCentreIsOneClosedLoopAtItsRadius) {
    const glm::dvec3 c(10.25, -20.5, 30.75); // float-exact: the equator's vertices lie exactly on the plane
    const double R = 25.0;
    const Mesh sphere = uv_sphere(c, R, 40, 72);
    double longest = 0; // the longest edge: the chord error bound
    for (const auto& t : sphere.triangles)
        for (int k = 0; k < 3; ++k)
            longest = std::max(longest, glm::length(glm::dvec3(sphere.positions[t[k]]) -
                                                    glm::dvec3(sphere.positions[t[(k + 1) % 3]])));
    const double inner = std::sqrt(R * R - 0.25 * longest * longest) - 1e-4;

    for (const double h : {0.0, 0.37 * R, -0.81 * R}) {
        SlicePlane p;
        p.orientation = SliceOrientation::Axial;
        p.right = {1, 0, 0};
        p.up = {0, -1, 0};
        p.normal = {0, 0, 1};
        p.origin = p.center = c + glm::dvec3(0, 0, h);
        p.pixel_mm = 0.25;
        const SliceGrid g = slice_grid(p, 256, 256);
        const auto segs = mesh_outline(sphere, g);
        ASSERT_FALSE(segs.empty());
        double area = 0; // shoelace in LPS (x, y), about the normal +z
        for (const auto& s : segs) {
            for (const glm::vec2& e : {s.a, s.b}) {
                const glm::dvec3 q = pixel_to_lps(g, glm::dvec2(e));
                const double d = glm::length(q - c);
                EXPECT_LE(d, R + 1e-4);
                EXPECT_GE(d, inner);
                EXPECT_NEAR(q.z, c.z + h, 1e-9);
            }
            const glm::dvec3 a = pixel_to_lps(g, glm::dvec2(s.a)) - c, b = pixel_to_lps(g, glm::dvec2(s.b)) - c;
            area += 0.5 * (a.x * b.y - a.y * b.x);
        }
        const Loops loops = chain(segs);
        EXPECT_TRUE(loops.ok) << "h = " << h;
        ASSERT_EQ(loops.lengths.size(), 1u) << "h = " << h;
        EXPECT_EQ(loops.lengths[0], segs.size());
        // Counter-clockwise about the normal around the solid, and about the circle's area.
        const double rr = R * R - h * h;
        EXPECT_GT(area, 0);
        EXPECT_NEAR(area, std::numbers::pi * rr, 0.02 * std::numbers::pi * rr) << "h = " << h;
    }
    // The equator plane: 72 segments along the 72 equator edges (their vertices are on the plane).
    SlicePlane p = default_planes(Volume::dense({2, 2, 2}, VoxelType::U8, make_affine({1, 1, 1}, {0, 0, 0})))[0];
    p.origin = p.center = c;
    EXPECT_EQ(mesh_outline(sphere, slice_grid(p, 64, 64)).size(), 72u);
}

// The outline index skips the blocks of triangles a plane misses and gives
// the same segments, in the same order, as the whole mesh: spheres far
// apart (each its own blocks) cut by planes through one, both, none, on a
// block's face and along every axis, oblique too.
TEST(SliceOutline, TheIndexGivesTheSameSegmentsAsTheWholeMesh) {
    Mesh m;
    for (int k = 0; k < 6; ++k) {
        const Mesh s = uv_sphere(glm::dvec3(60.0 * k, 7.0 * k, -3.0 * k), 12.0 + k, 60, 90);
        const auto base = std::uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), s.positions.begin(), s.positions.end());
        for (auto t : s.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    ASSERT_GT(m.triangles.size(), 4 * kOutlineBlock);
    const OutlineIndex index = outline_index(m);
    ASSERT_EQ(index.lo.size(), (m.triangles.size() + kOutlineBlock - 1) / kOutlineBlock);
    std::size_t compared = 0;
    for (const glm::dvec3& n :
         {glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::normalize(glm::dvec3(1, 0.3, 0.2))})
        for (const double offset : {-100.0, 0.0, 12.0, 60.0, 125.5, 301.0, double(index.hi[0].x)}) {
            SlicePlane p;
            p.normal = n;
            p.right = glm::normalize(glm::cross(std::abs(n.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0), n));
            p.up = glm::cross(n, p.right);
            p.origin = p.center = n * offset;
            p.pixel_mm = 0.5;
            const SliceGrid g = slice_grid(p, 512, 512);
            const auto all = mesh_outline(m, g), fast = mesh_outline(m, g, index);
            ASSERT_EQ(all.size(), fast.size()) << "offset " << offset;
            for (std::size_t i = 0; i < all.size(); ++i) {
                EXPECT_EQ(all[i].a, fast[i].a);
                EXPECT_EQ(all[i].b, fast[i].b);
            }
            compared += all.size();
        }
    EXPECT_GT(compared, 1000u);
}

TEST(SliceOutline, FacesInThePlaneAndDegenerateTriangles) {
    const Mesh cube = box({0, 0, 0}, {2, 2, 2});
    SlicePlane p;
    p.pixel_mm = 0.5;
    p.origin = p.center = {1, 1, 2}; // the top face
    auto top = mesh_outline(cube, slice_grid(p, 16, 16));
    // A vertex on the plane counts as above: the solid is below, so its top face's border is drawn, once.
    Loops loops = chain(top);
    EXPECT_TRUE(loops.ok);
    ASSERT_EQ(loops.lengths.size(), 1u);
    double length = 0;
    for (const auto& s : top) length += glm::length(s.b - s.a) * 0.5;
    EXPECT_NEAR(length, 8.0, 1e-5);  // the square's perimeter
    p.origin = p.center = {1, 1, 0}; // the bottom face: the solid is above, nothing crosses
    EXPECT_TRUE(mesh_outline(cube, slice_grid(p, 16, 16)).empty());
    p.origin = p.center = {1, 1, 1};
    loops = chain(mesh_outline(cube, slice_grid(p, 16, 16)));
    EXPECT_TRUE(loops.ok);
    EXPECT_EQ(loops.lengths.size(), 1u);

    // Crossing the plane z = 1: a zero-area triangle (two equal vertices, on the plane) gives a
    // zero-length segment, dropped; a proper triangle with an edge in the plane gives that edge.
    Mesh m;
    m.positions = {{0, 0, -1}, {1, 0, 1}, {1, 0, 1}, {2, 0, 1}};
    m.triangles = {{0, 1, 2}, {0, 1, 3}};
    const auto segs = mesh_outline(m, slice_grid(p, 16, 16));
    EXPECT_EQ(segs.size(), 1u);
    // Nothing to intersect, or a broken index.
    EXPECT_TRUE(mesh_outline(Mesh{}, slice_grid(p, 16, 16)).empty());
    m.triangles.push_back({0, 1, 9});
    try {
        mesh_outline(m, slice_grid(p, 16, 16));
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), "slice outline");
        EXPECT_NE(e.reason().find("triangle 2"), std::string::npos) << e.reason();
    }
}

// The parallel path (blocks of 32768 triangles) on a large mesh: the
// segments still chain into closed loops (tests/bench/slices_bench.cpp times it).
TEST(SliceOutline, AMillionTrianglesChainIntoClosedLoops) {
    const Mesh sphere = uv_sphere({1, 2, 3}, 80, 640, 1024); // 1.31 M triangles
    SlicePlane p;
    p.origin = p.center = {1, 2, 3.3};
    p.pixel_mm = 0.35;
    const SliceGrid g = slice_grid(p, 512, 512);
    EXPECT_TRUE(chain(mesh_outline(sphere, g)).ok);
}

// ---- the planes in the 3D view -------------------------------------------------------

namespace {

// The corners of the axis-aligned box [lo, hi] in volume_corners' order.
std::array<glm::dvec3, 8> box_corners(glm::dvec3 lo, glm::dvec3 hi) {
    std::array<glm::dvec3, 8> c{};
    for (int i = 0; i < 8; ++i) c[std::size_t(i)] = {i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z};
    return c;
}

// `got` is `want` as a cycle (same vertices in the same cyclic order, any start).
void expect_same_cycle(const std::vector<glm::dvec3>& got, const std::vector<glm::dvec3>& want, double tol) {
    ASSERT_EQ(got.size(), want.size());
    std::size_t start = 0;
    while (start < got.size() && glm::length(got[start] - want[0]) > tol) ++start;
    ASSERT_LT(start, got.size()) << "the first expected vertex is missing";
    for (std::size_t i = 0; i < want.size(); ++i)
        EXPECT_LT(glm::length(got[(start + i) % got.size()] - want[i]), tol) << "vertex " << i;
}

// Convex and counter-clockwise about `n`: every turn is to the left.
void expect_convex_ccw(const std::vector<glm::dvec3>& poly, const glm::dvec3& n) {
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % poly.size()];
        const auto& c = poly[(i + 2) % poly.size()];
        EXPECT_GT(glm::dot(glm::cross(b - a, c - b), n), 0.0) << "turn at vertex " << (i + 1) % poly.size();
    }
}

} // namespace

// An axial plane through a box: the rectangle of the box's x and y extent at
// the plane's z, counter-clockwise seen from above (+z).
TEST(SliceOutline3d, AnAxialPlaneGivesTheBoxsRectangleAtItsHeight) {
    const auto c = box_corners({-5, -10, 0}, {15, 30, 60});
    const auto poly = plane_box_section(c, {0, 0, 1}, 20.0);
    expect_same_cycle(poly, {{-5, -10, 20}, {15, -10, 20}, {15, 30, 20}, {-5, 30, 20}}, 1e-12);
    // A face of the box is the face; a plane beside the box gives nothing.
    EXPECT_EQ(plane_box_section(c, {0, 0, 1}, 60.0).size(), 4u);
    EXPECT_TRUE(plane_box_section(c, {0, 0, 1}, 60.5).empty());
    EXPECT_TRUE(plane_box_section(c, {0, 0, 1}, -1.0).empty());
}

// The unit cube cut by x + y + z = k: a regular hexagon at k = 1.5 (the
// midpoints of the six edges the plane crosses), a triangle at k = 0.5
// (the three edges at the origin, halfway), nothing at k = 0 (one corner).
TEST(SliceOutline3d, ObliquePlanesThroughTheUnitCube) {
    const auto c = box_corners({0, 0, 0}, {1, 1, 1});
    const glm::dvec3 n = glm::normalize(glm::dvec3(1, 1, 1));
    const auto hex = plane_box_section(c, n, 1.5 / std::sqrt(3.0));
    expect_same_cycle(hex, {{1, 0.5, 0}, {0.5, 1, 0}, {0, 1, 0.5}, {0, 0.5, 1}, {0.5, 0, 1}, {1, 0, 0.5}}, 1e-12);
    expect_convex_ccw(hex, n);
    const auto tri = plane_box_section(c, n, 0.5 / std::sqrt(3.0));
    expect_same_cycle(tri, {{0.5, 0, 0}, {0, 0.5, 0}, {0, 0, 0.5}}, 1e-12);
    EXPECT_TRUE(plane_box_section(c, n, 0.0).empty());
    // Through two opposite edges: the diagonal rectangle (corners on the plane count once).
    const glm::dvec3 d = glm::normalize(glm::dvec3(1, -1, 0));
    const auto diagonal = plane_box_section(c, d, 0.0);
    expect_same_cycle(diagonal, {{0, 0, 0}, {1, 1, 0}, {1, 1, 1}, {0, 0, 1}}, 1e-12);
    expect_convex_ccw(diagonal, d);
}

// Random planes through a sheared, rotated box (an oblique volume's):
// 3 to 6 vertices, each on the plane and on the box's surface (one of its
// box coordinates at 0 or 1), the polygon convex and counter-clockwise.
TEST(SliceOutline3d, RandomPlanesThroughAnObliqueVolumesBox) {
    const Volume v = oblique_linear({12, 9, 7});
    const auto c = volume_corners(v);
    // The box coordinates: c[0] + E * t, t in [0, 1]^3, E's columns the three edges from corner 0.
    const glm::dmat3 e(c[1] - c[0], c[2] - c[0], c[4] - c[0]);
    const glm::dmat3 inv = glm::inverse(e);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0), t(0.05, 0.95);
    int seen[7] = {};
    for (int k = 0; k < 400; ++k) {
        const glm::dvec3 n = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
        const glm::dvec3 through = c[0] + e * glm::dvec3(t(rng), t(rng), t(rng)); // inside the box
        const auto poly = plane_box_section(c, n, glm::dot(through, n));
        ASSERT_GE(poly.size(), 3u);
        ASSERT_LE(poly.size(), 6u);
        ++seen[poly.size()];
        for (const auto& p : poly) {
            EXPECT_NEAR(glm::dot(p, n), glm::dot(through, n), 1e-9);
            const glm::dvec3 b = inv * (p - c[0]);
            double face = 1.0;
            for (int a = 0; a < 3; ++a) {
                EXPECT_GE(b[a], -1e-9);
                EXPECT_LE(b[a], 1.0 + 1e-9);
                face = std::min({face, std::abs(b[a]), std::abs(b[a] - 1.0)});
            }
            EXPECT_LT(face, 1e-9) << "a vertex inside the box, not on its surface";
        }
        expect_convex_ccw(poly, n);
    }
    EXPECT_GT(seen[3] + seen[4] + seen[5] + seen[6], 0);
    EXPECT_GT(seen[6], 0) << "no hexagon in 400 random planes";
}

// A view's outline is its plane through the volume's box, the box of the
// voxels' extent (index -0.5 .. n - 0.5); it follows the plane as it scrolls.
TEST(SliceOutline3d, TheAxialViewsOutlineFollowsItsSlice) {
    const Volume v =
        Volume::dense({10, 20, 30}, VoxelType::F32, make_affine({0.5, 1.0, 2.0}, {-3.0, 4.0, 5.0}, glm::dmat3(1.0)));
    auto planes = default_planes(v);
    SlicePlane& axial = planes[0];
    scroll_slices(axial, 3);
    const double z = axial.offset_mm();
    EXPECT_NEAR(z, 5.0 + (29.0 / 2.0 + 3.0) * 2.0, 1e-9);
    const double x0 = -3.0 - 0.25, x1 = -3.0 + 9.5 * 0.5, y0 = 4.0 - 0.5, y1 = 4.0 + 19.5;
    expect_same_cycle(slice_outline_3d(v, axial), {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}}, 1e-9);
}

// Where the three views' crosshairs meet: the shared point after
// set_crosshair, still that point when one view kept its slice.
TEST(SliceOutline3d, TheCrosshairPointIsWhereTheViewsMarkIt) {
    const Volume v = oblique_linear();
    auto planes = default_planes(v);
    const glm::dvec3 pick = kCentre + glm::dvec3(3.3, -4.4, 5.5);
    set_crosshair(planes, pick);
    EXPECT_LT(glm::length(crosshair_point(planes) - pick), 1e-12);
    set_offset(planes[1], planes[1].offset_mm() + 7.0); // the coronal view kept another slice
    EXPECT_LT(glm::length(crosshair_point(planes) - pick), 1e-12);
    // Slicer's colours: axial red, coronal green, sagittal yellow.
    EXPECT_NEAR(slice_color(SliceOrientation::Axial).r, 243.0 / 255.0, 1e-3);
    EXPECT_NEAR(slice_color(SliceOrientation::Coronal).g, 176.0 / 255.0, 1e-3);
    EXPECT_NEAR(slice_color(SliceOrientation::Sagittal).g, 213.0 / 255.0, 1e-3);
}
