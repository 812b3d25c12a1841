// The desktop application's main window (docs/gui.md): the 3D view
// and the axial, coronal and sagittal slice views of one core::Scene, a
// window/level bar, File > Open (files, DICOM folders, recent files, drag
// and drop) loading in the background, and a Surfaces dock adding
// isosurfaces in the background. Presentation only: loading, extraction,
// reslicing, outlines and sampling are the core's (renderer/core).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <QMainWindow>
#include <QString>
#include <QStringList>

#include "io/markups.hpp"
#include "io/progress.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/frame/annotations.hpp"

class QAction;
class QComboBox;
class QDockWidget;
class QDoubleSpinBox;
class QLabel;
class QMenu;
class QProgressDialog;
class QStackedWidget;
class QThread;
class QTimer;
class QUndoStack;
class QVBoxLayout;

namespace iso::core {
class Scene;
struct Session;
struct SliceViewsState;
enum class ViewLayout : std::uint8_t;
struct RenderRequest;
struct SessionParts;
} // namespace iso::core

namespace iso::gui {

// The window's markups with, for each, the .mrk.json files that hold it
// (canonical paths: the files it was loaded from or saved to), so loading a
// file again can offer to replace what came from it. What an undo step
// snapshots and restores.
struct MarkupsState {
    std::vector<Markup> markups;
    std::vector<QStringList> sources; // one per markup
};

class LoadWarnings;
class MeasureTools;
class StructureTools;
class MeasurementsPanel;
class SliceView;
class SurfacesPanel;
class Viewer;
class VolumePanel;
class ViewToolBar;

class MainWindow : public QMainWindow {
public:
    explicit MainWindow(QWidget* parent = nullptr);
    ~MainWindow() override;

    // File > Open's path: loads a volume file, DICOM folder or mesh in the
    // background (progress dialog with Cancel); on success it replaces the
    // scene, on failure a dialog names the file and the reason.
    // `series`: the DICOM series to load (LoadOptions::series: index or UID);
    // empty: the only one. A folder opened without a series has its series
    // listed first in the background (core::list_series); with several the
    // series chooser (series_dialog.hpp) asks which, and opens that one by
    // its UID (Cancel opens nothing); with one it opens directly.
    void open_path(const QString& path, const QString& series = {});
    // What is open: the file or folder and the DICOM series chosen (empty: none).
    const QString& path() const { return path_; }
    const QString& series() const { return series_; }
    // The Surfaces dock's "Add surface": extracts an isosurface of the
    // volume in the background (SurfacesPanel::add_surface).
    void add_surface(double iso);
    SurfacesPanel* surfaces_panel() const { return surfaces_; }
    // The Volume dock (volume_panel.hpp, volume_commands.cpp): the volume
    // ray cast in the 3D view and the crop box; its edits are undo steps.
    VolumePanel* volume_panel() const { return volume_; }
    // A background job (load or extraction) is running.
    bool busy() const { return job_ != nullptr; }

    const core::Scene& scene() const { return *scene_; }
    core::Scene& scene() { return *scene_; }
    SliceView* slice_view(core::SliceOrientation o) const { return views_[std::size_t(o)]; }
    Viewer* viewer() const { return viewer_; }
    ViewToolBar* view_toolbar() const { return view_bar_; }
    const core::WindowLevel& window_level() const { return window_; }
    void set_window_level(const core::WindowLevel& w);

    // The measurements (3D Slicer markups, LPS mm) the views draw, the
    // measurements panel lists, sessions and exported images carry.
    const std::vector<Markup>& markups() const { return state_.markups; }
    // Replaces them, from no file, outside the undo stack (a session restoring its markups).
    void set_markups(std::vector<Markup> m);
    const MarkupsState& markups_state() const { return state_; }
    // An edit of the markups, one step of Edit > Undo ("Undo TEXT"): the
    // state becomes `after`; undo restores `before` (by default the
    // current state; a drag passes the state at its press, having shown
    // its steps through show_markups).
    void edit_markups(const QString& text, MarkupsState after, std::optional<MarkupsState> before = {});
    // Shows `s` without an undo step (the live steps of a drag; the undo commands).
    void show_markups(MarkupsState s);
    // Edit > Undo / Redo: every markup edit goes through it.
    QUndoStack* undo_stack() const { return undo_; }
    // The markup the Measurements panel's selected row names: drawn
    // highlighted in the views (none: no row selected).
    std::optional<std::size_t> selected_markup() const { return selected_; }
    // Selects it (the panel's row follows) and, with `centre`, moves the
    // slice views' crosshair to its first point and the 3D view's target
    // there (the camera keeps its distance and direction).
    void select_markup(std::optional<std::size_t> index, bool centre = true);
    // The slice views' crosshair to `lps` and the 3D view's target there (its distance and direction kept).
    void centre_on(const glm::dvec3& lps);
    // Moves the slice views' shared crosshair to `lps` (a 3D pick): each
    // plane through it, but the plane of `keep` stays where it is (a point
    // placed on that view: the next one lands on the same slice).
    void set_crosshair(const glm::dvec3& lps, const SliceView* keep = nullptr);
    // The pick readout and the Ruler / Angle tools; the Measurements dock.
    MeasureTools* measure_tools() const { return tools_; }
    MeasurementsPanel* measurements_panel() const { return measurements_; }
    // The Isolate and Distance tools; their table of isolated structures is in the Measurements dock.
    StructureTools* structure_tools() const { return structures_; }

