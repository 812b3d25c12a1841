// The workspace: the live form of a Session (docs/architecture.md,
// "Workspace"), what the desktop app shows and edits, with no Qt in it. It
// holds the scene (volume and surfaces with their looks), the 3D view's
// look (AO, transparency, volume look, crop box) and camera, the slice
// views' window/level, planes and crosshair, the layout, the markups and
// the selected one, the session file it was saved to and whether it changed
// since. Modelled on 3D Slicer's MRML scene: widgets observe it and change
// it; they hold no state of their own.
//
// Every change notifies the observers with the parts it touched (Part), so
// a view redraws for what concerns it, and `picture_key()` (what the 3D
// picture depends on) is derived from the same notifications: one key.
//
// Edits: `record(text, parts, change)` runs `change` (any sequence of the
// setters below) and returns a WorkspaceEdit, the state of the parts before
// and after; `restore(edit.before, edit.parts)` undoes it. The desktop app
// keeps them on its one QUndoStack (app/gui/app_context.hpp, WorkspaceCommand); a
// display-free caller keeps them in an EditHistory (below). One command
// type, written once: no edit knows how to undo itself.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/markups.hpp"
#include "io/progress.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"

namespace iso::core {

// What a change touched; an edit's parts are the ones it restores.
enum class Part : std::uint32_t {
    Data = 1u << 0,      // the input replaced (a new scene): every other part with it
    Surfaces = 1u << 1,  // surfaces added, removed, re-extracted, recoloured, shown or hidden
    Look = 1u << 2,      // the 3D view's look: AO, transparency, volume look, crop box
    Camera = 1u << 3,    // the 3D view's camera
    Window = 1u << 4,    // the slice views' window/level
    Slices = 1u << 5,    // the slice planes and their crosshair
    Layout = 1u << 6,    // the layout and the slice planes drawn in 3D
    Markups = 1u << 7,   // the measurements
    Selection = 1u << 8, // the selected measurement
    File = 1u << 9,      // the session file, saved or not
};
using Parts = std::uint32_t;
constexpr Parts operator|(Part a, Part b) { return Parts(a) | Parts(b); }
constexpr Parts operator|(Parts a, Part b) { return a | Parts(b); }
constexpr Parts& operator|=(Parts& a, Part b) { return a = a | Parts(b); }
constexpr bool has(Parts p, Part part) { return (p & Parts(part)) != 0; }
// The parts the 3D picture depends on (the window/level and the selection's
// table row do not change it; the selection highlights a markup: it does).
constexpr Parts kPictureParts = Part::Data | Part::Surfaces | Part::Look | Part::Camera | Part::Slices | Part::Layout |
                                Part::Markups | Part::Selection;
// The parts whose change is unsaved work (the view's camera, the slice
// positions and the window/level are kept in a session but are not edits).
constexpr Parts kEditedParts = Part::Surfaces | Part::Look | Part::Markups;

// The measurements with, for each, the .mrk.json files that hold it
// (canonical paths: loaded from or saved to), so loading a file again can
// offer to replace what came from it.
struct MarkupsState {
    std::vector<Markup> markups;
    std::vector<std::vector<std::string>> sources; // one per markup
    bool operator==(const MarkupsState&) const = default;
};

// A workspace's state, part by part (what an edit keeps of before and after).
struct WorkspaceState {
    struct Surface {
        SurfaceId id = 0;
        SurfaceInfo info;
        std::shared_ptr<const Mesh> mesh; // shared with the scene: never changed in place
    };
    std::vector<Surface> surfaces; // in the scene's order
    FrameLook look;
    std::optional<Camera> camera; // none: not set yet (the anterior view, fitted)
    WindowLevel window;
    std::array<SlicePlane, 3> planes{}; // axial, coronal, sagittal
    ViewLayout layout = ViewLayout::FourUp;
    bool slice_planes_in_3d = false;
    MarkupsState markups;
    std::optional<std::size_t> selected;
};

// The two states are the same in `parts` (surfaces: the same ids, settings
// and meshes; the same mesh object, or equal triangles).
bool same_parts(const WorkspaceState& a, const WorkspaceState& b, Parts parts);

// One edit: the state of the parts it touched, before and after.
struct WorkspaceEdit {
    std::string text; // what it did ("add iso 500", "move Ruler 1"): Edit > Undo TEXT
    Parts parts = 0;
    WorkspaceState before, after;
    // Not empty: the next edit with the same key and parts merges into this
    // one (the steps of one slider drag or spin-box run: one undo step).
    std::string merge_key;
    // Takes `next` in (after = next.after) when it continues this edit.
    bool merge(const WorkspaceEdit& next);
};

class Workspace {
public:
    // An empty workspace (nothing open); `look` is the 3D view's initial look
    // (the desktop app's: cone AO with still frames), kept across data.
    explicit Workspace(FrameLook look = {});
    ~Workspace();
    Workspace(const Workspace&) = delete;
    Workspace& operator=(const Workspace&) = delete;

