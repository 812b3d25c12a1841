// A closed surface cut by an axis-aligned LPS box and closed again: the
// part of the solid inside the box, its cuts capped by the polygons the
// surface traces on the box's faces (VTK's vtkClipClosedSurface: the same
// clipping and cap triangulation 3D Slicer and ParaView use). The cut is
// exact for the surface as it is: a triangle crossing a face is split at
// the face (linear interpolation along its edges), and a cap is the
// polygon of those crossings, so the part's enclosed volume is the
// surface's solid intersected with the box, to rounding (docs/measure.md,
// "Structures within a box").
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"

namespace iso {

struct LpsBox {
    glm::dvec3 lo{0.0}, hi{0.0}; // LPS mm, lo < hi on every axis
    // The point lies in the box, its faces included.
    bool contains(const glm::dvec3& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
    }
    bool operator==(const LpsBox&) const = default;
};

// Parses "x0,y0,z0,x1,y1,z1" (LPS mm; either corner first on each axis).
// Throws iso::Error(what, ...) for a malformed, non-finite or flat box.
LpsBox parse_box(const std::string& what, const std::string& text);

// A half-space: the points p with dot(p - origin, normal) >= 0.
struct HalfSpace {
    glm::dvec3 origin{0.0}, normal{0.0, 0.0, 1.0};
};

// The part of closed surface `m` within every half-space (a convex region),
// capped on each plane by the polygons the surface traces there
// (vtkClipClosedSurface); normals recomputed, one vertex per point.
Mesh clip_closed(const Mesh& m, const std::vector<HalfSpace>& region);

// The part of closed surface `m` within `box`, capped: a closed surface
// again (an open surface is cut, but its cuts are left open). A surface
// wholly inside comes back as it is; one wholly outside comes back empty.
// Positions in LPS mm; normals recomputed (caps flat). Throws iso::Error
// for a box that is not finite or flat.
Mesh clip_to_box(const Mesh& m, const LpsBox& box);

// How a part touches the box's faces: the area of its triangles lying in
// each face (the caps), in the order x0 (right), x1 (left), y0
// (anterior), y1 (posterior), z0 (inferior), z1 (superior), mm^2.
std::array<double, 6> cap_areas(const Mesh& m, const LpsBox& box);
// The faces' names in that order: "right", "left", "anterior", "posterior", "inferior", "superior".
const char* box_face_name(int face);

} // namespace iso