    // Layouts and the slice planes in the 3D view (layouts.cpp, docs/gui.md
    // "Layouts"). View > Layout: Four-Up (2 x 2), Conventional, 3D only,
    // or one slice view alone; the views are moved and shown or hidden, not
    // made again (the 3D view keeps its GL context, camera and AO).
    core::ViewLayout layout() const;
    void set_layout(core::ViewLayout l);
    QAction* layout_action(core::ViewLayout l) const;
    // View > Slice planes in 3D: the 3D view draws each slice plane's outline
    // in the volume (core::slice_outline_3d) in its colour and the crosshair point.
    bool slice_planes_in_3d() const;
    void set_slice_planes_in_3d(bool on);
    QAction* slice_planes_action() const { return slice_planes_3d_; }
    // The slice views' planes (axial, coronal, sagittal), and setting them
    // from a session's state (each view keeps the framing it gets).
    const std::array<core::SlicePlane, 3>& planes() const { return planes_; }
    void set_slice_views(const core::SliceViewsState& s);

    // Sessions and export (app/gui/session_io.cpp, docs/sessions.md).
    // What the window shows as a core::Session (input, series, surfaces,
    // the 3D view's camera and AO, window/level, markups, the layout and
    // the slice views).
    core::Session current_session() const;
    // The session file last saved or opened (empty: none).
    const QString& session_path() const { return session_path_; }
    // File > Save session / Open session: in the background; an open
    // replaces the scene and restores the camera, window/level and markups.
    // `then` runs after a successful save (which marks the state saved:
    // the undo stack's clean state, the recovery file removed).
    // `recovered`: the session is the recovery file, so it opens as unsaved
    // work (no session file named, the title marked modified).
    void save_session(const QString& path, std::function<void()> then = {});
    void open_session(const QString& path, bool recovered = false);

    // Unsaved work (unsaved_work.cpp, docs/gui.md "Unsaved work").
    // Surfaces or measurements changed since the last session save or open:
    // the undo stack is not at its clean state (the title shows "*").
    bool modified() const;
    // Runs `proceed` at once when nothing is unsaved; else asks first (a
    // window-modal box named "unsaved": Save, Discard, Cancel): Save saves
    // the session (to the current session file, else where a file dialog
    // says) and proceeds only when that succeeded; Discard proceeds; Cancel
    // does nothing. `doing` says what would discard it ("quitting").
    void ask_to_save(const QString& doing, std::function<void()> proceed);
    // Where autosave writes the session while there is unsaved work: beside
    // the settings (QStandardPaths::AppConfigLocation), recovery.isoscope.json.
    static QString recovery_path();
    // Autosave's period in ms: 60000, or ISOSCOPE_AUTOSAVE_MS when set.
    void set_autosave_interval(int ms);
    int autosaves() const { return autosaves_; } // recovery files written so far
    // At start: when a recovery file exists (the app was killed or crashed
    // with unsaved work), offers to restore it (a box named "recovery":
    // Restore opens it as unsaved work, Discard deletes it); the environment
    // variable ISOSCOPE_RECOVERY=restore or discard answers without asking.
    // `otherwise` runs when there is none or it was discarded.
    void offer_recovery(std::function<void()> otherwise = {});
    // File > Export image: renders the current state as `isoscope render
    // --session` does (the session file it names: the current one when
    // the state is unchanged since it was saved or opened, else PATH.session.json
    // written next to the image).
    void export_image(const QString& path, const core::RenderRequest& frame, const core::SessionParts& take);
    // File > Export to DICOM: the figure as a Secondary Capture into `folder`
    // (core::export_dicom), in this session's series (dicom_series_).
    void export_dicom(const QString& folder, const core::RenderRequest& frame, const core::SessionParts& take);
    // File > Save surfaces: one surface in LPS mm (.stl, .ply, .obj, .vtp).
    void save_surface(std::uint32_t id, const QString& path);

