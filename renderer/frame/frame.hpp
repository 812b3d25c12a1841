// What a frame is, for everyone who asks for one or reads one: the objects'
// properties, the options of a frame (size, background, AO and its settings,
// transparency, annotations, a pick riding on it), the test hooks, and what
// comes back (the image or an AOV, the pass statistics, the VOIT figures, the
// pick lists, the AO state). A leaf: it includes no pass and no Renderer, so
// the passes (renderer/passes) and the front ends share it without a cycle.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "io/image.hpp"
#include "io/mesh.hpp"
#include "io/progress.hpp"
#include "renderer/frame/ao_settings.hpp"
#include "renderer/graph/frame_graph.hpp"
#include "renderer/volume/transfer_function.hpp"

namespace iso {

struct Annotations; // renderer/frame/annotations.hpp

struct SceneObject {
    std::string name;
    glm::vec3 color{0.9f, 0.85f, 0.8f}; // linear RGB albedo
    float opacity = 1.0f;
    bool visible = true, pickable = true;
    // Every edge joins two triangles and the triangles wind outward (a
    // closed surface): its clusters that face away from an eye outside its
    // bounds may be culled (docs/lod.md). False when not known.
    bool closed = false;
};

enum class Aov { None, Depth, Normal, Id, Ao };
Aov aov_from_name(const std::string& name); // "depth", "normal", "id", "ao"; throws iso::Error

// How the AO term is computed (docs/ao.md): not at all; cone tracing in a
// slicemap (interactive); the disk hierarchy of GPU Gems 3 ch. 12 (still
// pictures); or Embree ray tracing (the ground truth, refined progressively
// on the CPU by the core or the 3D view and handed to the GL frame as
// RenderOptions::ao_image).
enum class AoMethod { Off, Cone, Disk, Raytraced };
const char* ao_method_name(AoMethod m); // "off", "cone", "disk", "raytraced"
// Also accepts "reference", the ray-traced method's former name (old sessions
// and commands). Throws iso::Error("ambient occlusion", ...).
AoMethod ao_method_from_name(const std::string& name);

// Anti-aliasing (docs/rendering.md, "Anti-aliasing"). Each frame stores
// `samples` visibility sub-samples per pixel (depth, object id, normal) but
// shades once per pixel; a reconstruction pass maps every sub-sample to the
// shaded colour of its own pixel or of a neighbour of the same object with a
// similar normal (DSRAA, decoupled sub-pixel reconstruction). Frames asked to
// accumulate (RenderOptions::accumulate: the 3D view's still frames and
// exports) are drawn with a sub-pixel jitter and averaged in linear light,
// the first with DSRAA, the later ones with one sample each (DSRAA's fixed
// sub-samples, moved by the jitter, would reach into the neighbours and
// blur the average), which converges to exact coverage for everything,
// translucent layers and the overlay included; exports stop when the
// average changes by less than `tolerance` (the RMS change, in sRGB units
// 0..1, of the pixels that moved) between N/2 and N frames, or at `frames`.
struct AntiAliasing {
    int samples = 4;         // visibility sub-samples per pixel: 1 (no DSRAA), 2, 4 or 8
    int frames = 64;         // accumulated frames at most (exports; the 3D view stops at view_frames)
    int view_frames = 16;    // the 3D view's still frames
    double tolerance = 0.04; // exports: convergence of the accumulated image (sRGB units)
    float normal_cos = 0.8f; // DSRAA: a neighbour's normal matches a sub-sample's within acos(normal_cos)
    bool operator==(const AntiAliasing&) const = default;
};

// Levels of detail and culling of massive surfaces (docs/lod.md): a
// surface of at least min_triangles triangles is cut into clusters with
// coarser levels (core::SurfaceLod builds them, Renderer::set_lod takes
// them); each frame draws, per cell, the coarsest level whose error projects to at most `error_px` pixels, and culls the
// clusters outside the view, facing away (closed surfaces seen from
// outside) or hidden behind what is drawn. Picks, rulers, measurement and
// surface distance always use the full geometry.
struct LodSettings {
    bool enabled = true;   // auto; off: every triangle of every surface is drawn
    double error_px = 0.5; // the bound on the projected geometric error, pixels
    // The bound while the camera moves (RenderOptions::moving: the 3D view's
    // drag frames and the plain frame standing in for its still frames),
    // when larger: as ParaView's interactive LOD, a moving view is drawn
    // coarser and the still frames after it restore error_px.
    double moving_error_px = 2.0;
    bool culling = true; // frustum, back-facing and occlusion culling of clusters (with enabled)
    // Surfaces with fewer triangles are drawn whole (their clusters would
    // cost more than they save); tests lower it.
    std::size_t min_triangles = 262144;
    bool operator==(const LodSettings&) const = default;
};

// How a frame shades its surfaces: the one description that the CLI's
// options, the 3D view, sessions, image exports and the renderer all read
// (each takes what applies to it: the renderer ignores ao_frames and
// ao_rays, the 3D view ao_rays).
struct FrameLook {
    glm::vec3 background{0.08f, 0.09f, 0.11f}; // linear RGB
    bool transparent_background = false;       // colour images: alpha 0 where no surface is
    // Off: every surface is drawn opaque whatever its opacity (the desktop
    // app's transparency toggle); the VOIT passes then have nothing to do.
    bool transparency = true;
    // Flat shading: every surface is its albedo (no lighting, no AO), so
    // transparency compositing can be checked exactly.
    bool flat_shading = false;
    // VOIT (order-independent transparency through per-pixel fragment
    // lists) for surfaces with opacity < 1: stop compositing a pixel once the
    // remaining transmittance is below oit_epsilon; the node pool grows up
    // to oit_memory_mib.
    float oit_epsilon = 1.0f / 512.0f;
    double oit_memory_mib = 256;
    // Ambient occlusion (modulates the ambient term; Aov::Ao reads it raw).
    // Off: its passes are culled. cone.radius_mm is R for every method; the
    // other members of `cone` are the cone tracer's, `disk` the disk
    // method's (docs/ao.md, "Disk AO on the GPU").
    AoMethod ao = AoMethod::Off;
    ConeAoSettings cone;
    DiskAoSettings disk;
    int ao_frames = 1; // cone: still frames accumulated, each with new jitter sets (the 3D view: while nothing moves)
    // Ray-traced: rays per pixel are added in batches until the standard
    // error of every pixel's estimate is at most ao_error, up to ao_rays.
    int ao_rays = 1024;
    double ao_error = 0.005;
    AntiAliasing aa;
    // The volume, ray cast (docs/volume.md): off unless enabled; drawn from
    // the renderer's volume (Renderer::set_volume), composited exactly with
    // the surfaces (flat_shading: the transfer function's colours unshaded).
    VolumeLook volume;
    // A crop that cuts the surfaces and the volume alike (LPS mm).
    Clip clip;
    LodSettings lod;
    bool operator==(const FrameLook&) const = default;
};

// Every member's range (the settings of the AO method asked for through
// their tables); throws iso::Error naming the first setting out of range,
// never a flag.
void validate(const FrameLook& look);

// A pick region in image pixels, from the image's top-left corner.
struct PickRegion {
    int x = 0, y = 0, width = 1, height = 1;
};

// One fragment of a picked pixel, as the frame rasterized it.
struct PickFragment {
    float depth = 0;             // reversed Z (larger is nearer)
    std::uint32_t object = 0;    // 1-based object id
    std::uint32_t primitive = 0; // the triangle in the object's mesh
    float alpha = 1;             // the object's opacity (1: opaque)
    float transmittance = 1;     // of everything in front of it in this pixel
};

// What a pick found: per pixel of the region (clipped to the image; row by
// row from its top-left), the fragments front to back (ties by object, then
// triangle). Opaque surfaces list every layer along the pixel (hidden ones
// too); translucent ones only in front of the nearest opaque.
struct PickList {
    PickRegion region{0, 0, 0, 0};
    std::vector<std::vector<PickFragment>> pixels;
    std::uint64_t offered = 0, capacity = 0; // entries offered and stored: offered > capacity lost some
};

struct RenderOptions {
    int width = 512, height = 512;
    FrameLook look;
    Aov aov = Aov::None;
    // Annotations drawn over the colour image (not over AOVs); null: none.
    const struct Annotations* annotations = nullptr;
    float scale = 1.0f; // text, line widths and glyphs scale with it
    // Draw into this GL framebuffer (e.g. a Qt widget's) instead of reading
    // the image back; 0 means read back into RenderResult::image.
    unsigned target_framebuffer = 0;
    bool present = false;
    // Off: the frame has no image output, neither read back nor presented (a
    // frame that only picks): the graph then culls what only the image
    // needs (AO, lighting, the VOIT resolve, the overlay, the read-back).
    bool image = true;
    // Finish the GPU's work at the end of each pass so that per-pass times
    // are real (costs some throughput; for --stats and benchmarks).
    bool time_passes = false;
    // Long passes (disk AO's gather: seconds per frame on llvmpipe) run in
    // bands and report after each (stage "disk AO"); returning false stops
    // them: the frame is finished without the rest and RenderResult::cancelled
    // is set (the caller throws; nothing throws through the frame graph).
    ProgressFn progress;
    // A pick riding on this frame (docs/picking.md): image pixels from the
    // top-left; clipped to the image. Fragments inside are listed by the
    // frame's own geometry passes; RenderResult::pick holds the lists.
    std::optional<PickRegion> pick;
    // Accumulate this frame into the running average of the frames before it
    // (look.aa): the renderer jitters each frame by a sub-pixel offset
    // (Halton 2, 3; the first frame unjittered) and restarts the average
    // whenever anything but the jitter changes (camera, size, surfaces,
    // look, annotations). RenderResult::aa_frames counts the frames in it.
    bool accumulate = false;
    // The camera is moving (the 3D view's drag frames): the volume is
    // sampled at look.volume.moving_step instead of look.volume.step, and
    // massive surfaces drawn to look.lod.moving_error_px.
    bool moving = false;
    bool restart_accumulation = false; // this frame starts the average (an export's first frame)
    // The sub-pixel offset of this frame instead of the renderer's sequence,
    // in pixels (x right, y down, each in [-0.5, 0.5]): exact-coverage
    // references place their sub-samples on a stratified grid.
    std::optional<glm::vec2> jitter;
    // Ray-traced AO (look.ao Raytraced): the AO term computed outside the
    // frame, one float channel per pixel (1 = unoccluded, NaN: background),
    // width x height, rows from the top as Image stores them; the frame
    // uploads it and lights with it. Required for such a frame's image.
    const Image* ao_image = nullptr;
};

// Test and benchmark hooks, apart from what a user asks for.
struct RenderHooks {
    // Read the slicemap back into RenderResult::slicemap (tests, the
    // voxel-grid reference).
    bool read_slicemap = false;
    // Rebuild the slicemap even if nothing changed (benchmarks time a new view).
    bool ao_force_voxelize = false;
    // Read the VOIT lists back: each pixel's list length into
    // RenderResult::oit_lists (rows top to bottom; tests).
    bool read_oit_lists = false;
    // Disk AO: read the element terms (one accessibility per node of the
    // concatenated hierarchy) into RenderResult::disk_terms, and each
    // gathered pixel's receiver (world point, w = its AO; world normal) into
    // RenderResult::disk_receivers (rows bottom-up as GL stores them; tests).
    bool read_disk = false;
};

// What the VOIT passes did this frame (all zero without translucent objects).
struct OitStats {
    std::uint64_t fragments = 0; // translucent fragments in front of the opaque surfaces
    // Fragments that found the pool full at its cap. They are merged per
    // pixel (order-independent: their opacity-weighted mean colour and their
    // total coverage 1 - prod(1 - alpha)) and composited behind the pixel's
    // sorted list. A frame that finds the cap too small is drawn again with a
    // per-pixel depth cut (a depth histogram of each pixel's fragments): each
    // pixel keeps its nearest fragments, up to a common level that fits the
    // pool, and merges those beyond. Merged fragments then all lie behind
    // the stored ones, and the pixel's error is at most the transmittance
    // reaching them times their coverage (docs/voit.md): merge_error_max is
    // the largest over the image, in [0, 1] per channel of linear colour.
    std::uint64_t merged = 0;
    std::uint64_t overflowed = 0; // of them, found the pool full (the depth cut did not make room: the looser bound)
    std::uint64_t merged_pixels = 0;
    double merge_error_max = 0;
    std::uint64_t capacity = 0; // nodes the pool held
    std::uint32_t max_list = 0; // longest pixel list
    std::uint64_t shaded = 0;   // fragments shaded (the rest were behind an opaque-enough front)
    std::uint64_t lists = 0;    // pixels with a list
    int redraws = 0;            // frames redrawn with a larger pool
};

// What the volume pass did this frame (all zero without a volume).
struct VolumeStats {
    bool drawn = false;
    double step_mm = 0;              // the sample step
    std::size_t chunks = 0;          // of the range index
    std::size_t empty_chunks = 0;    // mapped to zero opacity by the transfer function: never marched
    std::uint64_t rays = 0;          // pixels whose ray met the (clipped) volume
    std::uint64_t samples = 0;       // samples taken
    std::uint64_t skipped = 0;       // samples skipped in empty chunks
    std::uint64_t terminated = 0;    // rays ended early (transmittance below epsilon)
    std::uint64_t texture_bytes = 0; // the volume's 3D texture
    bool uploaded = false;           // the texture was (re)made this frame
};

// What the cluster culling did this frame (docs/lod.md): clusters of the
// surfaces with levels, those at each cell's selected level (tested) and
// what culled them; triangles drawn against the full meshes' (surfaces
// without levels count whole).
struct LodStats {
    bool used = false;
    std::uint64_t clusters = 0, tested = 0, culled_frustum = 0, culled_backface = 0, culled_occlusion = 0, drawn = 0;
    std::uint64_t triangles_drawn = 0, triangles_full = 0;
    int phases = 0;           // draw phases of the G-buffer (2: with last frame's visibility)
    double build_seconds = 0; // levels built for this frame (by core::SnapshotRenderer, for the first that asks)
};

// A label the overlay drew (a markup's name or value, one of
// Annotations::labels, an orientation letter, the scale bar's length): where
// it went and, so that what was drawn can be checked against the image, its
// text's coverage and its halo over the box (docs/text.md).
struct LabelBox {
    std::string text;
    glm::ivec2 lo{0}, hi{0};           // pixels from the image's top-left corner, hi exclusive: text and halo
    glm::vec2 anchor{0.0f};            // the point it labels (fixed labels: the box's centre)
    bool moved = false;                // away from its default place, joined to its anchor by a leader line
    bool fixed = false;                // an orientation letter or the scale bar's length: never moved
    glm::vec3 color{1.0f}, halo{0.0f}; // sRGB
    // (hi - lo) pixels each, row-major from the top row, 0..255: the glyphs'
    // coverage and the halo's alpha (the largest of overlapping glyphs').
    std::vector<std::uint8_t> coverage, halo_alpha;
    // A legend row (Annotations::legend; fixed too): the opaque half of its
    // colour swatch, the surface's colour in sRGB, pixels like lo/hi (hi exclusive).
    bool legend = false;
    glm::ivec2 swatch_lo{0}, swatch_hi{0};
};

struct RenderResult {
    Image image; // RGBA8 sRGB colour, or the AOV as floats
    graph::FrameStats stats;
    std::string gl_renderer;
    SliceMap slicemap;      // with RenderHooks::read_slicemap
    bool voxelized = false; // the slicemap was rebuilt this frame (else reused)
    int ao_frames = 0;      // still frames accumulated into the AO so far
    int aa_frames = 0;      // frames in the accumulated image (RenderOptions::accumulate)
    int aa_samples = 1;     // DSRAA sub-samples per pixel this frame (1: not used)
    double ao_guard = 0;    // guard band used by the slicemap, fraction of the viewport per side
    OitStats oit;
    VolumeStats volume;
    LodStats lod;
    std::vector<std::uint32_t> oit_lists; // with RenderHooks::read_oit_lists
    PickList pick;                        // with RenderOptions::pick
    // Disk AO: the hierarchy was built (some surface's on the CPU) and
    // uploaded this frame, the element passes ran (else both were kept from
    // an earlier frame); its size; with RenderHooks::read_disk, what it read.
    bool disk_built = false, disk_elements = false;
    std::size_t disk_nodes = 0, disk_triangles = 0;
    double disk_build_ms = 0; // CPU time of the hierarchy builds this frame
    bool cancelled = false;   // RenderOptions::progress asked to stop: the image is incomplete
    std::vector<float> disk_terms;
    std::vector<glm::vec4> disk_receivers; // 2 per pixel: (point, AO), (normal, 0)
    std::vector<LabelBox> labels;          // the overlay's labels (colour images with annotations)
};

} // namespace iso