    // ---- what is open ---------------------------------------------------
    // Replaces the data with `scene` (opened from `input`, DICOM `series`):
    // the volume's default planes and window, no markups, no crop, the
    // volume not shown, no session file; the look's AO and transparency stay.
    void reset(std::unique_ptr<Scene> scene, std::string input, std::string series);
    // A session's state (open_session made its scene): every part it keeps.
    // `session_path`: where it was read from (empty: unsaved work, such as a
    // recovery file).
    void adopt(OpenedSession opened, const std::string& session_path);
    // The state as a session (the input's SHA-256 left empty).
    Session session() const;
    bool has_data() const { return !input_.empty(); }
    const std::string& input() const { return input_; }
    const std::string& series() const { return series_; }
    Scene& scene() { return *scene_; }
    const Scene& scene() const { return *scene_; }
    // The scene is replaced by reset() and adopt() only; its surfaces change
    // through the setters below, so that observers hear of it.

    // ---- the session file ---------------------------------------------
    const std::string& session_path() const { return session_path_; }
    // Saved to (or opened from) `path`: the state now is the saved one.
    void mark_saved(const std::string& path);
    // Unsaved work: the edited parts (kEditedParts; of the look, the volume
    // look and the crop box) differ from the state last saved or opened (an
    // edit undone back to it is not a change).
    bool modified() const;
    // Makes the state unsaved work whatever it is (a recovered session).
    void mark_unsaved();

    // ---- parts, read ----------------------------------------------------
    const FrameLook& look() const { return live_.look; }
    const std::optional<Camera>& camera() const { return live_.camera; }
    const WindowLevel& window() const { return live_.window; }
    const std::array<SlicePlane, 3>& planes() const { return live_.planes; }
    ViewLayout layout() const { return live_.layout; }
    bool slice_planes_in_3d() const { return live_.slice_planes_in_3d; }
    const std::vector<Markup>& markups() const { return live_.markups.markups; }
    const MarkupsState& markups_state() const { return live_.markups; }
    std::optional<std::size_t> selected() const { return live_.selected; }
    // The state of `parts` now (surfaces: their ids, settings and meshes).
    WorkspaceState capture(Parts parts) const;

    // ---- parts, changed (each notifies its part) -------------------------
    // Throws iso::Error for a look out of range (validate) or a crop box
    // whose minimum exceeds its maximum on an axis (the scene would empty
    // without a word).
    void set_look(const FrameLook& look);
    void set_camera(const Camera& c);
    void set_window(const WindowLevel& w);
    void set_planes(const std::array<SlicePlane, 3>& planes);
    // Every plane through `lps`; the plane of `keep` stays (a point placed
    // on that view: the next one lands on the same slice). Nothing without a volume.
    void set_crosshair(const glm::dvec3& lps, std::optional<SliceOrientation> keep = std::nullopt);
    void set_layout(ViewLayout l);
    void set_slice_planes_in_3d(bool on);
    // The selection stays while its markup can only have stayed where it was
    // (edited, or markups added after it); after a removal it goes.
    void set_markups(MarkupsState m);
    // A row of the measurements (none: no selection); out of range: none.
    void select(std::optional<std::size_t> index);

