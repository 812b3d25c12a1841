// Sessions: what the user sees in the desktop app, as a small JSON file that
// reopens it (File > Save session / Open session, `isoscope gui S.json`) and
// that `isoscope render --session S.json` renders. The format is in
// docs/sessions.md: a version field, the input (path relative to the
// session's folder when it is below it, absolute otherwise; its SHA-256),
// the DICOM series, the surfaces (kind, value, name, source, "#rrggbb" sRGB
// colour, opacity, visibility, the post-processing they were extracted
// with), the 3D camera, window/level, view options, the markups (inline,
// as 3D Slicer markups JSON in LPS), and the volume look and crop box.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/markups.hpp"
#include "io/progress.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/surface/postprocess.hpp"
#include "renderer/frame/camera.hpp"

namespace iso::core {

// The version this isoscope writes and the only one it reads.
constexpr int kSessionVersion = 1;

struct SessionSurface {
    SurfaceInfo::Kind kind = SurfaceInfo::Kind::Iso;
    double value = 0; // iso value or label (mesh: unused)
    std::string name;
    std::string source;            // absolute path in memory
    std::string color = "#e6e6e6"; // sRGB, as colour pickers give it
    float opacity = 1.0f;
    bool visible = true;
    // What the surface was extracted with (iso and label surfaces), and the
    // part kept of it (an isolated component, a part within a box, the cuts).
    PostProcessOptions post;
    // A grown region: grown again from its seed, then `post` applied.
    std::optional<GrownFrom> grown;
};

// The desktop app's arrangement of its views (View > Layout), named as 3D
// Slicer names its layouts: Four-Up (2 x 2: 3D top left, axial top right,
// coronal and sagittal below), Conventional (the 3D view large above, the
// three slice views in a row below), and the One-Up layouts (one view alone:
// 3D only, axial, coronal or sagittal).
enum class ViewLayout : std::uint8_t { FourUp, Conventional, ThreeD, Axial, Coronal, Sagittal };
// "four_up", "conventional", "3d", "axial", "coronal", "sagittal" (the session file's names).
const char* view_layout_name(ViewLayout l);
std::optional<ViewLayout> view_layout_from_name(const std::string& name);

// One slice view's position and framing (LPS mm): its plane's origin (the
// slice: offset_mm is dot(origin, normal)), the point at the image's centre
// (its pan) and the size of a pixel (its zoom).
struct SliceViewState {
    glm::dvec3 origin{0.0};
    glm::dvec3 center{0.0};
    double pixel_mm = 1.0;
};
// The three slice views and the crosshair they share (crosshair_point).
struct SliceViewsState {
    glm::dvec3 crosshair{0.0};
    std::array<SliceViewState, 3> views{}; // axial, coronal, sagittal
};
// The state of the planes (default_planes' order), and back: onto the
// volume's default planes (their axes and steps), the crosshair first
// (set_crosshair), then each view's origin, centre (moved onto the plane)
// and pixel size.
SliceViewsState capture_slice_views(const std::array<SlicePlane, 3>& planes);
void apply_slice_views(const SliceViewsState& s, std::array<SlicePlane, 3>& planes);

struct Session {
    std::string input;                    // absolute path of the file or folder opened
    std::string input_sha256;             // empty: not recorded (save_session fills it in)
    std::string series;                   // DICOM series (LoadOptions::series); empty: the only one
    std::vector<SessionSurface> surfaces; // in the scene's order
    // The 3D view's camera: eye, target, up, field of view (near and far
    // are fitted to the surfaces when drawn). None: the anterior view.
    std::optional<Camera> camera;
    std::optional<WindowLevel> window; // the slice views' window/level
    // The 3D view's ambient occlusion: cone, raytraced or off (the file's
    // view.ao: true or false; view.ao_method "raytraced" when it is).
    AoMethod ao = AoMethod::Cone;
    bool transparency = true;    // the 3D view's transparency on (off: every surface opaque)
    std::vector<Markup> markups; // LPS mm
    // The desktop app's layout, slice views and whether its 3D view draws
    // the slice planes; none (a session saved before they were stored, or
    // by the CLI): the app's defaults (Four-Up, the volume's default planes).
    std::optional<ViewLayout> layout;
    std::optional<SliceViewsState> slice_views;
    bool slice_planes_in_3d = false;
    // The volume ray cast in the 3D view (the desktop app's Volume panel):
    // whether it is shown, its transfer function and mode (the other
    // VolumeLook settings are not stored: their defaults). None (a session
    // saved before it was stored, by the CLI, of a mesh): off, and the
    // file has no "volume" field.
    std::optional<VolumeLook> volume;
    // The crop box (LPS mm: min, max) cutting surfaces and volume alike
    // (FrameLook::clip.box); none: no crop, and no "clip" field.
    std::optional<std::pair<glm::dvec3, glm::dvec3>> clip_box;
    // Found while loading, not stored: e.g. the input changed since saving.
    std::vector<std::string> warnings;
};

// What the window shows, as a session (no file access: the SHA-256 is left
// empty); each surface's post-processing is its SurfaceInfo::post; the 3D
// view's AO (cone or off), transparency toggle, volume look (when it has a
// transfer function) and clip box come from `view`.
Session capture_session(const Scene& scene, const std::string& input, const std::string& series,
                        const std::optional<Camera>& camera, const std::optional<WindowLevel>& window,
                        const FrameLook& view, std::vector<Markup> markups);

// The JSON of a session stored at `session_path` (paths below its folder
// relative) and back. from_json checks every field and throws iso::Error
// naming `session_path` and the field; it does not touch the input.
nlohmann::ordered_json session_json(const Session& s, const std::string& session_path);
Session session_from_json(const nlohmann::json& j, const std::string& session_path);

// Writes the session atomically (the old file stays whole on failure),
// filling in the input's SHA-256 when it is empty. Throws iso::Error.
void save_session(const Session& s, const std::string& path);
// Reads and checks a session file: the JSON, every field, that the input
// exists; a changed input (SHA-256) is a warning. Throws iso::Error naming
// the file and the field.
Session load_session(const std::string& path);
// The same without looking at the input (no existence check, no hashing).
Session read_session(const std::string& path);

// The same state: same input, series, surfaces, camera, window, view
// options, markups, layout and slice views (the recorded SHA-256s and
// warnings aside).
bool same_state(const Session& a, const Session& b);

struct OpenedSession {
    Session session;
    std::unique_ptr<Scene> scene;
    std::vector<SurfaceId> surfaces; // the session's surfaces, in its order
};

// Builds the session's scene: opens the input with the series, extracts
// the iso and label surfaces (each with its post-processing, in the
// session's order; iso surfaces as the Surfaces panel makes them,
// Scene::extract_isosurface and add_isosurface), applies names, colours,
// opacities and visibility.
// Throws iso::Error (iso::Cancelled when `progress` returns false).
OpenedSession open_session(const Session& s, const ProgressFn& progress = {});
// load_session and open_session; the input's errors come prefixed with the session's path.
OpenedSession open_session(const std::string& path, const ProgressFn& progress = {});

// Which parts of a session's picture the session gives (the others are the
// caller's): its camera (else the frame's view), its markups (added to the
// frame's) and its AO method (else the frame's). The transparency toggle,
// the volume look (enabled, transfer function, mode) and the clip box are
// always the session's when it has them.
struct SessionParts {
    bool camera = true;
    bool markups = true;
    bool ao = true;
};

// The render request for the session's state: `frame` (size, scale,
// annotations, background, AO settings, ...: the caller's) with the parts
// `take` names from the session; `session_file` (may be empty) is recorded
// in the image's metadata with its SHA-256. `isoscope render --session` and
// the desktop app's File > Export image both build their request with it.
RenderRequest session_request(const Session& s, const std::string& session_file, RenderRequest frame,
                              const SessionParts& take = {});

} // namespace iso::core
