#include "app/gui/main_window.hpp"

#include <QCheckBox>
#include <QColorDialog>
#include <QComboBox>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QDragEnterEvent>
#include <QDropEvent>
#include <QFileDialog>
#include <QFileInfo>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QMimeData>
#include <QProgressDialog>
#include <QPushButton>
#include <QSettings>
#include <QSlider>
#include <QStackedWidget>
#include <QStandardItemModel>
#include <QStatusBar>
#include <QThread>
#include <QTimer>
#include <QToolBar>
#include <QUndoCommand>
#include <QUndoStack>
#include <QTableWidget>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "app/gui/load_warnings.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/measurements_panel.hpp"
#include "app/gui/series_dialog.hpp"
#include "app/gui/slice_panel.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/view_toolbar.hpp"
#include "app/gui/structure_tools.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/viewer.hpp"
#include "app/gui/volume_panel.hpp"
#include "io/error.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

namespace {
constexpr int kRecentMax = 8;

// The window/level bar's presets: "default", the CT presets, "custom".
// The CT presets are in Hounsfield units: for a volume without that unit
// (core::value_unit) they stay listed but disabled, saying why.
void enable_ct_window_presets(QComboBox* combo, bool hu) {
    auto* model = qobject_cast<QStandardItemModel*>(combo->model());
    for (int i = 1; i + 1 < combo->count(); ++i) {
        model->item(i)->setEnabled(hu);
        model->item(i)->setToolTip(hu ? QString() : "For CT in Hounsfield units; this volume's values have no unit");
    }
}

// The entry that names window `w`: "default" (the volume's default window),
// a CT preset (HU volumes only), else "custom" (the last entry).
int window_preset_index(const QComboBox* combo, const core::WindowLevel& w, const core::Scene& scene) {
    const auto same = [&w](const core::WindowLevel& o) {
        return std::abs(o.center - w.center) < 0.05 && std::abs(o.width - w.width) < 0.05;
    };
    if (!scene.has_volume()) return 0;
    if (same(core::default_window(scene.volume()))) return 0;
    if (!core::value_unit(scene).empty()) {
        const auto presets = core::ct_window_presets();
        for (std::size_t i = 0; i < presets.size(); ++i)
            if (same(presets[i].window)) return int(i) + 1;
    }
    return combo->count() - 1;
}
} // namespace

namespace {
// One markup edit: the whole state before and after (a few markups: copies are cheap and undo is exact).
class MarkupsCommand : public QUndoCommand {
public:
    MarkupsCommand(MainWindow& w, const QString& text, MarkupsState before, MarkupsState after)
        : QUndoCommand(text), window_(w), before_(std::move(before)), after_(std::move(after)) {}
    void undo() override {
        window_.show_markups(before_);
        window_.statusBar()->showMessage("Undone: " + text());
    }
    void redo() override {
        window_.show_markups(after_);
        if (!first_) window_.statusBar()->showMessage("Redone: " + text());
        first_ = false; // push() runs redo() once: the edit itself, which says what it did
    }

private:
    MainWindow& window_;
    MarkupsState before_, after_;
    bool first_ = true;
};
} // namespace

