#include "app/gui/main_window.hpp"

#include <QDockWidget>
#include <QDragEnterEvent>
#include <QDropEvent>
#include <QFileInfo>
#include <QGridLayout>
#include <QMenuBar>
#include <QMimeData>
#include <QStatusBar>
#include <QTimer>
#include <QUndoStack>
#include <QTableWidget>
#include <QVBoxLayout>

#include "app/gui/crop_box.hpp"
#include "app/gui/data_actions.hpp"
#include "app/gui/files.hpp"
#include "app/gui/help_menu.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/layouts.hpp"
#include "app/gui/load_warnings.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/measurements_panel.hpp"
#include "app/gui/slice_panel.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/structure_tools.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/unsaved_work.hpp"
#include "app/gui/view3d.hpp"
#include "app/gui/view_toolbar.hpp"
#include "app/gui/viewer.hpp"
#include "app/gui/volume_panel.hpp"
#include "app/gui/window_level_bar.hpp"
#include "renderer/core/scene.hpp"

namespace iso::gui {

namespace detail {
WindowModel::WindowModel()
    : workspace_(std::make_unique<core::Workspace>(ViewerOptions::interactive_look())),
      undo_(std::make_unique<QUndoStack>()) {}
WindowModel::~WindowModel() = default;
} // namespace detail

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
    setWindowTitle("isoscope[*]");
    setAcceptDrops(true);
    resize(1280, 900);
    jobs_ = std::make_unique<Jobs>(this);
    context_ = std::make_unique<AppContext>(*workspace_, *undo_, *jobs_, *this);
    jobs_->message = [this](const QString& m) { statusBar()->showMessage(m); };

    add_views();
    files_ = new Files(*context_);
    unsaved_ = new UnsavedWork(*context_, *files_);
    files_->add_menu(menuBar()->addMenu("&File"));
    add_edit_menu();
    window_bar_ = new WindowLevelBar(*context_, this);
    addToolBar(window_bar_);
    view_bar_ = new ViewToolBar(*context_, this);
    addToolBar(view_bar_);
    addToolBarBreak(); // the tools on a row of their own: none hides in an overflow at 1280 pixels
    measure_ = new MeasureTools(*context_);
    structures_ = new StructureTools(*context_);
    add_docks();
    files_->add_markups_actions([this] { measurements_->load_dialog(); }, [this] { measurements_->save_dialog(); });
    add_view_and_help_menus();
    load_warnings_ = new LoadWarnings(this);
    statusBar()->addPermanentWidget(load_warnings_);
    statusBar()->showMessage("Ready");
    // The tools take the views' clicks: each new 3D view, and the slice views now.
    view3d_->viewer_made.push_back([this](Viewer& v) {
        measure_->attach(v); // a markup point first, then the crop box's handles
        crop_->attach(v);
    });
    measure_->other_tool_click = [this](Viewer& v, QPointF p) { structures_->viewer_click(v, p); };
    measure_->other_slice_click = [this](const glm::dvec3& lps) { return structures_->slice_click(lps); };
    measure_->other_tool_press = [this](Viewer& v, QPointF p) { return structures_->outline_press(v, p); };
    measure_->other_tool_move = [this](QPointF p) { structures_->outline_move(p); };
    measure_->other_tool_release = [this](Viewer& v, QPointF p, bool dragged) {
        structures_->outline_release(v, p, dragged);
    };
    crop_ = new CropBoxTool(*context_);
    for (SliceView* v : context_->slices) {
        measure_->attach(*v); // a markup point first, then the crop box's sides
        crop_->attach(*v);
    }
    observer_ = workspace_->observe([this](core::Parts p) { watched(p); });
    watched(core::Parts(core::Part::Data));
}

MainWindow::~MainWindow() {
    workspace_->unobserve(observer_);
    // The undo stack's signals reach the parts (its actions, the tools): no more.
    undo_->disconnect();
    undo_->clear();
    // Workers still running (an abandoned load, an extraction, an autosave)
    // finish before the workspace they may read goes.
    jobs_->wait_all(true);
    delete surfaces_; // its re-extractions read the scene: they stop first
    surfaces_ = nullptr;
    // The 3D view releases its GL objects through the scene: it goes first.
    delete view3d_;
    view3d_ = nullptr;
}

bool MainWindow::busy() const { return jobs_->busy(); }

Viewer* MainWindow::viewer() const { return view3d_ ? view3d_->viewer() : nullptr; }

void MainWindow::open_path(const QString& path, const QString& series) { files_->open_path(path, series); }

void MainWindow::open_session(const QString& path, bool recovered) { files_->open_session(path, recovered); }

void MainWindow::offer_recovery(std::function<void()> otherwise) { unsaved_->offer_recovery(std::move(otherwise)); }

QString MainWindow::about_text() const { return gui::about_text(viewer()); }

// ---- arrangement ---------------------------------------------------------------------

