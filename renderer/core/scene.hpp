// The core Scene that both front ends use: `isoscope render` and
// `isoscope view` build one, the Qt widget draws it. It holds what was
// opened (a volume, mesh files), the surfaces made from them as handles with
// the properties a user edits (colour, opacity, visibility, pickable), and
// the verbs: render, export mesh, export image (pick and measure are
// core/pick.hpp and core/measure.hpp). Modelled on Polyscope's structures (include/polyscope/structure.h).
// Errors name the operation and the file, never a command-line flag: the
// CLI maps them (app/cli/main.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "io/dicom_capture.hpp"
#include "io/image.hpp"
#include "io/mesh.hpp"
#include "renderer/core/surface_lod.hpp"
#include "io/progress.hpp"
#include "io/volume.hpp"
#include "io/volume_io.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/grow.hpp"
#include "renderer/surface/postprocess.hpp"
#include "renderer/gpu/renderer.hpp"
#include "renderer/frame/camera.hpp"

namespace iso::core {

struct OutlineIndex;

// A surface of the scene: 1-based, the value the id AOV and picking report.
using SurfaceId = std::uint32_t;

struct SurfaceInfo {
    enum class Kind { Iso, Label, Mesh };
    std::string name; // "iso 500", "label 3", the mesh file's name
    Kind kind = Kind::Mesh;
    double value = 0;      // iso value or label
    std::string source;    // the file or folder it came from
    glm::vec3 color{0.9f}; // linear RGB albedo
    float opacity = 1.0f;  // 0..1
    bool visible = true, pickable = true;
    // How an Iso or Label surface was made from the volume (smoothing,
    // decimation, keep-largest, the part kept): a session restores the
    // surface by extracting `value` again with these.
    PostProcessOptions post;
    // A grown region (kind Mesh): its seed and range. A session grows it
    // again (then applies `post`: the cuts made on it).
    std::optional<GrownFrom> grown;
    bool operator==(const SurfaceInfo&) const = default;
};

// A mesh with what the scene keeps beside it: its bounds and its slice
// outlines' block index (slices.hpp). prepare_mesh works both out, on a
// worker: at 32 M triangles they take a third of a second, which adding the
// mesh on the GUI thread then does not. A plain Mesh converts to one whose
// bounds the scene works out when it takes it, and its index at first use.
struct PreparedMesh {
    PreparedMesh() = default;
    PreparedMesh(Mesh m); // NOLINT: implicit, so that every Mesh taker takes one
    std::shared_ptr<const Mesh> mesh;
    std::optional<Bounds> bounds;
    std::shared_ptr<const OutlineIndex> outline;
};
PreparedMesh prepare_mesh(Mesh m);

// What a frame draws, taken at one moment: each surface slot's mesh
// (shared and never changed in place: a replaced mesh is a new one), a
// version that changes whenever the slot's mesh does, and its drawing
// properties. A render thread draws a snapshot while the GUI thread goes on
// editing the scene (the desktop app's still frames).
struct SceneSnapshot {
    struct Surface {
        std::shared_ptr<const Mesh> mesh; // null: removed
        std::uint64_t version = 0;
        SceneObject object;
        std::shared_ptr<SurfaceLod> lod; // its levels of detail, built once for every renderer (null: removed)
    };
    std::vector<Surface> surfaces; // slot i is surface id i + 1
    Bounds bounds;                 // of the visible surfaces (Scene::bounds)
    // The volume (ray cast when the frame's look.volume asks; null: none),
    // a version that changes with it, and its range index when one was made
    // (the renderer makes one otherwise).
    std::shared_ptr<const Volume> volume;
    std::uint64_t volume_version = 0;
    std::shared_ptr<const ChunkIndex> volume_index;
};

// Draws snapshots in the current GL context, keeping its GPU copies across
// calls and uploading only the slots whose version changed; renderer
// object ids equal the surface ids. Scene::render draws through one; a
// thread with its own context keeps another.
class SnapshotRenderer {
public:
    SnapshotRenderer();
    ~SnapshotRenderer();
    RenderResult render(const SceneSnapshot& s, const Camera& camera, const RenderOptions& opt);
    Renderer& renderer();                                 // made on first use in the current context
    void release();                                       // with the context current, before it goes
    bool started() const { return renderer_ != nullptr; } // GPU resources made and not released
    // Levels of detail a frame asks for and lacks are built in the
    // background (interactive views: the frames meanwhile draw every
    // triangle) instead of inside the frame (the CLI, exports).
    void set_background_lod(bool on) { background_lod_ = on; }

private:
    double upload_lod(const SceneSnapshot& s, const RenderOptions& opt);
    std::unique_ptr<Renderer> renderer_;
    std::vector<std::uint64_t> uploaded_;   // per slot: the version on the GPU
    std::vector<const void*> lod_uploaded_; // per slot: the levels on the GPU (null: none)
    bool background_lod_ = false;
    std::uint64_t volume_version_ = 0; // of the volume handed to the renderer
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    // ---- content ----------------------------------------------------------
    // Opens a file or DICOM folder: a mesh file (is_mesh_path) becomes a
    // surface and its id is returned; anything else is loaded as the scene's
    // volume (replacing an earlier one) and 0 is returned. Throws iso::Error.
    SurfaceId open(const std::string& path, const LoadOptions& opt = {});
    // Makes `v` the scene's volume (replacing an earlier one), as open()
    // does for a volume file; `source` names it (metadata, errors).
    void set_volume(Volume v, const std::string& source);
    bool has_volume() const;
    const Volume& volume() const; // throws without one
    // The volume as the scene shares it (with snapshots and background work
    // that must outlive a replacement); null without one.
    std::shared_ptr<const Volume> shared_volume() const;
    const std::string& volume_source() const;
    // Isosurfaces of the volume, in increasing iso order, coloured skin to
    // bone; each gets an empty-surface warning when outside the value range.
    // `seconds`, when given, gets each step's time added (isoscope mesh).
    std::vector<SurfaceId> add_isosurfaces(std::vector<double> isos, const ExtractOptions& extract = {},
                                           const PostProcessOptions& post = {}, ProgressFn progress = {},
                                           ExtractSeconds* seconds = nullptr);
    // One surface per label (empty: every non-zero label) of a label map.
    std::vector<SurfaceId> add_label_surfaces(const std::vector<double>& labels, const ExtractOptions& extract = {},
                                              const PostProcessOptions& post = {}, ProgressFn progress = {},
                                              ExtractSeconds* seconds = nullptr);
    SurfaceId add_mesh(PreparedMesh m, SurfaceInfo info);