struct MainWindow::Job {
    QThread* thread = nullptr;
    QProgressDialog* dialog = nullptr;
    QTimer* timer = nullptr;
    QString title;
    bool abandonable = false;
    std::atomic<double> fraction{0.0};
    std::atomic<bool> cancel{false}, abandoned{false};
    std::mutex stage_mutex;
    std::string stage;
    std::exception_ptr error;
    std::function<void(std::exception_ptr)> done;
};

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent), scene_(std::make_unique<core::Scene>()) {
    setWindowTitle("isoscope[*]");
    setAcceptDrops(true);
    resize(1280, 900);

    // ---- views: 3D top left, axial top right, coronal and sagittal below
    auto* central = new QWidget(this);
    auto* grid = new QGridLayout(central);
    grid->setContentsMargins(2, 2, 2, 2);
    grid->setSpacing(2);
    view3d_ = new QStackedWidget(central);
    placeholder_ = new QLabel(
        "Open a volume (File > Open, or drop a file or folder here),\nthen add a surface in the Surfaces panel.",
        view3d_);
    placeholder_->setObjectName("view3d_hint");
    placeholder_->setAlignment(Qt::AlignCenter);
    placeholder_->setWordWrap(true);
    view3d_->addWidget(placeholder_);
    view3d_->setMinimumSize(320, 240);
    grid->addWidget(view3d_, 0, 0);
    const core::SliceOrientation orientations[] = {core::SliceOrientation::Axial, core::SliceOrientation::Coronal,
                                                   core::SliceOrientation::Sagittal};
    const std::pair<int, int> cells[] = {{0, 1}, {1, 0}, {1, 1}};
    for (int i = 0; i < 3; ++i) {
        auto* panel = new SlicePanel(orientations[i], central); // the view, its slider and Fit
        auto* v = panel->view();
        v->on_click = [this](SliceView& view, QPointF p) { slice_clicked(view, p); };
        v->on_scroll = [this](SliceView& view, double steps) { slice_scrolled(view, steps); };
        v->on_paint_overlay = [this](SliceView& view, QPainter& p) { tools_->paint_slice(view, p); };
        v->on_window = [this](SliceView&, const core::WindowLevel& w) { set_window_level(w); }; // a left drag
        views_[std::size_t(i)] = v;
        grid->addWidget(panel, cells[i].first, cells[i].second);
    }
    grid->setRowStretch(0, 1);
    grid->setRowStretch(1, 1);
    grid->setColumnStretch(0, 1);
    grid->setColumnStretch(1, 1);
    setCentralWidget(central);

    add_file_and_edit_menus();

    add_window_level_bar();
    tools_ = new MeasureTools(*this);
    for (auto* v : views_) tools_->attach(*v);

    // ---- 3D view bar: patient views, reset, AO and transparency toggles
    view_bar_ = new ViewToolBar([this] { return viewer_; }, this);
    addToolBar(view_bar_);

    // ---- Surfaces dock
    auto* dock = new QDockWidget("Surfaces", this);
    dock->setObjectName("surfaces");
    surfaces_ = new SurfacesPanel(dock);
    surfaces_->run_job = [this](const QString& title, auto work, auto done) {
        run_job(title, false, std::move(work), std::move(done));
    };
    surfaces_->busy = [this] { return busy(); };
    surfaces_->message = [this](const QString& m) { statusBar()->showMessage(m); };
    surfaces_->error = [this](const QString& title, const QString& what, std::exception_ptr e) {
        show_error(title, what, e);
    };
    surfaces_->changed = [this](bool outlines) {
        update_3d();
        if (outlines) refresh_slices();
        measurements_->refresh_soon(); // which surface each point is on, what a ruler passes through
    };
    surfaces_->set_scene(scene_.get());
    wire_surface_undo();
    dock->setWidget(surfaces_);
    addDockWidget(Qt::RightDockWidgetArea, dock);
    add_volume_dock(dock);
    measurements_ = new MeasurementsPanel(*this);
    add_structure_tools();
    addDockWidget(Qt::RightDockWidgetArea, measurements_);
    // Wide enough for the Measurements table's surface and notes columns.
    resizeDocks({dock, measurements_}, {400, 400}, Qt::Horizontal);
    // Surfaces above (a row or two visible; their list scrolls), measurements below.
    resizeDocks({dock, measurements_}, {500, 300}, Qt::Vertical);

    add_view_and_help_menus();
    load_warnings_ = new LoadWarnings(this);
    statusBar()->addPermanentWidget(load_warnings_);
    statusBar()->showMessage("Ready");
    for (std::size_t i = 0; i < 3; ++i) views_[i]->set_content(scene_.get(), &planes_[i]);
    watch_unsaved_work();
    enable_data_actions();
}

