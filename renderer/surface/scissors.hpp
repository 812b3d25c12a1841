// Scissors in 3D (3D Slicer's Segment Editor Scissors, made exact on a
// surface): a closed outline drawn on a view, swept along the view's rays
// (a generalized cone from the eye in perspective, a prism in
// orthographic), keeps the part of a closed surface inside it, or outside
// it, cut at the swept walls and capped by the polygons the surface traces
// there (docs/measure.md, "Scissors").
//
// How: the outline (or, to keep the outside, a rectangle around the
// surface's projection with the outline as a hole) is cut into triangles by
// ear clipping; each triangle swept along its corners' rays is a convex
// region bounded by three planes (each wall of a swept segment is planar:
// two rays from one eye, or two parallel rays), so the surface's part in it
// is vtkClipClosedSurface's (clip_closed: exact clipping, capped). The
// parts are joined: the caps on walls two triangles share (inner walls) are
// dropped, and the points the two sides computed for one crossing are
// welded, so the result is one closed surface whose enclosed volume is the
// sum of the parts' (each exact), and whose outer walls are capped.
// Written here: VTK clips closed surfaces by convex regions only (plane
// collections), and no Debian package sweeps a non-convex outline.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "io/mesh.hpp"

namespace iso {

// The view an outline is swept along, as two maps between LPS mm and the
// image plane (pixels): where a point projects (none behind the eye), and
// the ray through an image point (origin, unit direction).
struct OutlineSweep {
    std::function<std::optional<glm::dvec2>(const glm::dvec3&)> project;
    std::function<std::pair<glm::dvec3, glm::dvec3>(const glm::dvec2&)> ray;
};

struct ScissorsCut {
    Mesh part;                        // closed when the surface is; empty when nothing is kept
    std::vector<glm::dvec2> outline;  // the outline as cut (simplified, counter-clockwise)
    std::size_t pieces = 0;           // convex regions the kept region was cut into
    std::size_t pieces_with_part = 0; // those the surface reaches
};

// The part of closed surface `m` inside (`keep_inside`) or outside the
// outline (image pixels, closed: the last corner joins the first) swept
// along `sweep`. Throws iso::Error: fewer than three distinct corners, an
// outline that crosses itself or encloses no area, and (keeping the
// outside) a surface reaching behind the eye.
ScissorsCut scissors_cut(const Mesh& m, const std::vector<glm::dvec2>& outline, const OutlineSweep& sweep,
                         bool keep_inside);

// An outline drawn on a perspective view, kept with the part it cut so that
// a session or a moved iso value makes the part again: the outline (image
// pixels from the top-left, closed), the view (its projection x view
// matrix, reversed Z as Camera makes it; the eye; the image size) and the
// side kept.
struct ViewOutline {
    std::vector<glm::dvec2> outline;
    glm::dmat4 view_projection{1.0};
    glm::dvec3 eye{0.0};
    int width = 0, height = 0;
    bool keep_inside = true;
    bool operator==(const ViewOutline&) const = default;
};
// The view's sweep: where a point projects, and the ray from the eye
// through an image point, as Camera::pixel_ray casts it (the same numbers).
OutlineSweep outline_sweep(const ViewOutline& v);
// scissors_cut along that sweep. Throws iso::Error as it does, and for a
// view without size or with a singular matrix.
ScissorsCut scissors_cut(const Mesh& m, const ViewOutline& v);

// ---- the outline's geometry (tested on its own) ----------------------------------

// Douglas-Peucker within `tolerance` pixels, consecutive duplicates dropped
// (a pointer's outline has a point per move).
std::vector<glm::dvec2> simplify_outline(const std::vector<glm::dvec2>& closed, double tolerance);
// Twice the signed area (positive: counter-clockwise with y up).
double signed_area2(const std::vector<glm::dvec2>& polygon);
// Two edges that are not neighbours meet (or neighbours overlap).
bool outline_crosses_itself(const std::vector<glm::dvec2>& closed);
// Ear clipping of a simple polygon (either orientation; a polygon with a
// hole joined to it by a bridge, whose two copies of each bridge end are
// separate corners, works too): n - 2 triangles, corner indices, each
// counter-clockwise. Throws iso::Error when no ear is left (a polygon that
// is not simple).
std::vector<std::array<std::size_t, 3>> triangulate_polygon(const std::vector<glm::dvec2>& polygon);

} // namespace iso
