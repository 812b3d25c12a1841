// Drawing massive surfaces by clusters (docs/lod.md): a surface's clusters
// and levels (renderer/lod/cluster_lod.hpp) on the GPU, the compute pass
// that culls them (shaders/render/lod_cull.comp) and the indirect draws of
// what survives (glMultiDrawElementsIndirectCount). The geometry passes
// (G-buffer, VOIT lists, voxelization) draw through draw_surfaces(), which
// falls back to one glDrawElements for surfaces without levels.
//
// The G-buffer's opaque surfaces are drawn in the two-pass occlusion
// scheme: first the clusters that were visible in the last frame, then a
// depth pyramid of what was drawn, then the rest, each tested against it;
// a last pyramid marks what is visible for the next frame. A surface
// without a last frame (its first on this renderer) starts instead with
// the clusters of its nearest sixteenth of cells, then tests the next
// sixteenths in turn.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "renderer/gl/objects.hpp"
#include "renderer/lod/cluster_lod.hpp"

namespace iso::passes {

struct FrameContext;
struct DrawItem;
class GlResources;

// Words of a surface's counts buffer: per-slot draw counts, then the
// statistics from word kStatsWord on (lod_cull.comp: C_SELECTED ...).
constexpr std::uint32_t kCountWords = 20, kStatsWord = 12;

// One surface's clusters on the GPU (kept by the Renderer with its mesh).
struct GpuLod {
    gl::Buffer cells, clusters, state, commands, counts, order;
    std::uint32_t cluster_count = 0;
    std::vector<lod::Cell> cpu_cells; // the batches of a frame without history
    std::size_t full_triangles = 0;
    std::vector<lod::Proxy> proxies; // stand-ins while moving, finest first
    // Culled frames drawn so far: the state's visibility is the last one's when > 0.
    int frames = 0;
};
// Uploads `c`; the mesh's vertex array `vao` gets c.indices as its element
// buffer, which is returned (level 0 first: the whole mesh, reordered).
GpuLod upload_lod(const lod::ClusterLod& c, std::uint32_t vao, gl::Buffer& indices);

// The depth pyramid of the occlusion test, kept across frames.
struct CullState {
    gl::Texture pyramid;
    int width = 0, height = 0, levels = 0;
};

// How a geometry pass wants its surfaces drawn.
enum class DrawSet {
    Visible,  // the G-buffer: levels, frustum, back faces, occlusion (two passes)
    InView,   // translucent surfaces: levels and frustum
    Complete, // voxelization: levels only (AO needs what is outside the view too)
};

// Draws `items`: `bind(item)` sets the item's uniforms and binds the
// program (again after a compute step), then the item is drawn whole or by
// its culled clusters, or, in a moving frame (RenderOptions::moving), by
// its coarsest stand-in (lod::Proxy) whose error projects within the
// moving bound at the surface's nearest point. `depth` (and `samples`) is the depth texture being
// drawn into, for the pyramid (DrawSet::Visible). A pick frame (ctx.pick)
// draws level 0 only, culled to the pick region: picks stay on the full
// geometry. Statistics go to ctx.result->lod.
void draw_surfaces(const FrameContext& ctx, GlResources& gl, const std::vector<DrawItem>& items, DrawSet set,
                   const std::function<void(const DrawItem&)>& bind, std::uint32_t depth = 0, int samples = 1);

// The stand-in a moving frame draws for `item` instead of its clusters
// (draw_surfaces; not for DrawSet::Complete), or null: the coarsest whose
// error projects within the moving bound at the nearest point of the
// surface's bounds (lod::error_limit_mm).
const lod::Proxy* moving_proxy(const FrameContext& ctx, const DrawItem& item);

// The shaders' define and binding for the triangle a pick names: level 0's
// order maps a drawn triangle back to the mesh's (shaders/render/lod_pick.glsl).
void bind_triangle_order(const DrawItem& item, std::uint32_t program);

} // namespace iso::passes