// The File menu, and the Edit menu with the undo stack every edit goes through.
void MainWindow::add_file_and_edit_menus() {
    // ---- File menu
    auto* file = menuBar()->addMenu("&File");
    file->addAction("&Open file...", QKeySequence::Open, this,
                    [this] { ask_to_save("opening another file", [this] { open_file_dialog(); }); });
    file->addAction("Open DICOM &folder...", this,
                    [this] { ask_to_save("opening another folder", [this] { open_folder_dialog(); }); });
    recent_menu_ = file->addMenu("&Recent files");
    rebuild_recent_menu();
    file->addSeparator();
    file->addAction("&Load markups...", this, [this] { measurements_->load_dialog(); })->setObjectName("load_markups");
    file->addAction("&Save markups...", this, [this] { measurements_->save_dialog(); })->setObjectName("save_markups");
    file->addSeparator();
    add_session_actions(file);
    file->addSeparator();
    file->addAction("&Quit", QKeySequence::Quit, this, [this] { close(); });

    // ---- Edit menu: undo and redo of the markup edits
    undo_ = new QUndoStack(this);
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
        if (state_.markups.empty()) return;
        edit_markups("Delete all measurements", {});
        statusBar()->showMessage("Deleted all measurements (Edit > Undo brings them back)");
    });
    clear->setObjectName("clear_measurements");
}

// The window/level bar: presets (CT's from Radiopaedia's table), centre and width.
void MainWindow::add_window_level_bar() {
    auto* wl = addToolBar("Window/level");
    wl->setObjectName("window_level");
    wl->addWidget(new QLabel(" Window: "));
    window_preset_ = new QComboBox(wl);
    window_preset_->setObjectName("window_preset");
    window_preset_->setToolTip("Window presets of the slice views (CT ones for volumes in HU); 'custom': set by hand");
    window_preset_->addItem("default");
    for (const auto& p : core::ct_window_presets())
        window_preset_->addItem(QString("%1 (W %2 / L %3)")
                                    .arg(QString::fromUtf8(p.name.data(), qsizetype(p.name.size())))
                                    .arg(p.window.width)
                                    .arg(p.window.center));
    window_preset_->addItem("custom"); // numbers set by hand or a drag
    wl->addWidget(window_preset_);
    wl->addWidget(new QLabel(" Level (center): "));
    center_ = new QDoubleSpinBox(wl);
    center_->setObjectName("window_center");
    center_->setToolTip("Window level: the value shown mid-grey (a left drag up or down in a slice view changes it)");
    center_->setRange(-1e6, 1e6);
    center_->setDecimals(1);
    wl->addWidget(center_);
    wl->addWidget(new QLabel(" Width: "));
    width_ = new QDoubleSpinBox(wl);
    width_->setObjectName("window_width");
    width_->setToolTip("Window width: the range of values from black to white (a left drag left or right changes it)");
    width_->setRange(0, 2e6);
    width_->setDecimals(1);
    wl->addWidget(width_);
    connect(window_preset_, &QComboBox::currentIndexChanged, this, [this](int index) {
        if (updating_window_ || index < 0 || index == window_preset_->count() - 1) return;
        if (index == 0) {
            if (scene_->has_volume()) set_window_level(core::default_window(scene_->volume()));
            return;
        }
        set_window_level(core::ct_window_presets()[std::size_t(index - 1)].window);
    });
    const auto spin_changed = [this] {
        if (updating_window_) return;
        set_window_level({center_->value(), width_->value()});
    };
    connect(center_, &QDoubleSpinBox::valueChanged, this, spin_changed);
    connect(width_, &QDoubleSpinBox::valueChanged, this, spin_changed);
    set_window_level(window_);
}

MainWindow::~MainWindow() {
    // The undo stack is a child: ~QWidget deletes it after this destructor,
    // and its clear() then signals lambdas that read this window's members.
    undo_->disconnect(this);
    wait_for_autosave();           // it reads nothing of the window, but its thread must end
    surfaces_->set_scene(nullptr); // its re-extractions read the scene: they stop first
    // Workers still running (an abandoned load, an extraction) finish before
    // the scene they may use goes; extractions stop at their next progress call.
    for (auto& j : running_) {
        j->cancel = true;
        j->thread->wait();
        delete j->thread;
    }
    // The viewer releases its GL objects through the scene: it goes first.
    delete viewer_;
    viewer_ = nullptr;
}

// ---- background jobs ---------------------------------------------------------------

