// One frame of the renderer as pass-graph passes, one function per pass in
// its own file (docs/pass_graph.md, "How to add a pass"). A pass function
// takes the graph, the frame's context and its input handles, declares what
// it creates, reads and writes, and returns its output handles; its GL work
// runs later, in FrameGraph::execute, and only if something needed reads
// what it writes. build_frame() assembles the whole frame; with a null
// FrameContext::gl it only declares, so the real frame's culling is tested
// without a GPU (tests/unit/frame_test.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec4.hpp>
#include <glm/mat4x4.hpp>

#include "renderer/graph/frame_graph.hpp"
#include "renderer/graph/resource_pool.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"
#include "renderer/volume/preintegration.hpp"

namespace iso::gl {
class Program;
}

namespace iso {
struct DiskHierarchy;
}

namespace iso::passes {

class GlResources;
struct DiskState;
struct GpuLod;
struct CullState;

// A VOIT list node (OitNode in shaders/render/oit_common.glsl): five 32-bit
// words, the link to the next node last.
constexpr std::size_t kOitNodeWords = 5, kOitNodeNextWord = 4, kOitNodeBytes = 4 * kOitNodeWords;

// A visible, non-empty mesh as the passes draw it.
struct DrawItem {
    std::uint32_t vao = 0;  // GL vertex array (positions at 0, normals at 1)
    std::int32_t count = 0; // indices
    std::uint32_t id = 0;   // object id (1-based) written to the id AOV
    glm::vec3 color{1.0f};  // linear albedo
    float opacity = 1.0f;
    Bounds bounds; // LPS mm: orders the translucent draws near to far
    // Its clusters and levels (lod_draw.hpp; null: drawn whole), and
    // whether it is closed (back-facing clusters may be culled).
    GpuLod* lod = nullptr;
    bool closed = false;
};

// What the AO passes keep between frames besides their history resources.
struct AoHistory {
    std::vector<double> view_key; // what the slicemap was built for
    ConeAoSettings settings;      // what the accumulated AO was traced with
    int frames = 0;               // still frames accumulated so far
};

// What the accumulation of jittered frames keeps between frames besides its
// history texture: what the average is of (everything but the jitter), and
// how many frames are in it.
struct AaHistory {
    std::vector<double> key;
    int frames = 0;
};

// A visible opaque surface as disk AO sees it: how to get its mesh (read
// back from the renderer's GPU buffers, called only when the hierarchy is not
// cached; the GL context is current) and the slot where its hierarchy is
// cached (built on first use, dropped when the mesh is replaced).
struct DiskSurface {
    std::uint32_t id = 0;
    std::uint64_t version = 0; // changes when the object's mesh changes
    std::function<Mesh()> mesh;
    std::shared_ptr<const DiskHierarchy>* cache = nullptr;
};

// The volume as a frame ray casts it (docs/volume.md): the renderer keeps
// its 3D texture (the values, 16-bit where the data is) and the occupancy
// of its chunks under the frame's transfer function across frames.
struct VolumeInput {
    std::uint32_t texture = 0, occupancy = 0; // GL textures: values (linear filtering), per chunk 1/0 (R8UI)
    glm::ivec3 dims{1};
    glm::dmat4 index_to_lps{1.0};
    glm::vec2 value_map{1.0f, 0.0f}; // value = texel * x + y
    int chunk_size = 32;
    glm::ivec3 chunk_counts{1};
    std::size_t empty_chunks = 0;
    double min_spacing = 1;
    std::uint64_t texture_bytes = 0;
    bool uploaded = false; // the texture was made this frame
    // The transfer function's tables (made when it changes; the pass
    // uploads them with the frame's other tables).
    std::shared_ptr<const TransferTables> tables;
};

struct FrameContext {
    GlResources* gl = nullptr; // null: declare only (compile without a GPU)
    graph::ResourcePool* pool = nullptr;
    Camera camera;
    RenderOptions opt;
    RenderHooks hooks;
    int width = 1, height = 1;
    glm::mat4 view_projection{1.0f};
    // The projection the geometry is rasterized with: view_projection moved
    // by this frame's sub-pixel jitter (the AO passes keep the unjittered one,
    // so a jittered frame neither rebuilds the slicemap nor restarts the AO).
    glm::mat4 raster_view_projection{1.0f};
    glm::vec2 jitter{0.0f};  // pixels, x right, y down
    int aa_samples = 1;      // DSRAA visibility sub-samples (1: none: no colour image, a pick or an AOV)
    AaHistory* aa = nullptr; // required when the frame accumulates
    int aa_frame = 0;        // this frame's index in the accumulated average (0: it starts again)
    glm::mat3 world_to_view{1.0f};
    std::vector<DrawItem> draws;       // opaque (opacity 1): the G-buffer and AO
    std::vector<DrawItem> translucent; // opacity < 1: the VOIT lists
    std::vector<glm::vec4> objects;    // per object id (0 unused): linear albedo, opacity
    std::size_t oit_capacity = 0;      // nodes of the VOIT pool this frame
    bool oit_merge = false;            // the pool is at its cap: fragments that find it full are merged, not redrawn
    bool oit_cut = false;           // at the cap, merge each pixel's farthest fragments (a depth cut) so the rest fit
    std::optional<PickRegion> pick; // clipped to the image; none when empty
    glm::vec2 translucent_depth{0.0f};      // linear depth (mm) the translucent objects' bounds span, within near..far
    Bounds bounds;                          // of the visible meshes
    std::uint64_t geometry_version = 0;     // changes when meshes are added
    Overlay overlay;                        // annotation triangles and their glyph atlas (empty: none)
    AoHistory* ao = nullptr;                // required when the AO passes run
    std::vector<DiskSurface> disk_surfaces; // the opaque draws' meshes, for disk AO
    DiskState* disk = nullptr;              // required when the disk AO passes run
    CullState* cull = nullptr;              // the depth pyramid of the cluster culling (lod_draw.hpp)
    RenderResult* result = nullptr;         // what passes report back (image, AO state, slicemap)
    const VolumeInput* volume = nullptr;    // the volume to ray cast in the colour image (null: none)
};

// Builds the context of a frame: matrices, bounds and the AO/overlay inputs.
FrameContext make_context(const Camera& camera, const RenderOptions& opt, std::vector<DrawItem> draws,
                          const Bounds& bounds);
// Sets the frame's sub-pixel jitter (pixels, x right, y down) and the projection it rasterizes with.
void set_jitter(FrameContext& ctx, glm::vec2 jitter);

// A pass that only reads (a read-back, a presentation) and runs for that
// side effect: `execute(const Reads&, const graph::Resources&)` gets the
// handles in the order given.
struct Reads {
    std::vector<graph::TextureHandle> textures;
    std::vector<graph::BufferHandle> buffers;
};
template <class Execute>
void side_effect_pass(graph::FrameGraph& fg, const char* name, const Reads& reads, Execute&& execute) {
    fg.add_pass<Reads>(
        name,
        [&](graph::FrameGraph::Builder& b, Reads& d) {
            for (const auto h : reads.textures) d.textures.push_back(b.read(h));
            for (const auto h : reads.buffers) d.buffers.push_back(b.read(h));
            b.side_effect();
        },
        std::forward<Execute>(execute));
}

// ---- passes (one file each) ----------------------------------------------

// The pick's lists (pick.cpp), written by the geometry passes of the frame
// it rides on: counters (offered, capacity), entries, per-pixel heads.
struct PickBuffers {
    graph::BufferHandle counters, entries, heads;
    bool valid() const { return counters.valid(); }
};
// The pick region in GL window pixels (bottom-up): x, y, width, height.
glm::ivec4 pick_rect_gl(const FrameContext& ctx);
// Entries the pick's pool holds: 64 layers per region pixel, at least 4096.
std::size_t pick_capacity(const FrameContext& ctx);
// In a pass's setup: the first writer (the VOIT list pass, or else
// pick_resolve) creates the lists, later ones write new versions.
PickBuffers write_pick(graph::FrameGraph::Builder& b, const FrameContext& ctx, const PickBuffers& previous);
// In its execute: binds them and the region to `prog` (the first writer
// also clears them). The shader needs PICK_APPEND (pick_defines()).
void bind_pick(GlResources& gl, const graph::Resources& r, const FrameContext& ctx, const PickBuffers& p,
               iso::gl::Program& prog, bool first);
inline std::string pick_defines(const PickBuffers& p) { return p.valid() ? "#define PICK_APPEND 1\n" : ""; }

struct GBuffer {
    graph::TextureHandle depth, normal, id, albedo;
    graph::BufferHandle params;     // the pass's own
    graph::TextureHandle primitive; // with a pick: the nearest opaque surface's triangle (R32UI)
    // With DSRAA (ctx.aa_samples > 1): the visibility sub-samples
    // (multisample textures: depth; RG32UI object id and octahedral normal,
    // the albedo follows from the id), the object table (per id: linear
    // albedo, opacity) and the edge list (shaders/render/dsraa_edges.glsl:
    // the pixels whose sub-samples do not all match their sample 0); the
    // channels above are then their sample 0, the one sample each pixel
    // shades.
    graph::TextureHandle ms_depth, ms_vis;
    graph::BufferHandle objects, edges;
};
GBuffer gbuffer(graph::FrameGraph& fg, const FrameContext& ctx);
// The compute step (add each pixel's nearest opaque surface from the
// G-buffer, sort each list, transmittances) and the read-back into
// RenderResult::pick. `lists`: the translucent fragments' (invalid: none).
void pick(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, const PickBuffers& lists);

// The cone-AO passes' shared plan for this frame (ao_plan.cpp): grid sizes,
// guard band, z range bounds, whether the slicemap must be rebuilt.
struct AoPlan {
    ConeAoSettings settings;
    double guard = 0;
    int grid_w = 1, grid_h = 1, ao_w = 1, ao_h = 1;
    bool coarse = false, voxelize = false;
    glm::vec2 sm_scale{1.0f}, proj_scale{1.0f};
    float scene_far = 0, radius = 0, near_margin = 0, near_plane = 0, far_plane = 0;
    glm::dmat4 sm_projection{1.0};
    glm::mat4 sm_view_projection{1.0f}, view{1.0f};
    std::vector<double> key;
    std::size_t pattern_bytes = 0;
    // The history resources the plan checks and the chain declares.
    graph::TextureDesc slicemap_desc;
    static constexpr graph::BufferDesc kZRangeDesc{8}; // nearest and farthest depth, float bits
};
AoPlan plan_ao(const FrameContext& ctx);
// Passes keep the plan until they execute.
using AoPlanRef = std::shared_ptr<const AoPlan>;

struct AoResources {
    graph::BufferHandle zrange;    // history: the slicemap's linear z range
    graph::TextureHandle slicemap; // history: the solid voxelization
};
graph::BufferHandle zrange(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                           graph::BufferHandle range);
graph::TextureHandle voxelize(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan,
                              graph::BufferHandle range, graph::TextureHandle slicemap);
// What the cone tracer reads besides the slicemap: this frame's cones and
// jitter sets, and the parameters (the VOIT resolve traces with both).
struct ConeTrace {
    graph::TextureHandle ao;
    graph::BufferHandle pattern, params;
};
// Traces the cones into `target` (history: accumulates over still frames).
ConeTrace cone_ao(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan, const GBuffer& gb,
                  const AoResources& in, graph::TextureHandle target);
graph::TextureHandle ao_upsample(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan,
                                 const GBuffer& gb, graph::TextureHandle coarse);
void read_slicemap(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan, const AoResources& in);
// The AO chain's outputs: the full-resolution AO image (1 = unoccluded),
// and what tracing more points needs (the VOIT resolve's translucent AO).
struct AmbientOcclusion {
    graph::TextureHandle ao;
    AoResources tracer; // slicemap and its z range
    ConeTrace cones;    // pattern and parameters
    int layers = 1;     // the slicemap's, for the tracer's LAYERS
};
// Declares the AO chain (zrange, voxelize when stale, cone_ao, ao_upsample
// when coarser).
AmbientOcclusion ambient_occlusion(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb);

// Disk AO (disk_ao.cpp; docs/ao.md, "Disk AO on the GPU"): disk_build
// (when the visible surfaces changed: CPU builds of the new ones, the
// concatenation and its upload), disk_elements (when the hierarchy, the
// settings or R changed: the element passes and the blend), disk_gather
// (every frame: per pixel from the G-buffer) into the AO image. The
// hierarchy and the terms live in DiskState across frames; the graph sees
// them through two tiny history buffers that order the passes and let it
// cull the chain when nothing reads the AO image.
graph::TextureHandle disk_ambient_occlusion(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb);

// Ray-traced AO (ao_import.cpp): RenderOptions::ao_image uploaded into a
// transient R32F texture (rows flipped to GL's bottom-up order).
graph::TextureHandle imported_ao(graph::FrameGraph& fg, const FrameContext& ctx);

// Deferred lighting; `ao` invalid: no AO.
graph::TextureHandle lighting(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                              graph::TextureHandle ao);
// Annotations over `color`; markups are dimmed where the G-buffer's `depth` is in front of them.
graph::TextureHandle overlay(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color,
                             graph::TextureHandle depth);
// VOIT (docs/voit.md): the translucent fragments' lists, then their
// front-to-back composite over `color`; returns the composited colour.
// `ao` non-null: each shaded fragment traces its own AO through that chain.
// With a pick (ctx.pick), the translucent fragments in its region are
// listed too: `pick` is set to the lists.
graph::TextureHandle voit(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, graph::TextureHandle color,
                          const AmbientOcclusion* ao, PickBuffers& pick);
// Volume ray casting (volume.cpp; docs/volume.md) over `color` when no
// translucent surface is drawn (the VOIT resolve marches it otherwise).
graph::TextureHandle volume(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                            graph::TextureHandle color);
// What a pass that marches the volume reads besides the colour: declared in
// its setup, bound in its execute (texture units 4-6, buffers 11-12, the
// parameters at 3), the counters read back into RenderResult::volume after.
struct VolumeBindings {
    graph::TextureHandle depth;
    graph::BufferHandle tables, counters, params;
};
VolumeBindings declare_volume(graph::FrameGraph::Builder& b, const FrameContext& ctx, const GBuffer& gb);
void bind_volume(GlResources& gl, const graph::Resources& r, const FrameContext& ctx, const VolumeBindings& v);
void report_volume(GlResources& gl, const graph::Resources& r, const FrameContext& ctx, const VolumeBindings& v);
// The frame's clip in the surfaces' programs (shaders/render/clip.glsl):
// the define to build them with, and the uniforms to set on the bound one.
std::string clip_define(const FrameContext& ctx);
// The volume march's variant (volume_march.glsl): gradient shading and
// pre-integration are compiled in or out, not branched on (llvmpipe runs
// both sides of a branch, so a path a frame does not take would still cost).
std::string volume_variant(const FrameContext& ctx);
void set_clip(const FrameContext& ctx, iso::gl::Program& prog);
// The sample step of this frame in mm (the still or the moving step).
double volume_step_mm(const FrameContext& ctx);
// DSRAA's reconstruction (dsraa.cpp): each visibility sub-sample takes the
// shaded colour of its own pixel, else of the nearest neighbour of the same
// object with a similar normal, else the background; the pixel is their
// mean in linear light. Returns `color` unchanged without sub-samples.
graph::TextureHandle dsraa(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                           graph::TextureHandle color);
// The accumulation of jittered frames (accumulate.cpp): the running mean in
// linear light (history), and this frame's result encoded as sRGB.
graph::TextureHandle accumulate(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color);
// What the accumulated average depends on besides the jitter.
std::vector<double> accumulation_key(const FrameContext& ctx);
// Sub-pixel offset of the k-th accumulated frame (Halton 2, 3; frame 0 unjittered), pixels in [-0.5, 0.5).
glm::vec2 jitter_offset(int k);
void present(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color);
void readback(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle source);

// The whole frame: gbuffer -> [AO] -> lighting -> [overlay] -> present or
// readback of the colour image or the requested AOV.
void build_frame(graph::FrameGraph& fg, const FrameContext& ctx);

} // namespace iso::passes