    // Surfaces: what Scene does, notified.
    SurfaceId add_isosurface(PreparedMesh m, double iso, const PostProcessOptions& post = {},
                             std::optional<glm::vec3> color = std::nullopt);
    SurfaceId add_mesh(PreparedMesh m, SurfaceInfo info);
    // Colour, opacity, visibility, name, pickable (kind, value, source and
    // post-processing are the mesh's: replace_surface).
    void set_surface_info(SurfaceId id, const SurfaceInfo& info);
    void replace_surface(SurfaceId id, PreparedMesh m, double value, const PostProcessOptions& post);
    void remove_surface(SurfaceId id);
    // A planned component (plan_component, done off the GUI thread) as a
    // surface of its own, its parent hidden (3D Slicer's "keep selected
    // island": what is left on screen is the structure). Isolating again a
    // component that is already a surface adds nothing: `isolated.surface`
    // names the existing one and `added` is false (shown, its parent hidden).
    struct Isolation {
        IsolatedComponent isolated;
        bool added = true;
    };
    Isolation isolate(ComponentPlan plan);
    // The surface that already is this component of `from` (same parent,
    // same component of it, or `from` itself when it is a single isolated
    // component), if any.
    std::optional<SurfaceId> existing_component(const ComponentPlan& plan) const;

    // ---- edits -----------------------------------------------------------
    // Runs `change`, returning it as an edit of `parts` (the state before
    // and after). When `change` throws, the parts are put back as they were
    // and the exception goes on. An edit that changed nothing has equal
    // before and after (the caller may drop it: unchanged()).
    WorkspaceEdit record(std::string text, Parts parts, const std::function<void()>& change,
                         std::string merge_key = {});
    // Puts `parts` back as `s` has them (an undo: s = edit.before; a redo: edit.after).
    void restore(const WorkspaceState& s, Parts parts);
    static bool unchanged(const WorkspaceEdit& e) { return same_parts(e.before, e.after, e.parts); }

    // ---- observers ---------------------------------------------------------
    using Observer = std::function<void(Parts)>;
    // Called after every change with the parts it touched; returns a handle for unobserve.
    int observe(Observer o);
    void unobserve(int handle);
    // Counts the notifications of any of `parts` (it changes whenever one of
    // them does): a key for what depends on those parts, derived from the
    // notifications (the 3D view's ray-traced AO: data, surfaces, camera, look).
    std::uint64_t revision(Parts parts) const;
    // revision(kPictureParts): what the 3D picture depends on (the 3D view's
    // still frames restart when it changes).
    std::uint64_t picture_key() const { return revision(kPictureParts); }
    // Each notification's count (tests).
    std::uint64_t notifications() const { return notifications_; }

private:
    void notify(Parts parts);
    void restore_surfaces(const std::vector<WorkspaceState::Surface>& surfaces);
    std::unique_ptr<Scene> scene_;
    std::string input_, series_, session_path_;
    WorkspaceState live_;  // every part but the surfaces (the scene's)
    WorkspaceState saved_; // the edited parts when last saved or opened
    bool force_modified_ = false;
    std::vector<std::pair<int, Observer>> observers_;
    int next_observer_ = 1;
    std::array<std::uint64_t, 16> revisions_{}; // per Part bit: its notifications
    std::uint64_t notifications_ = 0;
    bool notifying_ = false;
    Parts pending_ = 0; // changes made by observers while notifying, told next
};

// Opens a session file into a new workspace (load_session, open_session, adopt).
// Throws iso::Error (iso::Cancelled when `progress` returns false).
std::unique_ptr<Workspace> open_workspace(const std::string& session_path, FrameLook look = {},
                                          const ProgressFn& progress = {});

// The history of edits for a caller without Qt (tests, scripts): Qt's
// QUndoStack's rules (a push drops what was undone; an edit with the merge
// key of the one on top merges into it) over the same WorkspaceEdit.
class EditHistory {
public:
    void push(WorkspaceEdit e);
    bool can_undo() const { return index_ > 0; }
    bool can_redo() const { return index_ < edits_.size(); }
    // The text of the step undo() / redo() would take (empty: none).
    std::string undo_text() const;
    std::string redo_text() const;
    bool undo(Workspace& w);
    bool redo(Workspace& w);
    std::size_t size() const { return edits_.size(); }
    std::size_t index() const { return index_; }
    void clear();

private:
    std::vector<WorkspaceEdit> edits_;
    std::size_t index_ = 0;
};

} // namespace iso::core