void MainWindow::run_job(const QString& title, bool abandonable, std::function<void(const ProgressFn&)> work,
                         std::function<void(std::exception_ptr)> done) {
    auto job = std::make_shared<Job>();
    job->title = title;
    job->abandonable = abandonable;
    job->done = std::move(done);
    Job* j = job.get();
    // The core calls this on the worker; returning false makes it throw iso::Cancelled.
    ProgressFn progress = [j](double f, std::string_view stage) {
        j->fraction = f;
        {
            std::lock_guard lock(j->stage_mutex);
            j->stage = stage;
        }
        return !j->cancel.load();
    };
    job->thread = QThread::create([j, work = std::move(work), progress] {
        try {
            work(progress);
        } catch (...) {
            j->error = std::current_exception();
        }
    });
    job->dialog = new QProgressDialog(title, "Cancel", 0, 1000, this);
    job->dialog->setObjectName("progress");
    job->dialog->setWindowModality(Qt::WindowModal);
    job->dialog->setAutoClose(false);
    job->dialog->setAutoReset(false);
    job->dialog->setMinimumDuration(300);
    job->dialog->setValue(0);
    connect(job->dialog, &QProgressDialog::canceled, this, [this, j] {
        j->cancel = true;
        if (!j->abandonable) {
            j->dialog->setLabelText(j->title + "\ncancelling...");
            return;
        }
        // The core's load reports no progress for most formats, so it cannot
        // stop early: the window stops waiting and drops the result.
        j->abandoned = true;
        if (job_.get() == j) job_.reset();
        QObject::disconnect(j->dialog, nullptr, this, nullptr);
        j->dialog->hide();
        statusBar()->showMessage(j->title + ": cancelled");
    });
    job->timer = new QTimer(this);
    connect(job->timer, &QTimer::timeout, this, [j] {
        if (j->abandoned) return;
        std::string stage;
        {
            std::lock_guard lock(j->stage_mutex);
            stage = j->stage;
        }
        j->dialog->setValue(int(std::clamp(j->fraction.load(), 0.0, 1.0) * 1000));
        if (!j->cancel && !stage.empty()) j->dialog->setLabelText(j->title + "\n" + QString::fromStdString(stage));
    });
    job->timer->start(50);
    connect(job->thread, &QThread::finished, this, [this, job] { finish_job(job); });
    job_ = job;
    running_.push_back(job);
    job->thread->start();
}

void MainWindow::finish_job(const std::shared_ptr<Job>& job) {
    std::erase(running_, job);
    job->timer->stop();
    job->timer->deleteLater();
    QObject::disconnect(job->dialog, nullptr, this, nullptr);
    job->dialog->hide();
    job->dialog->deleteLater();
    job->thread->deleteLater();
    if (job->abandoned) return;
    if (job_ == job) job_.reset();
    job->done(job->error);
}

void MainWindow::show_error(const QString& title, const QString& what, std::exception_ptr e) {
    QString reason;
    try {
        std::rethrow_exception(e);
    } catch (const Cancelled&) {
        statusBar()->showMessage(what + ": cancelled");
        return;
    } catch (const std::exception& ex) {
        reason = QString::fromStdString(ex.what());
    } catch (...) {
        reason = "unknown error";
    }
    statusBar()->showMessage(what + ": failed");
    // Not exec(): the window keeps running (and tests can find and close the box).
    auto* box = new QMessageBox(QMessageBox::Critical, title, what + "\n\n" + reason, QMessageBox::Ok, this);
    box->setObjectName("error");
    box->setAttribute(Qt::WA_DeleteOnClose);
    box->open();
}

// ---- opening -------------------------------------------------------------------------

void MainWindow::open_path(const QString& path, const QString& series) {
    // One DICOM file stands for its series: the series of that file, from its folder.
    if (const auto of = series.isEmpty() && !busy() ? core::dicom_series_of_file(path.toStdString()) : std::nullopt) {
        load(QString::fromStdString(of->folder), QString::fromStdString(of->uid));
        return;
    }
    if (series.isEmpty() && !busy() && QFileInfo(path).isDir()) {
        choose_series(path);
        return;
    }
    load(path, series);
}

