// The shape of a closed structure beyond its area and volume (docs/measure.md,
// "Structures within a box"): where its mass is (the centroid of the solid
// it encloses) and how large it is across (the largest diameter, 3D
// Feret's: the longest segment between two of its points, which joins two
// vertices of its convex hull). What a clinician reads off a nidus or a
// nodule besides its volume.
#pragma once

#include <glm/vec3.hpp>

#include "io/mesh.hpp"

namespace iso {

struct ShapeMeasures {
    // The centroid of the enclosed solid (LPS mm), from the signed tetrahedra
    // of the triangles (a closed, consistently wound surface; for an open one
    // it is that of the surface closed through the origin of its bounds:
    // meaningless, so `solid` says whether it is the solid's).
    glm::dvec3 centroid{0.0};
    bool solid = false;
    // The largest diameter and its two ends (LPS mm), exact: every pair of
    // the convex hull's vertices (qhull) is measured.
    double feret_mm = 0;
    glm::dvec3 feret_a{0.0}, feret_b{0.0};
    std::size_t hull_vertices = 0;
};

// `closed`: the surface is closed (measure_surface's answer). Empty meshes
// give zeros. Throws iso::Error when the hull cannot be made (qhull's
// message).
ShapeMeasures measure_shape(const Mesh& m, bool closed);

} // namespace iso