    // ---- surfaces made off the GUI thread ----------------------------------
    // The isosurface of the volume at `iso`, post-processed, as a mesh; the
    // scene is not changed (with an empty-surface warning outside the value
    // range). Safe on a worker thread while another thread renders or edits
    // the scene's surfaces: it reads only the volume, which must stay (no
    // open() meanwhile). The volume's range index (per-chunk min/max) is made
    // on the first call and reused by later ones with the same chunk size, so
    // a moved iso value visits only the chunks whose min/max contain it.
    // Throws iso::Cancelled when `progress` returns false.
    Mesh extract_isosurface(double iso, const ExtractOptions& extract = {}, const PostProcessOptions& post = {},
                            ProgressFn progress = {}) const;
    // The volume's value range (finite samples), computed once; throws without a volume.
    ValueRange value_range() const;
    // Adds a mesh extract_isosurface made: kind Iso, name "iso <value>",
    // `post` recorded, the volume as its source. Colour: the given one, else
    // the next along the skin-to-bone palette for the n surfaces already
    // there (surface_color(n, max(n + 1, 2)): skin, bone, then other hues).
    SurfaceId add_isosurface(PreparedMesh m, double iso, const PostProcessOptions& post = {},
                             std::optional<glm::vec3> color = std::nullopt);
    // Replaces a surface's mesh (a moved iso slider, other post-processing);
    // colour, opacity and visibility stay. An Iso surface whose name was the
    // automatic "iso <old>" is renamed "iso <value>". The renderer uploads
    // the new mesh on the next render, into the same object id.
    void replace_surface(SurfaceId id, PreparedMesh m, double value, const PostProcessOptions& post);
    // Removes a surface: its id is never reused (the others keep theirs),
    // surfaces() no longer lists it, info() and mesh() throw for it, and the
    // renderer drops its GPU copy on the next render.
    void remove_surface(SurfaceId id);
    // Puts a removed surface back under its id (an undone removal): the mesh
    // and properties given, its place in surfaces() the one it had; the
    // renderer uploads it again on the next render. Throws iso::Error when
    // `id` was never added or is not removed.
    void restore_surface(SurfaceId id, Mesh m, SurfaceInfo info);
    bool has_surface(SurfaceId id) const; // added and not removed
    // The surface's mesh as the scene shares it (with snapshots, undo steps).
    std::shared_ptr<const Mesh> shared_mesh(SurfaceId id) const;
    // Puts surface `id` (added once) into exactly this state: restored when
    // removed, its mesh replaced when it is another object (the renderer
    // uploads only then), its properties set. An undo step's way back.
    void set_surface(SurfaceId id, std::shared_ptr<const Mesh> m, SurfaceInfo info);

