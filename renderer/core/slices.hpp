// The slice views' headless half (docs/slices.md): axial, coronal
// and sagittal planes in LPS through a shared crosshair, the volume resliced
// on them (oblique, anisotropic and sheared grids exactly), window/level to
// 8-bit grey, pixel <-> LPS both ways with the value under a click, and the
// outlines of surfaces on a slice. The GUI draws what these return and owns
// no geometry of its own.
//
// Orientation follows 3D Slicer's slice views (vtkMRMLSliceNode's
// SetOrientationToAxial/Coronal/Sagittal, radiological convention):
//   axial    viewed from the feet:          image right = patient left (L), image up = anterior (A)
//   coronal  viewed from the front:         image right = patient left (L), image up = superior (S)
//   sagittal viewed from the patient's left: image right = posterior (P),   image up = superior (S)
// Pixels: column c from the left, row r from the top; continuous pixel
// coordinates put pixel (c, r)'s centre at (c + 0.5, r + 0.5), as a mouse
// position in a widget of the image's size does.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "renderer/surface/analysis.hpp"

namespace iso::core {

class Scene;

// ---- Planes ------------------------------------------------------------------

enum class SliceOrientation : std::uint8_t { Axial, Coronal, Sagittal };
const char* slice_orientation_name(SliceOrientation o); // "axial", "coronal", "sagittal"

// One slice view's plane and framing, all in LPS mm.
struct SlicePlane {
    SliceOrientation orientation = SliceOrientation::Axial;
    // The crosshair: the point the three views share (a 3D pick moves it).
    // It lies on the plane.
    glm::dvec3 origin{0.0};
    // The point shown at the image's centre (panning moves it); on the plane.
    glm::dvec3 center{0.0};
    // Unit in-plane axes: image right (columns) and image up (against rows).
    glm::dvec3 right{1.0, 0.0, 0.0};
    glm::dvec3 up{0.0, -1.0, 0.0};
    // Unit normal, the direction the offset grows: LPS +z (S) for axial, +y
    // (P) for coronal, +x (L) for sagittal, so offset_mm() reads as the LPS
    // coordinate of the slice.
    glm::dvec3 normal{0.0, 0.0, 1.0};
    // The region the view fits by default (default_planes: the volume's
    // bounding box); zoom_to_fit uses it.
    glm::dvec2 fov_mm{0.0};
    // The size of one image pixel: authoritative for every image of the
    // plane (a wider image shows more at the same scale). Zooming changes it.
    double pixel_mm = 1.0;
    // One slice step (scroll_slices): one voxel along the normal (slice_step_mm).
    double step_mm = 1.0;