// The views: 3D top left, axial top right, coronal and sagittal below (Four-Up; Layouts moves them).
void MainWindow::add_views() {
    auto* central = new QWidget(this);
    auto* grid = new QGridLayout(central);
    grid->setContentsMargins(2, 2, 2, 2);
    grid->setSpacing(2);
    view3d_ = new View3D(*context_, central);
    context_->viewer = [this] { return view3d_ ? view3d_->viewer() : nullptr; };
    std::array<QWidget*, 4> cells{view3d_, nullptr, nullptr, nullptr};
    const core::SliceOrientation orientations[] = {core::SliceOrientation::Axial, core::SliceOrientation::Coronal,
                                                   core::SliceOrientation::Sagittal};
    for (int i = 0; i < 3; ++i) {
        auto* panel = new SlicePanel(orientations[i], central); // the view, its slider and Fit
        panel->view()->set_workspace(workspace_.get());
        context_->slices[std::size_t(i)] = panel->view();
        cells[std::size_t(i) + 1] = panel;
    }
    setCentralWidget(central);
    layouts_ = new Layouts(*context_, grid, cells);
}

// Surfaces above Volume (tabbed), Measurements below with the isolated structures' table.
void MainWindow::add_docks() {
    auto* dock = new QDockWidget("Surfaces", this);
    dock->setObjectName("surfaces");
    surfaces_ = new SurfacesPanel(*context_, dock);
    dock->setWidget(surfaces_);
    addDockWidget(Qt::RightDockWidgetArea, dock);
    auto* volume_dock = new QDockWidget("Volume", this);
    volume_dock->setObjectName("volume");
    volume_ = new VolumePanel(*context_, volume_dock);
    volume_dock->setWidget(volume_);
    addDockWidget(Qt::RightDockWidgetArea, volume_dock);
    tabifyDockWidget(dock, volume_dock);
    dock->raise(); // the Surfaces tab in front; the Volume tab beside it
    measurements_ = new MeasurementsPanel(*context_);
    auto* box = new QWidget;
    auto* layout = new QVBoxLayout(box);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(measurements_->widget(), 3);
    layout->addWidget(structures_->table(), 2);
    measurements_->setWidget(box);
    addDockWidget(Qt::RightDockWidgetArea, measurements_);
    // Wide enough for the Measurements table's columns; surfaces above, measurements below.
    resizeDocks({dock, measurements_}, {460, 460}, Qt::Horizontal);
    resizeDocks({dock, measurements_}, {480, 320}, Qt::Vertical);
}

// Edit: undo and redo of every edit, and deleting every measurement.
void MainWindow::add_edit_menu() {
    auto* edit = menuBar()->addMenu("&Edit");
    auto* undo = undo_->createUndoAction(this, "&Undo");
    undo->setObjectName("undo");
    undo->setShortcut(QKeySequence::Undo);
    auto* redo = undo_->createRedoAction(this, "&Redo");
    redo->setObjectName("redo");
    redo->setShortcuts({QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z), QKeySequence(Qt::CTRL | Qt::Key_Y)});
    edit->addAction(undo);
    edit->addAction(redo);
    edit->addSeparator();
    auto* clear = edit->addAction("&Delete all measurements", this, [this] {
        if (workspace_->markups().empty()) return;
        context_->edit("Delete all measurements", core::Parts(core::Part::Markups),
                       [this] { workspace_->set_markups({}); });
        statusBar()->showMessage("Deleted all measurements (Edit > Undo brings them back)");
    });
    clear->setObjectName("clear_measurements");
}

void MainWindow::add_view_and_help_menus() {
    add_view_menu(*this, *layouts_);
    add_help_menu(*this, [this] { return about_text(); });
}

// What follows the workspace: the title (the session, else the data; "*"
// while there is unsaved work), what needs data, and a new input's status.
void MainWindow::watched(core::Parts parts) {
    const core::Workspace& w = *workspace_;
    if (core::has(parts, core::Part::Data)) {
        undo_->clear(); // the edits belong to what was open
        load_warnings_->set(QString::fromStdString(w.input()),
                            w.scene().has_volume() ? w.scene().volume().meta.warnings : std::vector<std::string>{});
    }
    const QString shown =
        QFileInfo(QString::fromStdString(w.session_path().empty() ? w.input() : w.session_path())).fileName();
    setWindowTitle(shown.isEmpty() ? "isoscope[*]" : "isoscope - " + shown + "[*]");
    setWindowModified(w.modified());
    if (parts & (core::Part::Data | core::Part::Surfaces | core::Part::Markups)) enable_data_actions(*this, w);
}

// ---- drag and drop, closing ----------------------------------------------------------

void MainWindow::dragEnterEvent(QDragEnterEvent* e) {
    if (e->mimeData()->hasUrls() && !e->mimeData()->urls().isEmpty() && e->mimeData()->urls().front().isLocalFile())
        e->acceptProposedAction();
}

void MainWindow::dropEvent(QDropEvent* e) {
    const auto urls = e->mimeData()->urls();
    if (urls.isEmpty() || !urls.front().isLocalFile()) return;
    e->acceptProposedAction();
    // Queued: the drag source is not kept waiting for the load to start.
    const QString path = urls.front().toLocalFile();
    QTimer::singleShot(0, this, [this, path] { files_->open_any(path); });
}

void MainWindow::closeEvent(QCloseEvent* e) {
    if (!unsaved_->may_close([this] { close(); })) {
        e->ignore();
        return;
    }
    QMainWindow::closeEvent(e);
}

} // namespace iso::gui