    std::vector<SurfaceId> surfaces() const; // in the order added (removed ones left out)
    SurfaceInfo& info(SurfaceId id);         // edit freely; the next render shows it
    const SurfaceInfo& info(SurfaceId id) const;
    const Mesh& mesh(SurfaceId id) const;
    // The mesh's outline index (slices.hpp): prepare_mesh's, else made on
    // first use (slice views outline every visible surface on each slice step).
    std::shared_ptr<const OutlineIndex> outline_index(SurfaceId id) const;
    Bounds bounds() const; // of the visible surfaces
    // The volume's index box [0, n-1] in LPS mm (empty without a volume).
    Bounds volume_bounds() const;
    // What a frame of `look` draws: the visible surfaces, and the volume's
    // box when the look ray casts it (within the clip box, if any).
    Bounds bounds(const FrameLook& look) const;
    // Every file or folder opened, in order (image metadata, cache keys).
    std::vector<std::string> sources() const;

    // ---- verbs ------------------------------------------------------------
    // A camera looking from `view` at the visible surfaces, fitted to them.
    Camera camera(PatientView view, double aspect) const;
    Camera camera(PatientView view, double aspect, const FrameLook& look) const; // fitted to bounds(look)
    // Renders with the caller's GL 4.5 context current. GPU resources live in
    // that context across calls (first call: the meshes are uploaded); call
    // release_gpu() with it current before the context goes.
    RenderResult render(const Camera& camera, const RenderOptions& opt);
    void release_gpu();
    // Whether render() made GPU resources (its renderer, the meshes'
    // copies) that release_gpu() has not freed yet.
    bool has_gpu_data() const;
    // Interactive views: levels of detail are built in the background, not
    // inside a frame (SnapshotRenderer::set_background_lod).
    void set_background_lod(bool on);
    // Whether surface `id`'s levels of detail are built (benchmarks wait for them).
    bool lod_ready(SurfaceId id) const;
    // The surfaces as they are now, for a renderer on another thread.
    SceneSnapshot snapshot() const;
    // The GPU renderer (tests, benchmarks); made on first use in the current context.
    Renderer& renderer();
    // Writes a surface in LPS mm (.stl, .ply, .obj, .vtp; tagged LPS).
    void export_mesh(SurfaceId id, const std::string& path) const;

private:
    std::vector<SurfaceId> add_extracted(std::vector<Mesh> meshes, SurfaceInfo::Kind kind,
                                         const std::vector<double>& values, const PostProcessOptions& post);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Writes an image (.png, .tif, .exr) with its metadata; never leaves a
// half-written file.
void export_image(const Image& image, const ImageMetadata& meta, const std::string& path);

// Writes a figure of the scene as a DICOM Secondary Capture in folder `dir`
// (io/dicom_capture.hpp): in the source's study when the scene's volume came
// from DICOM, else a new study; the series the options name, else the
// folder's isoscope series of that study, else a new one.
DicomCaptureResult export_dicom(const Scene& scene, const Image& image, const ImageMetadata& meta,
                                const std::string& dir, const DicomCaptureOptions& opt = {});

// Surface colours for iso values in increasing order (linear RGB): skin,
// bone, then ten other hues, each clearly apart from the one before (on the
// slices' grey too); past twelve, generated hues that do not repeat. A lone
// surface (count 1) is bone.
glm::vec3 surface_color(std::size_t index, std::size_t count);

} // namespace iso::core