    // The plane's signed position along its normal: dot(origin, normal).
    double offset_mm() const;
    bool operator==(const SlicePlane&) const = default;
};

// The plane of one orientation for `v`: origin and centre at the centre of
// the volume's LPS bounding box (the box of the voxels' extent, index
// -0.5 .. n - 0.5, so oblique grids are boxed by their corners), fov the
// box's extent along right and up, pixel_mm the smallest voxel spacing,
// step_mm one voxel along the normal. Throws iso::Error("slice views", ...)
// for an empty volume.
SlicePlane default_plane(const Volume& v, SliceOrientation o);
std::array<SlicePlane, 3> default_planes(const Volume& v); // axial, coronal, sagittal

// The distance along `normal` (unit, LPS) over which the continuous index
// changes by one voxel on some axis: 1 / max_a |(M^-1 n)_a| with M the
// index -> LPS matrix. The slice spacing for a normal along a grid axis; for
// an oblique grid the smallest step that reaches a new voxel.
double slice_step_mm(const Volume& v, const glm::dvec3& normal);

// Moves the plane (origin and centre) by `steps` * step_mm along its normal.
void scroll_slices(SlicePlane& p, double steps);
// Moves the plane so that offset_mm() == offset (origin and centre move along the normal).
void set_offset(SlicePlane& p, double offset_mm);
// Moves every plane's crosshair to `lps`: each plane moves along its normal
// through it; the centres stay where they were in-plane (no pan).
void set_crosshair(std::span<SlicePlane> planes, const glm::dvec3& lps);
// Sets pixel_mm so that fov_mm fills a width x height image (the larger ratio).
void zoom_to_fit(SlicePlane& p, int width, int height);
// The image size that shows fov_mm at pixel_mm: ceil(fov / pixel), at least 1.
std::array<int, 2> native_size(const SlicePlane& p);

// A view's pan and zoom (3D Slicer's middle and right drags). Both change
// only the framing (centre, pixel_mm), never the crosshair or the slice, so
// the grid slice_grid makes afterwards maps pixels to LPS as drawn.
// Pans by a drag of `delta` image pixels (x right, y down): the content
// follows the pointer, i.e. the LPS point under pixel q is afterwards under
// q + delta.
void pan_pixels(SlicePlane& p, const glm::dvec2& delta);
// Zooms a width x height image by `factor` (> 1 magnifies: pixel_mm /=
// factor) about the continuous pixel `fixed`: the LPS point under it stays
// under it. pixel_mm is kept within [1e-4, 1e4] mm; a factor that is not a
// positive finite number changes nothing.
void zoom_about(SlicePlane& p, int width, int height, const glm::dvec2& fixed, double factor);
// The zoom factor of a right drag of `dy_up` pixels (positive: up,
// magnifies) in a view `height` pixels tall: 2^(dy_up / (height / 2)), so a
// drag over half the view doubles or halves the scale whatever its size.
double drag_zoom_factor(double dy_up, int height);

// A view's Fit (key F, a double-click): the centre back on the volume's LPS
// bounding box's centre (moved along the normal onto the plane: the slice
// and the crosshair stay) and zoom_to_fit. Nothing for an empty volume.
void fit_view(SlicePlane& p, const Volume& v, int width, int height);

// The slices a view's slider spans: count offsets first_mm + i * step_mm
// (i = 0 .. count - 1), step_mm the plane's step (scroll_slices moves one),
// from half a step inside the volume's LPS bounding box along the normal
// (for a normal along a grid axis: the voxel centres, count = the voxels
// along it). At least one (a volume thinner than a step: its middle).
struct SliceRange {
    double first_mm = 0;
    double step_mm = 1;
    int count = 1;
};
SliceRange slice_range(const Volume& v, const SlicePlane& p);
// The slice nearest to an offset (half-way rounds up), clamped to the range.
int slice_index(const SliceRange& r, double offset_mm);

// ---- Annotations ------------------------------------------------------------------

// The patient direction at an edge of a plane's image, as 3D Slicer's slice
// view annotations: the letter (R, L, A, P, S or I) of the LPS axis nearest
// to the in-plane direction that points there (left: -right, right: right,
// top: up, bottom: -up; iso::orientation_letter, the 3D overlay's rule), so
// a plane whose axes are not LPS axes gets the nearest ones.
enum class SliceEdge : std::uint8_t { Left, Right, Top, Bottom };
std::string slice_edge_letter(const SlicePlane& p, SliceEdge e);

// A slice view's scale bar: the longest round length (1, 2 or 5 x 10^k mm,
// iso::round_length_mm, the 3D overlay's rule) not above a fifth of a view
// `width` pixels wide at the plane's pixel_mm; 0 for a width below 1 or a
// pixel size that is not a positive finite number.
double slice_scale_bar_mm(const SlicePlane& p, int width);

// ---- The planes in the 3D view ------------------------------------------------------

// Each orientation's colour, 3D Slicer's (its slice views' title bars and
// "slice intersections"): axial red #f34a33, coronal green #6eb04a,
// sagittal yellow #edd54c; sRGB components in [0, 1].
glm::vec3 slice_color(SliceOrientation o);

// The corners of the volume's LPS box: index -0.5 and n - 0.5 on each axis
// through the index -> LPS affine (a parallelepiped for an oblique or
// sheared grid). Corner i is at the high end of axis a when bit a of i is set.
std::array<glm::dvec3, 8> volume_corners(const Volume& v);
// The corners of an LPS box (min, max: a crop box), ordered as volume_corners orders them.
std::array<glm::dvec3, 8> box_corners(const std::pair<glm::dvec3, glm::dvec3>& box);

// The plane dot(p, normal) == offset_mm (normal unit) cut through the
// parallelepiped of `corners` (ordered as volume_corners orders them): the
// section's vertices, 3 to 6, in order counter-clockwise about the normal.
// Each is on the plane and on the box's surface (a point where an edge
// crosses the plane, or a corner on it). Empty when the plane misses the
// box or touches it only at a corner or along an edge.
std::vector<glm::dvec3> plane_box_section(const std::array<glm::dvec3, 8>& corners, const glm::dvec3& normal,
                                          double offset_mm);
// A slice plane's outline in the volume (plane_box_section of volume_corners):
// what the 3D view draws for the plane, in slice_color.
std::vector<glm::dvec3> slice_outline_3d(const Volume& v, const SlicePlane& p);

// The point the three views' crosshairs mark: each view draws it where its
// origin is, so the point lies on the line through each origin along that
// view's normal. For the three orthogonal planes of default_planes that is
// the sum over views i of dot(origin of the next view, normal_i) * normal_i
// (every origin, when set_crosshair put them all at one point).
glm::dvec3 crosshair_point(const std::array<SlicePlane, 3>& planes);

// ---- Pixels <-> LPS --------------------------------------------------------------

// A width x height image of a plane: continuous pixel coordinates (x, y)
// map to corner + x * dx + y * dy. The image's centre (width/2, height/2)
// is the plane's centre.
struct SliceGrid {
    int width = 0, height = 0;
    glm::dvec3 corner{0.0};      // LPS of (0, 0): the top-left corner of pixel (0, 0)
    glm::dvec3 dx{0.0}, dy{0.0}; // LPS per pixel: pixel_mm * right, -pixel_mm * up
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double offset_mm = 0; // the plane: dot(p, normal) == offset_mm
    double pixel_mm = 1.0;
};
// Throws iso::Error("slice image", ...) for a size below 1 or beyond 16384,
// or a plane whose axes are not orthonormal or whose pixel size is not positive.
SliceGrid slice_grid(const SlicePlane& p, int width, int height);

// The LPS point at continuous pixel coordinates (a click; (c + 0.5, r + 0.5)
// for pixel (c, r)'s centre). It lies on the plane.
glm::dvec3 pixel_to_lps(const SliceGrid& g, const glm::dvec2& pixel);

struct SlicePoint {
    glm::dvec2 pixel{0.0};  // continuous pixel coordinates of the point's projection onto the plane
    double distance_mm = 0; // signed distance from the plane along its normal
};
SlicePoint lps_to_pixel(const SliceGrid& g, const glm::dvec3& lps);

// The volume under a click: sample_volume (renderer/surface/analysis.hpp, what
// the core API's pick and value_at report) at pixel_to_lps(g, pixel): the
// trilinear value (HU for CT), the continuous index, the nearest voxel, its
// LPS centre and stored value. None outside the grid.
std::optional<VolumeSample> sample_at_pixel(const Volume& v, const SliceGrid& g, const glm::dvec2& pixel);

// ---- Reslicing ---------------------------------------------------------------------

enum class Interp : std::uint8_t {
    Nearest, // the stored value of the voxel whose centre is nearest (VolumeSample::voxel_value)
    Linear,  // trilinear (VolumeSample::value)
};

// Row-major, row 0 at the top; one float per pixel.
struct SliceImage {
    int width = 0, height = 0;
    std::vector<float> values;
    float at(int column, int row) const { return values[std::size_t(row) * std::size_t(width) + std::size_t(column)]; }
};

// The volume sampled at every pixel centre of the grid: exactly what
// sample_volume gives at pixel_to_lps(g, centre) (same inside test, same
// clamped outer half voxel, same NaN rule), rounded to float; NaN outside
// the grid. Dense volumes take a fast path (the index steps per column and
// per row come from the inverse affine once; rows in parallel through TBB);
// sparse ones go through Volume::value. `out` is resized and reused.
void reslice(const Volume& v, const SliceGrid& g, Interp interp, SliceImage& out);
// The same on the calling thread alone (an arena of one: TBB's loop runs
// inline), for a thread that must not wait: a parallel loop started from
// the GUI thread waits for every piece a worker took, and beside busy
// processes that held the desktop app's GUI thread 340 ms as a volume
// arrived (gui_massive_bench). The slice views use it up to 16 M voxels,
// where a view's slice is a few milliseconds of work (larger volumes'
// slices go to a pool thread: app/gui/slice_view.hpp).
void reslice_here(const Volume& v, const SliceGrid& g, Interp interp, SliceImage& out);
SliceImage reslice(const Volume& v, const SlicePlane& p, int width, int height, Interp interp = Interp::Linear);

// ---- Window / level ------------------------------------------------------------------

// Display mapping: values at center - width/2 and below are black (0),
// center + width/2 and above white (255), linear between (rounded), as
// VTK's and Slicer's window/level. A width below 1e-9 acts as a threshold
// at center.
struct WindowLevel {
    double center = 40.0;
    double width = 400.0;
    bool operator==(const WindowLevel&) const = default;
};

struct WindowPreset {
    std::string_view name;
    WindowLevel window;
};
// CT presets in HU, from Radiopaedia's "Windowing (CT)" table (brain, soft
// tissue, lung, bone), and a CT angiography window (W 600 / L 170, the CTA
// preset some open viewers use; Radiopaedia's table and Slicer list none):
// docs/slices.md.
std::span<const WindowPreset> ct_window_presets();
// The preset of that name (case-sensitive: "brain", "soft tissue", "lung", "bone", "angio").
std::optional<WindowLevel> ct_window_preset(std::string_view name);

// The window a view opens with: soft tissue for CT (meta.modality "CT");
// otherwise the value range's (min..max; a width of 1 when the range is flat).
WindowLevel default_window(const Volume& v);
// The same for the scene's volume, from its value range worked out once
// (Scene::value_range: a non-CT volume's scan is half a second at 2 GiB).
WindowLevel default_window(const Scene& s);
WindowLevel default_window(std::string_view modality, const ValueRange& range);

// Slicer's window/level drag (vtkSliceViewInteractorStyle, left button):
// from the window at the press, a drag of (dx right, dy_up) pixels adds
// gain * dx to the width (not below 0) and gain * dy_up to the level, with
// gain = (range.max - range.min) / 500 per pixel (1/500 for a flat range).
WindowLevel drag_window(const WindowLevel& start, const glm::dvec2& drag_right_up, const ValueRange& range);

// One value -> grey (NaN -> 0).
std::uint8_t window_grey(double value, const WindowLevel& w);

enum class PixelFormat : std::uint8_t {
    Grey8, // one byte per pixel, NaN (outside the volume) black
    Rgba8, // four bytes per pixel (R = G = B = grey, A = 255), NaN transparent (0, 0, 0, 0)
};
// The image through the window, row-major from the top (QImage's
// Format_Grayscale8 / Format_RGBA8888 with width * bytes-per-pixel stride).
std::vector<std::uint8_t> apply_window(const SliceImage& img, const WindowLevel& w,
                                       PixelFormat format = PixelFormat::Grey8);

// ---- Surface outlines ------------------------------------------------------------------

// One piece of a surface's outline on a slice, in continuous pixel
// coordinates. Oriented by the triangle's winding: for a closed, consistently
// oriented mesh, each segment's b is bitwise the next segment's a, so the
// segments chain into closed loops; with outward-facing triangles the solid
// lies to the left of a -> b seen from the side the plane's normal points to
// (counter-clockwise about the normal, in LPS).
struct SliceSegment {
    glm::vec2 a{0.0f}, b{0.0f};
};

// The intersection of a mesh (LPS) with the grid's plane: one segment per
// triangle that crosses it. A vertex exactly on the plane counts as above
// it (a symbolic perturbation), so a triangle touching the plane at a
// vertex gives nothing or a segment ending there, an edge in the plane is
// drawn once, and a triangle lying in the plane gives nothing (its region's
// border comes from the neighbours that go below). Each crossing point is
// computed from its edge's two vertices in a fixed order, so the triangles
// sharing an edge agree on it exactly. Segments outside the image are kept
// (the painter clips). Zero-length and non-finite segments are dropped.
// Parallel over triangles through TBB, in triangle order. Throws
// iso::Error("slice outline", ...) for a triangle naming a missing vertex.
std::vector<SliceSegment> mesh_outline(const Mesh& m, const SliceGrid& g);
// What lets an outline skip most of a large mesh: the bounds (LPS mm) of
// each block of kOutlineBlock consecutive triangles (an extraction's
// triangles come chunk by chunk, so a block is small in space). A plane
// that misses a block's box misses its triangles. Throws iso::Error as
// mesh_outline for a triangle naming a missing vertex.
constexpr std::size_t kOutlineBlock = 4096;
struct OutlineIndex {
    std::vector<glm::vec3> lo, hi; // per block
};
OutlineIndex outline_index(const Mesh& m);
// The same segments as mesh_outline(m, g), from the blocks the plane meets
// (a 32 M-triangle surface: milliseconds instead of a third of a second).
std::vector<SliceSegment> mesh_outline(const Mesh& m, const SliceGrid& g, const OutlineIndex& index);

} // namespace iso::core
