// Measurements in LPS millimetres (docs/measure.md): distances and angles
// between points, the value of a volume at a point, and the area, enclosed
// volume, topology and components of a surface, with an uncertainty for
// isosurfaces from the voxel size.
//
// Everything is computed in double precision on the CPU. Surfaces are taken
// as they are: vertices at equal positions are the same vertex (so STL
// triangle soups measure like indexed meshes), degenerate triangles count as
// zero area, and an open surface never reports a plain volume: its volume is
// a lower bound and says so (VolumeKind).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "renderer/surface/extract.hpp"

namespace iso {

// ---- Points ----------------------------------------------------------------

// |b - a| in mm. Throws iso::Error("distance", ...) for non-finite points.
double distance_mm(const glm::dvec3& a, const glm::dvec3& b);

// The angle at `vertex` between the rays to `a` and to `c`, in degrees
// (0..180), computed as atan2(|u x v|, u . v), accurate near 0 and 180.
// Throws iso::Error("angle", ...) when `a` or `c` coincides with `vertex`
// (closer than 1e-9 mm: no direction) or a point is not finite.
double angle_deg(const glm::dvec3& a, const glm::dvec3& vertex, const glm::dvec3& c);

// The volume at one LPS point.
struct VolumeSample {
    // Trilinear interpolation of the stored samples (values are stored after
    // rescale: Hounsfield units for CT). NaN when a sample it uses is NaN.
    double value = 0;
    glm::dvec3 index{0.0};                      // continuous index (i, j, k) of the point
    std::array<std::int64_t, 3> voxel{0, 0, 0}; // the nearest voxel (its centre is nearest)
    glm::dvec3 voxel_lps{0.0};                  // that voxel's centre, LPS mm
    double voxel_value = 0;                     // that voxel's stored value
    // The point lies in the outer half voxel of the grid, beyond the last
    // voxel centres: interpolation used the border samples for the missing
    // neighbours (the value is then extrapolated as constant across that rim).
    bool clamped = false;
};

// The value of `v` at `lps`: the point is mapped to a continuous index
// through the inverse of index_to_lps (so oblique, anisotropic and sheared
// grids are handled). Inside the grid means inside the voxels' extent,
// index in [-0.5, n - 0.5] on every axis; outside it the answer is
// std::nullopt. Dense and sparse (OpenVDB) volumes alike.
std::optional<VolumeSample> sample_volume(const Volume& v, const glm::dvec3& lps);

// ---- Surfaces ----------------------------------------------------------------

enum class VolumeKind : std::uint8_t {
    // Closed surface (every edge's uses cancel): the enclosed volume, by the
    // divergence theorem. Positive for outward-facing triangles (isosurfaces
    // face towards lower values), negative for a cavity or an inverted mesh.
    Enclosed,
    // Open surface: every boundary loop is capped by a fan of triangles
    // around the loop's centroid and the capped surface's enclosed volume is
    // reported. For an isosurface cut by the volume border, the loops lie on
    // the border and the capped volume is the structure's part inside the
    // scanned field: a lower bound on the structure, never its volume.
    LowerBound,
    // Triangles inconsistently oriented (an edge used twice in the same
    // direction): the volume is undefined and reported as NaN.
    Undefined,
};
const char* volume_kind_name(VolumeKind k); // "enclosed", "lower bound", "undefined"

// A surface (or component) whose signed volume is negative faces into what it
// encloses: it is the wall of a cavity (the inner wall of a hollow structure,
// an air pocket; or a mesh whose triangles face inwards), and what it
// encloses is a cavity of |volume|. The measures keep the sign (the sum over
// a hollow structure's walls is its material's volume); what is shown to a
// user (the CLI, the JSON, the desktop app) is never a negative volume but
// "encloses a cavity of |volume|", with a `cavity` flag in the JSON.
inline bool encloses_cavity(double signed_volume) { return signed_volume < 0; }

inline constexpr double kNoUncertainty = std::numeric_limits<double>::quiet_NaN();

// One connected component (triangles connected through shared vertices).
struct SurfacePart {
    std::size_t triangles = 0;
    double area_mm2 = 0;
    double volume_ml = 0; // 1 mL = 1000 mm^3; read with volume_kind
    VolumeKind volume_kind = VolumeKind::Enclosed;
    bool closed = true; // no boundary edges (volume_kind == Enclosed)
    std::size_t boundary_edges = 0, boundary_loops = 0;
    double boundary_length_mm = 0;
    glm::dvec3 bounds_min{0.0}, bounds_max{0.0};
    // Discretization uncertainty (measure_isosurface only; NaN otherwise):
    // see SurfaceMeasures.
    double area_uncertainty_mm2 = kNoUncertainty;
    double volume_uncertainty_ml = kNoUncertainty;
};

struct SurfaceMeasures {
    std::size_t triangles = 0;
    std::size_t vertices = 0;             // distinct positions used by triangles
    std::size_t degenerate_triangles = 0; // zero area (repeated or collinear vertices): area 0, volume 0
    double area_mm2 = 0;
    double volume_ml = 0; // sum over components; read with volume_kind
    // The weakest of the components': Undefined if any is, else LowerBound if any is open.
    VolumeKind volume_kind = VolumeKind::Enclosed;
    bool closed = true;
    // Edges (pairs of distinct vertices) by use: a boundary edge is used by
    // one triangle (in general: its uses in the two directions do not
    // cancel); a non-manifold edge by three or more; a misoriented edge by
    // two triangles in the same direction.
    std::size_t boundary_edges = 0, non_manifold_edges = 0, misoriented_edges = 0;
    std::size_t boundary_loops = 0;
    double boundary_length_mm = 0;
    glm::dvec3 bounds_min{0.0}, bounds_max{0.0};
    // Components by volume, descending (Undefined ones last, then by area).
    std::vector<SurfacePart> components;
    // Discretization uncertainty of area and volume (measure_isosurface; NaN
    // from measure_surface): Roache's Grid Convergence Index against the same
    // isosurface extracted from the volume resampled to about twice the
    // voxel size on the same extent,
    //     U = Fs * |M(h) - M(2h)| / (r^p - 1),  Fs = 3, p = 2,
    // r = the cube root of the coarse-to-fine voxel volume ratio (about 2, so
    // U is about |M(h) - M(2h)|), taken as the largest over
    // MeasureOptions::coarse_grids coarse grids whose samples fall at
    // different places. Per component, M(2h) sums the coarse components
    // matched to it (most of their vertices nearest to it on the grid; none:
    // M(2h) = 0, so U = |M(h)|). On the ball phantoms it covered the true
    // error in every case where the edge is resolved (blur >= 0.35 voxel, or
    // a linear ramp), typically 3-4x over and never under 1.06x; not the
    // area for sharper edges (see edge_fraction_spread), and not label-map
    // surfaces. docs/measure.md.
    double area_uncertainty_mm2 = kNoUncertainty;
    double volume_uncertainty_ml = kNoUncertainty;
    // Richardson extrapolation to zero voxel size from the same first coarse
    // grid (measure_isosurface; NaN otherwise): M(h) + (M(h) - M(2h)) /
    // (r^2 - 1). Marching cubes' error of a smooth surface goes as h^2 (the
    // triangles are chords: a ball's volume is -0.64 % at 10 voxels of
    // radius), and this removes its leading term (-0.07 % there). For a
    // structure the grid barely resolves, or a noisy one, prefer the plain
    // value and its uncertainty; the whole surface only.
    double area_extrapolated_mm2 = kNoUncertainty;
    double volume_extrapolated_ml = kNoUncertainty;
    // measure_isosurface: does the grid resolve the structure's edge? Each
    // vertex sits at a fraction t along its cut edge; where the edge's blur
    // spans a voxel or more, t is spread evenly over (0, 1); where the edge
    // is sharper than the grid (a binary mask, a label map, a very sharp
    // kernel), t crowds at 1/2. This is 4 x the mean |t - 1/2|: 1 for an
    // even spread, 0 when every vertex is at mid-edge (NaN from
    // measure_surface). Below kResolvedEdgeSpread a warning says the area is
    // biased upward (staircase) by more than the uncertainty covers.
    double edge_fraction_spread = kNoUncertainty;
    std::vector<std::string> warnings; // misoriented or non-manifold edges, no uncertainty, sharp edges, ...
};

// See SurfaceMeasures::edge_fraction_spread: 0.8 is reached at an edge blur
// (Gaussian sigma) of about 0.3 voxel on the ball phantoms (docs/measure.md).
inline constexpr double kResolvedEdgeSpread = 0.8;

struct MeasureOptions {
    int threads = 0; // 0: as many as TBB allows
    // measure_isosurface: how many coarse grids (about half the samples per
    // axis, then one more sample per axis for each further grid, so their
    // samples fall at different places on the structure); the uncertainty is
    // the largest of their estimates.
    int coarse_grids = 2;
    // measure_isosurface: the surface is some components of the isosurface
    // (the largest kept, one isolated), so the whole surface is compared with
    // the coarse components matched to them, not with the whole coarse
    // isosurface (its uncertainty is then its components' one).
    bool components_only = false;
    // measure_isosurface: what the surface's post-processing did that the
    // coarse isosurfaces must do too before they are compared (a part cut
    // by a box: the same cut); none: nothing.
    std::function<Mesh(const Mesh&)> coarse_post;
};

// Measures a mesh in the units of its positions (LPS mm). O(n): vertices are
// welded by exact position through a hash table, edges counted by bucket,
// components by union-find, area and volume summed in parallel (each
// component relative to its bounding-box centre, so large coordinates do not
// cost digits). Throws iso::Error("surface measure", ...) for a triangle
// that names a missing vertex or a vertex that is not finite.
SurfaceMeasures measure_surface(const Mesh& m, const MeasureOptions& opt = {});

// Per triangle of `m`, its connected component: an index into the
// components of measure_surface(m) (the same welding, the same order: by
// volume, descending). Throws as measure_surface.
std::vector<std::uint32_t> triangle_components(const Mesh& m, const MeasureOptions& opt = {});

// The triangles of `m` whose component (triangle_components) is `component`,
// with only the vertices they use (normals and colours kept).
Mesh component_mesh(const Mesh& m, const std::vector<std::uint32_t>& triangle_component, std::uint32_t component);

// Measures `surface`, the isosurface of `v` at `iso` as extract_isosurface
// made it, and adds the discretization uncertainty (SurfaceMeasures): the
// volume is resampled trilinearly to about half the samples per axis on the
// same extent (so a surface cut by the border is cut at the same place),
// the isosurface extracted from it and measured, and the two compared; the
// edge fraction spread is measured on `surface`. Axes with fewer than 3
// samples are not coarsened; if fewer than two axes can be (a coarsening
// ratio below 1.3), the uncertainty stays NaN with a warning.
// About 5x the time of measure_surface, 3x the extraction's (docs/measure.md).
// Note: measure_isosurface(v, iso, {}) is ambiguous; leave the options out.
SurfaceMeasures measure_isosurface(const Volume& v, double iso, const Mesh& surface, const MeasureOptions& opt = {});
// Extracts the isosurface too.
SurfaceMeasures measure_isosurface(const Volume& v, double iso, const MeasureOptions& opt = {});

// The volume resampled to about twice the voxel size on the same extent
// (m = ceil((n - 1) / 2) + 1 samples per axis of n >= 3, trilinear, float32,
// NaN and Inf substituted as extraction does); the ratio of the new voxel
// steps to the old per axis in `ratio`. Used by measure_isosurface, public for
// tests and benchmarks.
Volume coarsen_2x(const Volume& v, glm::dvec3* ratio = nullptr);
// The volume resampled (trilinearly, float32) to `dims` samples spanning the
// same extent: the first and last sample of every axis keep their positions.
// Throws iso::Error("resample", ...) for fewer than 2 samples on an axis of
// more than one.
Volume resample_extent(const Volume& v, std::array<std::int64_t, 3> dims, glm::dvec3* ratio = nullptr);

} // namespace iso