void MainWindow::choose_series(const QString& folder) {
    auto list = std::make_shared<std::vector<SeriesInfo>>();
    const std::string p = folder.toStdString();
    // Headers only, but a large folder takes a while: in the background, abandonable.
    run_job(
        "Listing the DICOM series in " + folder, true, [list, p](const ProgressFn&) { *list = core::list_series(p); },
        [this, list, folder](std::exception_ptr e) {
            if (e) {
                show_error("Cannot open", "Cannot open " + folder, e);
                return;
            }
            if (list->size() <= 1) {
                load(folder, {});
                return;
            }
            auto* chooser = new SeriesDialog(folder, std::move(*list), this);
            chooser->setAttribute(Qt::WA_DeleteOnClose);
            chooser->on_chosen = [this, chooser, folder](int row) {
                // By UID: it names the series whatever else the folder gains.
                const QString uid = QString::fromStdString(chooser->series()[std::size_t(row)].uid);
                QTimer::singleShot(0, this, [this, folder, uid] { open_path(folder, uid); });
            };
            connect(chooser, &QDialog::rejected, this,
                    [this, folder] { statusBar()->showMessage("Opening " + folder + ": cancelled"); });
            chooser->open(); // window-modal, not exec(): the event loop (and tests) go on
        });
}

void MainWindow::load(const QString& path, const QString& series) {
    if (busy()) {
        statusBar()->showMessage("Busy: wait for the current task or cancel it");
        return;
    }
    auto result = std::make_shared<std::unique_ptr<core::Scene>>();
    const std::string p = path.toStdString(), chosen = series.toStdString();
    run_job(
        "Opening " + path, true,
        [result, p, chosen](const ProgressFn& progress) {
            // A fresh scene on the worker: the one on screen stays untouched
            // until the load succeeded.
            auto s = std::make_unique<core::Scene>();
            LoadOptions opt;
            opt.progress = progress;
            opt.series = chosen;
            s->open(p, opt);
            *result = std::move(s);
        },
        [this, result, path, series](std::exception_ptr e) {
            if (e) {
                show_error("Cannot open", "Cannot open " + path, e);
                return;
            }
            set_scene(std::move(*result), path, series);
        });
}

void MainWindow::set_scene(std::unique_ptr<core::Scene> scene, const QString& path, const QString& series) {
    // The viewer's GL objects belong to the old scene: the viewer goes with it.
    if (viewer_) {
        view3d_->removeWidget(viewer_);
        delete viewer_;
        viewer_ = nullptr;
    }
    view3d_->setCurrentWidget(placeholder_);
    surfaces_->set_scene(nullptr); // stops re-extractions reading the old scene
    scene_ = std::move(scene);
    path_ = path;
    series_ = series;
    session_path_.clear(); // open_session sets it again
    dicom_series_.clear(); // a new session's DICOM figures go to a new series
    state_ = {};           // measurements belong to what was open
    selected_.reset();
    undo_->clear(); // and so do their edits
    tools_->reset();
    measurements_->refresh();
    planes_ = {};
    if (scene_->has_volume()) {
        planes_ = core::default_planes(scene_->volume());
        enable_ct_window_presets(window_preset_, !core::value_unit(*scene_).empty());
        updating_window_ = true;
        window_preset_->setCurrentIndex(0);
        updating_window_ = false;
        set_window_level(core::default_window(scene_->volume()));
    }
    for (std::size_t i = 0; i < 3; ++i) views_[i]->set_content(scene_.get(), &planes_[i]);
    surfaces_->set_scene(scene_.get());
    // The volume off, its default transfer function, the crop box its box.
    volume_->set_scene(scene_.get());
    structures_->reset(); // a session's isolated structures are measured again
    update_3d();
    setWindowTitle("isoscope - " + QFileInfo(path).fileName() + "[*]");
    remember_recent(path);
    load_warnings_->set(path, scene_->has_volume() ? scene_->volume().meta.warnings : std::vector<std::string>{});
    if (scene_->has_volume()) {
        const auto& v = scene_->volume();
        statusBar()->showMessage(
            QString("Opened %1: %2 x %3 x %4").arg(path).arg(v.dims[0]).arg(v.dims[1]).arg(v.dims[2]) +
            (v.meta.warnings.empty() ? QString() : QString(" (with warnings: see the status bar's right end)")));
    } else {
        statusBar()->showMessage("Opened " + path);
    }
}

