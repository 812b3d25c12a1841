// Exact closest points on triangle meshes, in double precision (docs/measure.md,
// "Distance between surfaces"): the shortest distance between two surfaces
// (a lesion to a vessel, a fragment to the bone it broke from) as the
// minimum over every pair of triangles, found through a bounding volume
// hierarchy over each mesh (a dual-tree branch and bound), and the point of a
// surface nearest to a given point.
//
// Written here: Embree (the project's ray-tracing reference) answers point
// queries against its own single-precision geometry, not triangle against
// triangle; VTK's vtkDistancePolyDataFilter and vtkImplicitPolyDataDistance
// measure from the vertices of one surface to the other, which misses the
// closest pair wherever it lies inside a triangle or on an edge (two
// parallel faces, a vertex of one facing an edge of the other). The
// triangle-pair distance is the classic decomposition (Ericson, Real-Time
// Collision Detection, 5.1.5 and 5.1.9): 9 edge-edge and 6 vertex-triangle
// distances, and 0 where an edge of one crosses the other.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"

namespace iso {

// The closest pair of points of two triangles (or a point and a triangle).
struct ClosestPair {
    double distance_mm = 0;
    glm::dvec3 a{0.0}, b{0.0}; // on the first and the second
};

using TriangleCorners = std::array<glm::dvec3, 3>;
// Triangle t of m, in double precision (t and its vertices must exist).
TriangleCorners triangle_corners(const Mesh& m, std::uint32_t t);

// The closest points of two triangles; 0 where they touch or cross. Degenerate
// triangles (collinear or repeated corners) are measured as the segments they are.
ClosestPair triangle_distance(const TriangleCorners& a, const TriangleCorners& b);
// The point of triangle `t` nearest to `p` (pair.a = p, pair.b on t).
ClosestPair point_triangle_distance(const glm::dvec3& p, const TriangleCorners& t);

// A bounding volume hierarchy over the triangles of a mesh (axis-aligned
// boxes in double precision, median splits, up to 4 triangles per leaf).
// Holds a reference to the mesh, which must outlive it.
class TriangleBvh {
public:
    explicit TriangleBvh(const Mesh& mesh);
    // Only these triangles of the mesh (one component, say).
    TriangleBvh(const Mesh& mesh, std::vector<std::uint32_t> triangles);

    const Mesh& mesh() const { return mesh_; }
    std::size_t size() const { return tris_.size(); }
    TriangleCorners corners(std::uint32_t triangle) const;

    struct Node {
        glm::vec3 lo, hi; // float, as the corners are: exact (40 bytes a node, 16.8 M nodes at 32.5 M triangles)
        std::uint32_t first = 0, count = 0; // a leaf: tris_[first, first + count)
        std::uint32_t left = 0, right = 0;  // an inner node (count 0): children
    };
    const std::vector<Node>& nodes() const { return nodes_; }
    const std::vector<std::uint32_t>& triangles() const { return tris_; } // in leaf order

private:
    struct Prim;
    void build();
    std::uint32_t build_node(std::uint32_t first, std::uint32_t count, std::vector<Prim>& prims);
    const Mesh& mesh_;
    std::vector<std::uint32_t> tris_;
    std::vector<Node> nodes_;
};

// The closest points of two surfaces, with the triangles they lie on.
struct SurfaceDistance {
    ClosestPair pair;
    std::uint32_t triangle_a = 0, triangle_b = 0;
    bool touching = false;          // distance 0: the surfaces meet or cross
    std::size_t triangle_pairs = 0; // triangle pairs measured (the rest were pruned by their boxes)
};

// The exact minimum distance over every pair of triangles of `a` and `b`.
// Throws iso::Error("surface distance", ...) when either has no triangles or a
// vertex is not finite.
SurfaceDistance surface_distance(const TriangleBvh& a, const TriangleBvh& b);
// The same by brute force over every pair (for tests and small meshes).
SurfaceDistance surface_distance_brute_force(const Mesh& a, const Mesh& b);

// The point of the surface nearest to `p`, and its triangle.
struct NearestPoint {
    glm::dvec3 point{0.0};
    double distance_mm = 0;
    std::uint32_t triangle = 0;
};
// Throws iso::Error("nearest point", ...) for an empty surface or a non-finite point.
NearestPoint nearest_point(const TriangleBvh& bvh, const glm::dvec3& p);

// The connected component of a mesh nearest to a point: every triangle's
// component (triangle_components: measure's numbering), the one of the
// triangle nearest to `at`, and the nearest point on it.
struct NearestComponent {
    std::vector<std::uint32_t> triangle_component;
    std::uint32_t component = 0;
    NearestPoint nearest;
};
NearestComponent nearest_component(const Mesh& m, const glm::dvec3& at);

// Where the segment [p, q] crosses the surface: the parameters t in [0, 1]
// along it, sorted, each with its triangle (a crossing exactly at an edge
// shared by two triangles may be listed twice: callers merge by distance).
struct SegmentCrossing {
    double t = 0;
    std::uint32_t triangle = 0;
};
std::vector<SegmentCrossing> segment_crossings(const TriangleBvh& bvh, const glm::dvec3& p, const glm::dvec3& q);

} // namespace iso
