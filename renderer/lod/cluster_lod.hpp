// Clusters and levels of detail of one surface, for drawing massive meshes
// (docs/lod.md): the mesh is cut into cells (compact groups of about
// LodBuildOptions::cell_triangles triangles, by median splits of their
// centroids), each cell is simplified into coarser levels with its border
// locked (libmeshoptimizer's meshopt_simplify with meshopt_SimplifyLockBorder),
// so any two neighbouring cells at any two levels meet on the same border
// vertices: no cracks, whatever level each cell is drawn at. Every level of
// every cell is cut again into clusters of at most cluster_triangles
// triangles with their bounds and normal cone: the unit the GPU culls
// (renderer/passes/lod_draw.cpp, shaders/render/cull.comp).
//
// All levels index the mesh's own vertices (the simplifier keeps a subset):
// the vertex buffer is drawn as it is, with the original normals. Level 0
// is the whole mesh, its triangles reordered by cluster; `triangle_order`
// maps them back, so that a pick on level 0 names the mesh's triangle.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/progress.hpp"

namespace iso::lod {

constexpr int kMaxLevels = 8;

// std430 layouts of shaders/render/cull.comp (LodCell, LodCluster).
struct alignas(16) Cell {
    glm::vec3 lo{0.0f};
    std::uint32_t levels = 1; // levels built (1: level 0 only)
    glm::vec3 hi{0.0f};
    std::uint32_t first_cluster = 0;
    // The error of drawing each level instead of level 0 (mm; error[0] = 0):
    // the larger of its geometric error (the simplifier's error of each
    // step, summed along the chain, an upper bound) and half its longest
    // edge, because a triangle interpolates the normals of its corners:
    // what it smooths away of the shading is about its own size, so a level
    // whose triangles all stay under a pixel keeps the shading's detail
    // within that pixel (docs/lod.md, "What the error bounds"). The longest,
    // not a mean: the simplifier makes large triangles where the surface is
    // flat, and a few of them showed as facets in the desktop app's small
    // view while the mean edge still allowed the level.
    std::array<float, kMaxLevels> error{};
    std::array<float, kMaxLevels> geometric{}; // the geometric part alone (statistics)
};
static_assert(sizeof(Cell) == 96);

struct alignas(16) Cluster {
    glm::vec3 lo{0.0f};
    std::uint32_t cell = 0;
    glm::vec3 hi{0.0f};
    std::uint32_t level = 0;
    // Normal cone: every triangle's unit normal (by its winding) is within
    // acos(cos_angle) of `axis`; cos_angle <= 0: no cone (never culled as
    // back-facing).
    glm::vec3 axis{0.0f, 0.0f, 1.0f};
    float cos_angle = -1.0f;
    glm::vec3 centre{0.0f}; // of the bounds, and the bounding sphere's radius
    float radius = 0.0f;
    std::uint32_t first_index = 0, index_count = 0;
    std::uint32_t pad[2] = {0, 0};
};
static_assert(sizeof(Cluster) == 80);

struct BuildOptions {
    std::size_t cell_triangles = 32768; // a cell's level 0, at most
    // A cluster, at most: on the 1024^3 phantom at 1920x1080 (llvmpipe),
    // 2048 drew 5.5 M triangles a frame after the first, 1024 4.1 M, 512
    // 2.9 M (G-buffer 2.4 s -> 0.25 s), 256 2.5 M with twice the draws.
    std::size_t cluster_triangles = 512;
    // Each level asks for this fraction of the level before; levels stop when
    // a step keeps more than `min_reduction` of its input (the locked border
    // is then most of the cell) or at kMaxLevels.
    double level_ratio = 0.25, min_reduction = 0.8;
    // The stand-ins' grids, sized for about these many triangles each
    // (ClusterLod::proxies); one is built when under an eighth of the mesh's.
    std::vector<std::size_t> proxy_triangles{std::size_t(1) << 19, std::size_t(1) << 17, std::size_t(1) << 15};
};

// A stand-in for the whole surface while the camera moves (a drag's
// frames), as ParaView draws a vtkQuadricClustering of its surfaces while
// interacting: the vertices clustered on one grid (moving_proxy.cpp), its
// triangles a range of ClusterLod::indices (the mesh's own vertices, drawn
// with one glDrawElements, no culling). `error` (mm) is the simplifier's
// error of the cells' levels it starts from (each cell's coarsest within
// half the grid's cell) plus the grid cell's diagonal (a vertex moves to
// another of its cell). Parts thinner than a
// grid cell may close up or vanish: it is for motion, never for a still
// frame, a pick or a measurement.
struct Proxy {
    std::uint32_t first_index = 0, index_count = 0;
    float error = 0.0f; // mm
    float cell = 0.0f;  // the grid's cell size, mm
};

struct ClusterLod {
    std::vector<std::uint32_t> indices; // every level's triangles, cluster by cluster
    std::size_t level0_indices = 0;     // the first ones: level 0, the whole mesh
    // Level 0's triangle i (indices[3i..3i+2]) is the mesh's triangle triangle_order[i].
    std::vector<std::uint32_t> triangle_order;
    std::vector<Cell> cells;
    std::vector<Cluster> clusters; // by cell, then level
    // Triangles of all cells at each level (a cell with fewer levels counts
    // its coarsest in the levels after it): what a frame draws at one level.
    std::array<std::size_t, kMaxLevels> level_triangles{};
    int max_levels = 1;
    // Stand-ins while moving, finest first (after every level in `indices`;
    // BuildOptions::proxy_triangles).
    std::vector<Proxy> proxies;
    double build_seconds = 0;
    std::size_t memory_bytes() const;
};

// Builds the clusters and levels of `m` (its triangles; the vertices are
// not copied). Runs on every core (TBB); `progress` gets the cells done.
// A mesh of fewer than two cells' triangles gets one cell.
ClusterLod build_cluster_lod(const Mesh& m, const BuildOptions& o = {}, const ProgressFn& progress = {});

// Vertex clustering (moving_proxy.cpp): `tris` with every vertex replaced
// by the one nearest the centre of its cell of a grid of `cell` mm from
// `origin` (ties by the lower id), the triangles that collapse dropped and
// repeats kept once (a triangle and its reverse are two: thin walls keep
// both sides). Deterministic, parallel.
std::vector<std::array<std::uint32_t, 3>> cluster_vertices(const std::vector<std::array<std::uint32_t, 3>>& tris,
                                                           const std::vector<glm::vec3>& positions,
                                                           const glm::vec3& origin, float cell);

// The stand-ins of `lod` (its cells and levels built from `m`), appended to
// lod.indices and listed in lod.proxies.
void build_proxies(const Mesh& m, ClusterLod& lod, const std::vector<std::size_t>& targets);

// The largest error (mm) drawn within `max_error_px` pixels at the
// nearest point of the box [lo, hi] to `eye` (at least `near_plane` away):
// the rule select_level, lod_cull.comp's select_level and a moving frame's
// stand-in (lod_draw.cpp) follow.
float error_limit_mm(const glm::vec3& eye, const glm::vec3& lo, const glm::vec3& hi, float pixels_per_mm_at_1mm,
                     float max_error_px, float near_plane);

// The level of `cell` drawn for a view: the coarsest whose error, projected
// at the cell's nearest point to `eye`, is at most `max_error_px` pixels;
// `pixels_per_mm_at_1mm` is the image height over 2 tan(fov_y / 2) (a
// length L at distance d spans L * pixels_per_mm_at_1mm / d pixels). The
// same rule as lod_cull.comp's select_level (no test compares the two yet).
std::uint32_t select_level(const Cell& cell, const glm::vec3& eye, float pixels_per_mm_at_1mm, float max_error_px,
                           float near_plane);

} // namespace iso::lod