void MainWindow::open_file_dialog() {
    const QString f =
        QFileDialog::getOpenFileName(this, "Open file", QString(),
                                     "Volumes and meshes (*.nrrd *.nhdr *.nii *.nii.gz *.mha *.mhd *.vti *.vdb *.dcm "
                                     "*.stl *.ply *.obj *.vtp *.vtk);;All files (*)");
    if (!f.isEmpty()) open_path(f);
}

void MainWindow::open_folder_dialog() {
    const QString d = QFileDialog::getExistingDirectory(this, "Open DICOM folder");
    if (!d.isEmpty()) open_path(d);
}

void MainWindow::remember_recent(const QString& path) {
    QSettings s;
    QStringList list = s.value("recent_files").toStringList();
    const QString abs = QFileInfo(path).absoluteFilePath();
    list.removeAll(abs);
    list.prepend(abs);
    while (list.size() > kRecentMax) list.removeLast();
    s.setValue("recent_files", list);
    rebuild_recent_menu();
}

void MainWindow::rebuild_recent_menu() {
    recent_menu_->clear();
    const QStringList list = QSettings().value("recent_files").toStringList();
    for (const auto& f : list)
        recent_menu_->addAction(f, this, [this, f] { ask_to_save("opening " + f, [this, f] { open_path(f); }); });
    recent_menu_->setEnabled(!list.isEmpty());
}

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
    QTimer::singleShot(0, this, [this, path] {
        // A session (.json; Slicer's .mrk.json are markups, not sessions) restores what it saved.
        const bool session =
            path.endsWith(".json", Qt::CaseInsensitive) && !path.endsWith(".mrk.json", Qt::CaseInsensitive);
        ask_to_save("opening " + path, [this, path, session] { session ? open_session(path) : open_path(path); });
    });
}

// ---- surfaces --------------------------------------------------------------------------

void MainWindow::add_surface(double iso) { surfaces_->add_surface(iso); }

void MainWindow::add_structure_tools() {
    structures_ = new StructureTools(*this);
    surfaces_->isolated = [this](const core::IsolatedComponent& c) {
        structures_->add_component(c);
        undo_->resetClean(); // a surface more, not an undo step: unsaved all the same
    };
    // The Measurements dock: the markups' table above the isolated structures'.
    auto* box = new QWidget;
    auto* layout = new QVBoxLayout(box);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(measurements_->widget(), 3);
    layout->addWidget(structures_->table(), 1);
    measurements_->setWidget(box);
}

// ---- views -----------------------------------------------------------------------------

void MainWindow::update_3d() {
    bool any_visible = false;
    for (auto id : scene_->surfaces()) any_visible |= scene_->info(id).visible;
    const bool volume_shown = scene_->has_volume() && volume_->state().look.enabled;
    if (!any_visible && !volume_shown) {
        // The camera frames the visible surfaces and the volume when it is
        // shown: with neither there is nothing to frame. The hint says what
        // to do next.
        placeholder_->setText(
            !scene_->has_volume() ? "Open a volume (File > Open, or drop a file or folder here),\nthen add "
                                    "a surface in the Surfaces panel."
            : scene_->surfaces().empty()
                ? "Add a surface in the Surfaces panel (a preset or an iso value,\nthen "
                  "Add surface), or tick Show volume in the Volume panel,\nto see it here."
                : "Every surface is hidden: tick one in the Surfaces panel\n(or Show volume in the Volume panel) to "
                  "see it here.");
        view3d_->setCurrentWidget(placeholder_);
        enable_data_actions();
        return;
    }
    enable_data_actions(); // data_actions.cpp
    if (!viewer_) {
        viewer_ = new Viewer(*scene_, PatientView::Anterior);
        viewer_->setObjectName("viewer");
        tools_->attach(*viewer_);
        tools_->redraw();
        view_bar_->attach(*viewer_);
        view3d_->addWidget(viewer_);
    }
    apply_volume(); // before its first frame: a volume alone is framed
    view3d_->setCurrentWidget(viewer_);
    update_slice_planes_3d();
    viewer_->update();
}

