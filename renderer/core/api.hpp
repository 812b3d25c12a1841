// The small headless core API that the CLI and the GUI call. It holds no
// presentation (no printing, no widgets) and no file-format code of its own.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "io/color.hpp"
#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/frame/frame.hpp"
#include "io/volume.hpp"
#include "io/volume_io.hpp"

namespace iso::core {

const char* version();
// The git commit it was built from (12 hex digits, "-dirty" when the tree
// had changes; "unknown" when built outside a git checkout).
const char* commit();

// Loads a volume (file or DICOM folder). Throws iso::Error.
Volume open_volume(const std::string& path, const LoadOptions& opt = {});
Mesh open_mesh(const std::string& path);

// Lists the DICOM series of a folder or file without loading pixel data.
std::vector<SeriesInfo> list_series(const std::string& path);
// The series to offer first among `list`: the one with the most slices among
// those fit for 3D (SeriesInfo::for_3d), else among all (the first of equals);
// -1 for an empty list.
int suggested_series(const std::vector<SeriesInfo>& list);
// Opening one DICOM file means its series: the file's folder and the
// SeriesInstanceUID of the file (LoadOptions::series picks the series by it).
// None when `path` is not a DICOM file (by its extension, as load_volume
// tells) or its header cannot be read (then loading the file says why).
struct SeriesOfFile {
    std::string folder, uid;
};
std::optional<SeriesOfFile> dicom_series_of_file(const std::string& path);

// What `isoscope info` shows, as one JSON object: dims, spacing,
// index_to_lps (row-major 4x4), range, type, memory_bytes, format, source,
// storage (dense/sparse), metadata, warnings and, for DICOM, the series list.
nlohmann::json describe(const Volume& v);

// ---- rendering ------------------------------------------------------------

// A frame as a front end asks for it: the one description that the CLI's
// options, the desktop app's exports and sessions fill in. What it looks
// like is `look` (the same FrameLook the 3D view and the renderer read);
// the rest says what to draw it of, from where, at what size, and what else
// to put on it or record.
struct RenderRequest {
    std::vector<double> isos;      // render_input: for volume inputs (meshes are drawn as they are)
    std::string series;            // render_input: DICOM series choice
    std::string view = "anterior"; // patient view
    // The camera to draw with instead of `view`'s (a session's, the 3D
    // view's): its eye, target, up and field of view are kept, its near and
    // far planes fitted to the visible surfaces (as the 3D view does).
    std::optional<Camera> camera;
    int width = 1024, height = 1024;
    // Background, transparency, flat shading and ambient occlusion: "cone",
    // "disk" and "raytraced" (Embree, traced on the CPU before the frame)
    // darken the ambient light of the colour image; the ao AOV writes the
    // raw term (1 = unoccluded) of any method.
    FrameLook look;
    Aov aov = Aov::None;     // a buffer instead of the colour image
    float scale = 1.0f;      // annotation scale (text, lines, glyphs)
    bool annotations = true; // scale bar and orientation letters
    // With annotations: the legend, a row per visible surface (its name,
    // colour swatch, opacity and iso value with unit; core/legend.hpp).
    bool legend = true;
    // 3D Slicer markups (LPS mm; io/markups.hpp) drawn over the colour image,
    // with annotations on or off, never on AOVs: glyphs, labels (a point's,
    // else its list's name), lines with their name and length, angles with
    // their name and value (markup_label_text); dimmed where a surface hides
    // them (docs/markups.md, "Drawing markups"). `markups_files` names the
    // files they came from, recorded with their SHA-256 in the metadata.
    std::vector<Markup> markups;
    std::vector<std::string> markups_files;
    bool time_passes = false; // real per-pass GPU times (glFinish after each pass)
    // Ray-traced AO terms are cached by a hash of everything they depend on
    // (input file contents, iso values, surfaces, camera, size, radius, rays,
    // target error, the definition's version) under
    // this folder; empty: $ISOSCOPE_CACHE_DIR, else $XDG_CACHE_HOME/isoscope,
    // else ~/.cache/isoscope. "-": no cache.
    std::string cache_dir;
    ProgressFn progress;
    // A pick riding on this frame (core::pick() sets it): image pixels from the top-left.
    std::optional<PickRegion> pick;
    // The session file this state came from (core/session.hpp): its path
    // and SHA-256 go into the metadata.
    std::string session_file;
};

// The frame a request asks for: its options, checked (errors name the
// setting, never a flag), and its camera (the request's own, its planes
// fitted to the visible surfaces as the 3D view does, or the patient view's).
RenderOptions frame_options(const RenderRequest& req);
Camera frame_camera(const Scene& scene, const RenderRequest& req);

// "#rrggbb" <-> linear RGB, the one sRGB pair (io/color.hpp), for the core's callers.
using iso::hex_from_linear;
using iso::linear_from_hex;

struct RenderOutput {
    Image image;
    ImageMetadata meta; // embedded in the exported file
    graph::FrameStats stats;
    std::string gl_renderer;
    Camera camera;
    bool ao_cache_hit = false;    // the ray-traced AO term came from the cache
    OitStats oit;                 // translucent surfaces (zero without)
    VolumeStats volume;           // volume rendering (zero without)
    PickList pick;                // with RenderRequest::pick
    std::vector<LabelBox> labels; // the overlay's labels as placed and drawn (docs/text.md)
    int aa_frames = 1;            // jittered frames averaged (look.aa)
    double aa_change = 0;         // the last change of their mean (sRGB units; look.aa.tolerance)
    // Levels of detail and culling (docs/lod.md): the first frame's and the
    // last one's statistics (build_seconds: the levels built for this render),
    // and the first frame's passes (stats are the last one's).
    LodStats lod_first, lod;
    graph::FrameStats first_stats;
};

// How an export's accumulation ended: frames averaged and the last change
// of their mean between N/2 and N frames (RMS over the pixels that changed,
// sRGB units), and the words the image metadata records.
struct Convergence {
    RenderResult first; // the first frame's statistics (no image)
    int frames = 1;
    int samples = 1; // DSRAA's sub-samples in the first frame (the GL's limit may lower look.aa.samples)
    double change = 0;
    std::string text() const;
};
// Draws the frame of an export: colour images accumulate jittered frames
// (look.aa) until their mean changes by at most look.aa.tolerance between
// N/2 and N frames (checked at N = 4, 8, 16, ...) or look.aa.frames are
// drawn; cone AO draws at least look.ao_frames. Reports progress (stage
// "anti-aliasing") and throws Cancelled when asked to stop.
RenderResult render_converged(Scene& scene, const Camera& cam, RenderOptions ro, const RenderRequest& req,
                              Convergence& out);

// Renders the scene headlessly (its own EGL context, made on first use; the
// caller's EGL context, or none, is current again on return, so that any
// one thread at a time may call it) as asked: camera from the patient view or `req.camera`, annotations and markups, AO (cone,
// disk or ray-traced), AOVs; the output carries the metadata to embed
// (sources and their SHA-256, iso values, camera, matrices, markups files
// and the measurements drawn, the session file and its SHA-256). `isos` and `series` of the
// request are not used here. Throws iso::Error.
RenderOutput render_image(Scene& scene, const RenderRequest& req);

// Opens `input` into a new scene (a mesh file, or a volume whose `req.isos`
// surfaces are extracted) and render_image()s it: `isoscope render`.
RenderOutput render_input(const std::string& input, const RenderRequest& req);

} // namespace iso::core
