// The desktop application's main window (docs/gui.md): it owns the
// workspace (renderer/core/workspace.hpp: what is open and every part a
// user edits), the one undo stack its edits go through and the background
// jobs, and arranges the views, docks, tool bars and menus that show and
// edit them (style.md 12: a model, commands). It holds no state of its
// own: each part below reads the workspace, observes its changes and sends
// it edits (app_context.hpp), and none of them calls back into the window.
//   views        View3D (view3d.hpp) and three SlicePanels, laid out by Layouts
//   docks        Surfaces, Volume, Measurements (with the isolated structures)
//   tool bars    window/level, 3D view, Measure, Structures
//   menus        File (files.hpp), Edit (undo, redo), View (layouts.hpp), Help
#pragma once

#include <array>
#include <functional>
#include <memory>

#include <QMainWindow>
#include <QString>

#include "app/gui/app_context.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/core/workspace.hpp"

class QUndoStack;

namespace iso::gui {

class CropBoxTool;
class Files;
class Jobs;
class Layouts;
class LoadWarnings;
class MeasureTools;
class MeasurementsPanel;
class SliceView;
class StructureTools;
class SurfacesPanel;
class UnsavedWork;
class View3D;
class Viewer;
class ViewToolBar;
class VolumePanel;
class WindowLevelBar;

namespace detail {
// What the window's parts refer to: made before the window's widgets and
// gone after them (a base class: constructed first, destroyed last), so
// that a part leaving with the window can still stop observing the workspace.
struct WindowModel {
    WindowModel();
    ~WindowModel();
    std::unique_ptr<core::Workspace> workspace_;
    std::unique_ptr<QUndoStack> undo_;
    std::unique_ptr<Jobs> jobs_;
    std::unique_ptr<AppContext> context_;
};
} // namespace detail

class MainWindow : private detail::WindowModel, public QMainWindow {
public:
    explicit MainWindow(QWidget* parent = nullptr);
    ~MainWindow() override;

    // ---- the model ---------------------------------------------------------
    core::Workspace& workspace() { return *workspace_; }
    const core::Workspace& workspace() const { return *workspace_; }
    core::Scene& scene() { return workspace_->scene(); }
    const core::Scene& scene() const { return workspace_->scene(); }
    // Edit > Undo / Redo: every edit of the workspace is one of its WorkspaceCommands.
    QUndoStack* undo_stack() const { return undo_.get(); }
    AppContext& context() { return *context_; }
    // A background job with a progress dialog runs (loading, extraction, ...).
    bool busy() const;

    // ---- File (files.hpp) ----------------------------------------------------
    Files* files() const { return files_; }
    UnsavedWork* unsaved_work() const { return unsaved_; }
    // File > Open's path: a volume file, DICOM folder or mesh, in the
    // background (a folder with several series asks which).
    void open_path(const QString& path, const QString& series = {});
    // File > Open session (`recovered`: the recovery file, opened as unsaved work).
    void open_session(const QString& path, bool recovered = false);
    // At start: offers to restore the recovery file of a run that ended
    // with unsaved work; `otherwise` runs when there is none or it was discarded.
    void offer_recovery(std::function<void()> otherwise = {});

    // ---- the parts -------------------------------------------------------------
    View3D* view3d() const { return view3d_; }
    Viewer* viewer() const; // the 3D view's viewer (null while there is nothing to draw)
    SliceView* slice_view(core::SliceOrientation o) const { return context_->slice_view(o); }
    WindowLevelBar* window_level_bar() const { return window_bar_; }
    ViewToolBar* view_toolbar() const { return view_bar_; }
    SurfacesPanel* surfaces_panel() const { return surfaces_; }
    VolumePanel* volume_panel() const { return volume_; }
    MeasureTools* measure_tools() const { return measure_; }
    MeasurementsPanel* measurements_panel() const { return measurements_; }
    StructureTools* structure_tools() const { return structures_; }
    Layouts* layouts() const { return layouts_; }
    CropBoxTool* crop_box() const { return crop_; }

    // Help > About's text (versions, the 3D view's GL renderer once it has
    // drawn) and Help > Mouse and keyboard's (help_menu.hpp).
    QString about_text() const;

protected:
    void dragEnterEvent(QDragEnterEvent* e) override;
    void dropEvent(QDropEvent* e) override;
    void closeEvent(QCloseEvent* e) override;

private:
    void add_views();
    void add_docks();
    void add_edit_menu();
    void add_view_and_help_menus();
    void watched(core::Parts parts); // the title, what needs data, the status after a load

    View3D* view3d_ = nullptr;
    WindowLevelBar* window_bar_ = nullptr;
    ViewToolBar* view_bar_ = nullptr;
    SurfacesPanel* surfaces_ = nullptr;
    VolumePanel* volume_ = nullptr;
    MeasureTools* measure_ = nullptr;
    MeasurementsPanel* measurements_ = nullptr;
    StructureTools* structures_ = nullptr;
    Layouts* layouts_ = nullptr;
    CropBoxTool* crop_ = nullptr;
    Files* files_ = nullptr;
    UnsavedWork* unsaved_ = nullptr;
    LoadWarnings* load_warnings_ = nullptr;
    int observer_ = 0;
};

} // namespace iso::gui