void MainWindow::set_markups(std::vector<Markup> m) {
    MarkupsState s;
    s.sources.resize(m.size());
    s.markups = std::move(m);
    show_markups(std::move(s));
}

void MainWindow::show_markups(MarkupsState s) {
    s.sources.resize(s.markups.size());
    // The selection stays while its markup can only have stayed where it was
    // (edited, or markups added after it); after a removal it goes.
    if (selected_ && (s.markups.size() < state_.markups.size() || *selected_ >= s.markups.size() ||
                      s.markups[*selected_].type != state_.markups[*selected_].type))
        selected_.reset();
    state_ = std::move(s);
    tools_->redraw(); // the 3D view's overlay and the slices
    measurements_->refresh();
}

void MainWindow::edit_markups(const QString& text, MarkupsState after, std::optional<MarkupsState> before) {
    after.sources.resize(after.markups.size());
    // push() runs the command's redo(), which shows `after`.
    undo_->push(new MarkupsCommand(*this, text, before ? std::move(*before) : state_, std::move(after)));
}

void MainWindow::select_markup(std::optional<std::size_t> index, bool centre) {
    if (index && *index >= state_.markups.size()) index.reset();
    selected_ = index;
    tools_->redraw();
    measurements_->show_selection();
    if (!index || !centre) return;
    const Markup& m = state_.markups[*index];
    const auto first = std::find_if(m.points.begin(), m.points.end(),
                                    [](const MarkupControlPoint& p) { return p.status == PositionStatus::Defined; });
    if (first != m.points.end()) centre_on(first->position);
}

void MainWindow::centre_on(const glm::dvec3& lps) {
    set_crosshair(lps);
    if (!viewer_) return;
    // The view turns about the point now; distance and direction stay.
    Camera c = viewer_->camera();
    const glm::dvec3 shift = lps - c.target;
    c.target += shift;
    c.eye += shift;
    viewer_->set_camera(c);
}

void MainWindow::set_crosshair(const glm::dvec3& lps, const SliceView* keep) {
    if (!scene_->has_volume()) return;
    std::optional<core::SlicePlane> kept;
    if (keep) kept = planes_[std::size_t(keep->orientation())];
    core::set_crosshair(planes_, lps);
    if (kept) { // its crosshair moves to the point, its slice stays
        auto& p = planes_[std::size_t(keep->orientation())];
        p.center = kept->center;
        core::set_offset(p, kept->offset_mm());
    }
    refresh_slices();
}

void MainWindow::refresh_slices() {
    for (auto* v : views_) v->refresh();
    update_slice_planes_3d(); // the planes' outlines in the 3D view follow
}

void MainWindow::set_window_level(const core::WindowLevel& w) {
    window_ = w;
    updating_window_ = true;
    center_->setValue(w.center);
    width_->setValue(w.width);
    window_preset_->setCurrentIndex(window_preset_index(window_preset_, w, *scene_));
    updating_window_ = false;
    for (auto* v : views_) v->set_window(w);
}

void MainWindow::slice_clicked(SliceView& view, QPointF pixel) {
    if (!scene_->has_volume()) return;
    if (tools_->slice_click(view, pixel)) return; // a point of a ruler or an angle
    const auto& g = view.grid();
    // The hover probe's text for the same point (slice_readout).
    statusBar()->showMessage(slice_readout(scene_->volume(), g, pixel));
    core::set_crosshair(planes_, core::pixel_to_lps(g, {pixel.x(), pixel.y()}));
    refresh_slices();
}

void MainWindow::slice_scrolled(SliceView& view, double steps) {
    if (!scene_->has_volume()) return;
    auto& plane = planes_[std::size_t(view.orientation())];
    core::scroll_slices(plane, steps);
    // The other views' crosshair lines follow the moved slice.
    core::set_crosshair(planes_, plane.origin);
    refresh_slices();
}

} // namespace iso::gui
