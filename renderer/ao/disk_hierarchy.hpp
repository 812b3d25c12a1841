// Disk hierarchy of disk-based ambient occlusion (`--ao disk`):
// Bunnell's elements (one oriented disk per vertex) grouped into a tree that
// is built once per surface on the CPU and uploaded as flat arrays, and the
// CPU evaluation of the whole method (element passes, convergence blend,
// gather at any receiver) that the GLSL compute shaders mirror line by line
// and are tested against. Kernels: renderer/ao/disk_geometry.hpp.
//
// Hand-written: no Debian package provides a disk hierarchy for AO.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "io/mesh.hpp"
#include "renderer/ao/disk_geometry.hpp"

namespace iso {

// One element; the std430 layout of the GPU buffer (three 16-byte vectors).
struct DiskNode {
    // xyz: centre (a leaf: its vertex; a parent: area-weighted mean of its
    // leaves), w: area (a leaf: a third of its adjacent triangles' areas; a
    // parent: the sum over its leaves).
    glm::vec4 centre_area{0.0f};
    // xyz: unit normal (a leaf: the vertex normal, else the area-weighted
    // mean of its triangles' normals; a parent: the normalized area-weighted
    // mean of its leaves' normals, zero when they cancel), w: radius of a
    // sphere about the centre holding every leaf disk below (disk radius
    // sqrt(area / pi) included) and every triangle those leaves own (a
    // leaf: max(sqrt(area / pi), farthest corner of its triangles)).
    glm::vec4 normal_bound{0.0f};
    // x: skip, the next node in depth-first pre-order after this subtree
    //    (nodes.size() after the last): stackless traversal;
    // y: first child (always this index + 1), -1 for a leaf;
    // z, w: a leaf's triangles, triangles[z .. z + w) (each triangle belongs
    //    to exactly one leaf: the leaf of its first corner); 0, 0 for a
    //    parent.
    // The trees of a concatenation follow one another in `nodes`, and a
    // root's skip is the next tree's root, so one traversal from node 0 to
    // nodes.size() visits every tree.
    glm::ivec4 links{0};
};
static_assert(sizeof(DiskNode) == 48, "DiskNode must match the std430 layout");

struct DiskHierarchy {
    std::vector<DiskNode> nodes;           // depth-first pre-order, roots first in their subtrees
    std::vector<std::int32_t> roots;       // root of each surface's tree (one per build; concatenate adds)
    std::vector<glm::vec4> triangles;      // 3 per triangle (xyz LPS mm, w = 0), grouped by owning leaf
    std::vector<std::int32_t> vertex_node; // mesh vertex -> its leaf (-1: unreferenced vertex)
    std::vector<std::int32_t> node_level;  // depth of each node (root 0), for bottom-up passes
    int levels = 0;                        // 1 + deepest level
};

// Builds the tree of one surface (LPS mm). Degenerate triangles add no area;
// a mesh without normals gets area-weighted face normals. Throws iso::Error
// on an empty mesh or non-finite positions.
DiskHierarchy build_disk_hierarchy(const Mesh& mesh);

// Several surfaces occlude each other: one hierarchy with every tree, node
// and triangle indices offset; `roots` lists each tree's root.
DiskHierarchy concatenate(const std::vector<const DiskHierarchy*>& parts);

// Occlusion (0 = open, 1 = fully occluded) at a receiver (p, n) within
// radius R: traverse every root, descending while d^2 < traversal_epsilon x
// area; far elements as disks, near leaves as their triangles clipped to the
// tangent plane with the exact form factor. `node_term` (one per node; empty
// = all 1, the first pass) modulates each contribution by
// triangle_attenuation(term). How R limits the chapter's unbounded sum is
// stated in docs/ao.md.
double disk_occlusion(const DiskHierarchy& h, const glm::dvec3& p, const glm::dvec3& n,
                      const std::vector<float>& node_term, const DiskAoSettings& s, double radius);

// The element passes: every leaf's accessibility (1 - occlusion at its
// disk) for `s.passes` passes, each modulated by the previous one, the last
// two combined by converge_blend; parents get the area-weighted mean of
// their leaves. Returns one accessibility per node. s.passes <= 0: no
// element passes, every term 1 (the gather then sums unmodulated form
// factors).
std::vector<float> disk_element_terms(const DiskHierarchy& h, const DiskAoSettings& s, double radius);

// disk_occlusion for a receiver that may lie on the inside of the surface:
// when its normal n points against `face_normal` (its surface's geometric
// normal: a pixel's triangle's, a vertex's area-weighted triangles') its
// hemisphere looks into the solid, where the surface's back faces are what
// it sees (as the ray-traced reference does); then back faces occlude
// instead of front faces (disks with their normals flipped, triangles with
// the form factor's sign flipped). Otherwise the same as disk_occlusion.
// Interpolated normals of marching-cubes surfaces do this at thin
// structures (docs/ao.md, "Disk AO: hierarchy and CPU evaluation", limits).
double disk_occlusion_sided(const DiskHierarchy& h, const glm::dvec3& p, const glm::dvec3& n,
                            const glm::dvec3& face_normal, const std::vector<float>& node_term, const DiskAoSettings& s,
                            double radius);

// The same passes; also appends each pass's terms (before the blend) to
// `per_pass` when not null (tests and the benchmark: convergence).
std::vector<float> disk_element_passes(const DiskHierarchy& h, const DiskAoSettings& s, double radius,
                                       std::vector<std::vector<float>>* per_pass);

// disk_occlusion computes in float, as the shader does; this is the same
// code in double, for the float-against-double test.
double disk_occlusion_double(const DiskHierarchy& h, const glm::dvec3& p, const glm::dvec3& n,
                             const std::vector<float>& node_term, const DiskAoSettings& s, double radius);

} // namespace iso