    // Help > About's text: isoscope's version and its libraries'
    // (core::component_versions), Qt's, and the 3D view's GL renderer once
    // it has drawn. Help > Mouse and keyboard's text (HTML).
    QString about_text() const;
    static QString bindings_html();

protected:
    void dragEnterEvent(QDragEnterEvent* e) override;
    void dropEvent(QDropEvent* e) override;
    void closeEvent(QCloseEvent* e) override;

private:
    struct Job;
    // Runs `work` on a worker thread with a progress dialog; `done` runs on
    // the GUI thread with the exception the work threw (null: success) unless
    // the job was abandoned. `abandonable`: Cancel closes the dialog at once
    // and drops the result (the work touches nothing the window shares).
    void run_job(const QString& title, bool abandonable, std::function<void(const ProgressFn&)> work,
                 std::function<void(std::exception_ptr)> done);
    void finish_job(const std::shared_ptr<Job>& job);
    void load(const QString& path, const QString& series);
    void choose_series(const QString& folder);
    void set_scene(std::unique_ptr<core::Scene> scene, const QString& path, const QString& series);
    void show_error(const QString& title, const QString& what, std::exception_ptr e);
    void refresh_slices();
    void add_structure_tools();
    void update_3d();
    void slice_clicked(SliceView& view, QPointF pixel);
    void slice_scrolled(SliceView& view, double steps);
    void remember_recent(const QString& path);
    void rebuild_recent_menu();
    void open_file_dialog();
    void open_folder_dialog();
    void add_session_actions(QMenu* file); // File menu entries (session_io.cpp)
    void add_window_level_bar();           // the window/level tool bar
    void add_file_and_edit_menus();        // File, and Edit with the undo stack
    void add_view_and_help_menus();        // View (docks, tool bars) and Help (bindings, About): help_menu.cpp
    void add_layout_actions(QMenu* view);  // View > Layout and Slice planes in 3D (layouts.cpp)
    void update_slice_planes_3d();         // the 3D view's slice outlines and crosshair, from the planes
    void wire_surface_undo();              // the Surfaces panel's undo steps (surface_commands.cpp)
    void watch_unsaved_work();             // the title's "*" and autosave (unsaved_work.cpp)
    void enable_data_actions();            // what needs a volume or a surface (data_actions.cpp)
    // The Volume dock, tabbed with `beside`; its state into the 3D view
    // (look and clip); a session's volume look and crop box into it; the
    // crop box's edges while cropping (volume_commands.cpp).
    void add_volume_dock(QDockWidget* beside);
    void apply_volume();
    void restore_volume(const core::Session& s);
    std::vector<Annotations::Line> crop_box_lines() const;
    void autosave();
    void wait_for_autosave();
    void remove_recovery_file();

    std::unique_ptr<core::Scene> scene_;
    std::array<core::SlicePlane, 3> planes_{};
    std::array<SliceView*, 3> views_{};
    Viewer* viewer_ = nullptr;
    ViewToolBar* view_bar_ = nullptr;
    QStackedWidget* view3d_ = nullptr; // the placeholder label or the viewer
    QLabel* placeholder_ = nullptr;
    core::WindowLevel window_;
    QComboBox* window_preset_ = nullptr;
    QDoubleSpinBox* center_ = nullptr;
    QDoubleSpinBox* width_ = nullptr;
    SurfacesPanel* surfaces_ = nullptr;
    VolumePanel* volume_ = nullptr;
    QMenu* recent_menu_ = nullptr;
    QString path_, series_;
    MarkupsState state_;
    std::optional<std::size_t> selected_;
    QUndoStack* undo_ = nullptr;
    QString session_path_;
    QString dicom_series_; // the series this session's DICOM figures go to (set by the first)
    MeasureTools* tools_ = nullptr;
    LoadWarnings* load_warnings_ = nullptr; // what opening the data said
    MeasurementsPanel* measurements_ = nullptr;
    StructureTools* structures_ = nullptr;
    std::shared_ptr<Job> job_;                  // the job the window waits for
    std::vector<std::shared_ptr<Job>> running_; // every worker still running (abandoned ones too)
    bool updating_window_ = false;
    std::uint8_t layout_ = 0;                  // a core::ViewLayout
    std::array<QAction*, 6> layout_actions_{}; // by core::ViewLayout
    QMenu* layout_menu_ = nullptr;
    QAction* slice_planes_3d_ = nullptr;
    QTimer* autosave_timer_ = nullptr;
    QThread* autosave_thread_ = nullptr; // the recovery file being written (null: none)
    bool edited_since_autosave_ = false, closing_ = false;
    int autosaves_ = 0;
    std::pair<std::string, std::string> input_hash_; // the input and its SHA-256, hashed once for autosaves
};

} // namespace iso::gui
