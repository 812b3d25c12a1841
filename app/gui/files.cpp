// Files (files.hpp): opening data and sessions, saving sessions, the
// question about unsaved work, recent files. Exports are exports.cpp.
#include "app/gui/files.hpp"

#include <QAction>
#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QMainWindow>
#include <QMenu>
#include <QMessageBox>
#include <QSettings>
#include <QStandardPaths>
#include <QTimer>

#include <memory>

#include "app/gui/app_context.hpp"
#include "app/gui/export_dialog.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/series_dialog.hpp"
#include "io/error.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"

namespace iso::gui {

namespace {
constexpr int kRecentMax = 8;
}

Files::Files(AppContext& context) : QObject(&context.window), context_(context) {}

void Files::add_menu(QMenu* file) {
    QMainWindow* w = &context_.window;
    file->addAction("&Open file...", QKeySequence::Open, this,
                    [this] { ask_to_save("opening another file", [this] { open_file_dialog(); }); });
    file->addAction("Open DICOM &folder...", this,
                    [this] { ask_to_save("opening another folder", [this] { open_folder_dialog(); }); });
    recent_menu_ = file->addMenu("&Recent files");
    rebuild_recent_menu();
    file->addSeparator();
    add_session_actions(file);
    file->addSeparator();
    add_export_actions(file);
    file->addSeparator();
    file->addAction("&Quit", QKeySequence::Quit, w, [w] { w->close(); });
}

void Files::add_markups_actions(std::function<void()> load_dialog, std::function<void()> save_dialog) {
    // Before the session entries: File > Load markups..., Save markups....
    QMenu* file = nullptr;
    for (QMenu* m : context_.window.findChildren<QMenu*>())
        if (m->title() == "&File") file = m;
    if (!file) return;
    QAction* before = file->actions().value(3); // after Open file, Open folder, Recent files
    auto* load = new QAction("&Load markups...", file);
    load->setObjectName("load_markups");
    connect(load, &QAction::triggered, this, [load_dialog] { load_dialog(); });
    auto* save = new QAction("&Save markups...", file);
    save->setObjectName("save_markups");
    connect(save, &QAction::triggered, this, [save_dialog] { save_dialog(); });
    file->insertActions(before, {file->insertSeparator(before), load, save});
}

// ---- opening ---------------------------------------------------------------------------

void Files::open_any(const QString& path) {
    // A session (.json; Slicer's .mrk.json are markups, not sessions) restores what it saved.
    const bool session =
        path.endsWith(".json", Qt::CaseInsensitive) && !path.endsWith(".mrk.json", Qt::CaseInsensitive);
    ask_to_save("opening " + path, [this, path, session] { session ? open_session(path) : open_path(path); });
}

void Files::open_path(const QString& path, const QString& series) {
    // One DICOM file stands for its series: the series of that file, from its folder.
    const bool busy = context_.busy();
    if (const auto of = series.isEmpty() && !busy ? core::dicom_series_of_file(path.toStdString()) : std::nullopt) {
        load(QString::fromStdString(of->folder), QString::fromStdString(of->uid));
        return;
    }
    if (series.isEmpty() && !busy && QFileInfo(path).isDir()) {
        choose_series(path);
        return;
    }
    load(path, series);
}

void Files::choose_series(const QString& folder) {
    auto list = std::make_shared<std::vector<SeriesInfo>>();
    const std::string p = folder.toStdString();
    // Headers only, but a large folder takes a while: in the background, abandonable.
    context_.jobs.run(
        "Listing the DICOM series in " + folder, true, [list, p](const ProgressFn&) { *list = core::list_series(p); },
        [this, list, folder](std::exception_ptr e) {
            if (e) {
                context_.error("Cannot open", "Cannot open " + folder, e);
                return;
            }
            if (list->size() <= 1) {
                load(folder, {});
                return;
            }
            auto* chooser = new SeriesDialog(folder, std::move(*list), &context_.window);
            chooser->setAttribute(Qt::WA_DeleteOnClose);
            chooser->on_chosen = [this, chooser, folder](int row) {
                // By UID: it names the series whatever else the folder gains.
                const QString uid = QString::fromStdString(chooser->series()[std::size_t(row)].uid);
                QTimer::singleShot(0, this, [this, folder, uid] { open_path(folder, uid); });
            };
            connect(chooser, &QDialog::rejected, this,
                    [this, folder] { context_.status("Opening " + folder + ": cancelled"); });
            chooser->open(); // window-modal, not exec(): the event loop (and tests) go on
        });
}

void Files::load(const QString& path, const QString& series) {
    if (context_.busy(true)) return;
    auto result = std::make_shared<std::unique_ptr<core::Scene>>();
    const std::string p = path.toStdString(), chosen = series.toStdString();
    context_.jobs.run(
        "Opening " + path, true,
        [result, p, chosen](const ProgressFn& progress) {
            // A fresh scene on the worker: the one on screen stays untouched
            // until the load succeeded.
            auto s = std::make_unique<core::Scene>();
            LoadOptions opt;
            opt.progress = progress;
            opt.series = chosen;
            s->open(p, opt);
            // Its value range here, not on the GUI thread at its first use
            // (a 2 GiB volume's scan held the window for half a second).
            if (s->has_volume()) s->value_range();
            *result = std::move(s);
        },
        [this, result, path, series](std::exception_ptr e) {
            if (e) {
                context_.error("Cannot open", "Cannot open " + path, e);
                return;
            }
            dicom_series_.clear(); // a new session's DICOM figures go to a new series
            context_.workspace.reset(std::move(*result), path.toStdString(), series.toStdString());
            loaded(path);
        });
}

void Files::loaded(const QString& path) {
    remember_recent(path);
    const core::Scene& scene = context_.workspace.scene();
    if (!scene.has_volume()) {
        context_.status("Opened " + path);
        return;
    }
    const auto& v = scene.volume();
    context_.status(
        QString("Opened %1: %2 x %3 x %4").arg(path).arg(v.dims[0]).arg(v.dims[1]).arg(v.dims[2]) +
        (v.meta.warnings.empty() ? QString() : QString(" (with warnings: see the status bar's right end)")));
}

void Files::open_file_dialog() {
    const QString f =
        QFileDialog::getOpenFileName(&context_.window, "Open file", QString(),
                                     "Volumes and meshes (*.nrrd *.nhdr *.nii *.nii.gz *.mha *.mhd *.vti *.vdb *.dcm "
                                     "*.stl *.ply *.obj *.vtp *.vtk);;All files (*)");
    if (!f.isEmpty()) open_path(f);
}

void Files::open_folder_dialog() {
    const QString d = QFileDialog::getExistingDirectory(&context_.window, "Open DICOM folder");
    if (!d.isEmpty()) open_path(d);
}

void Files::remember_recent(const QString& path) {
    QSettings s;
    QStringList list = s.value("recent_files").toStringList();
    const QString abs = QFileInfo(path).absoluteFilePath();
    list.removeAll(abs);
    list.prepend(abs);
    while (list.size() > kRecentMax) list.removeLast();
    s.setValue("recent_files", list);
    rebuild_recent_menu();
}

void Files::rebuild_recent_menu() {
    recent_menu_->clear();
    const QStringList list = QSettings().value("recent_files").toStringList();
    for (const auto& f : list)
        recent_menu_->addAction(f, this, [this, f] { ask_to_save("opening " + f, [this, f] { open_path(f); }); });
    recent_menu_->setEnabled(!list.isEmpty());
}

// ---- sessions ----------------------------------------------------------------------------

void Files::add_session_actions(QMenu* file) {
    file->addAction("Open &session...", this, [this] {
        ask_to_save("opening another session", [this] {
            const QString f = QFileDialog::getOpenFileName(&context_.window, "Open session", start_folder("session"),
                                                           "isoscope sessions (*.json);;All files (*)");
            if (!f.isEmpty()) open_session(f);
        });
    });
    file->addAction("Sa&ve session...", QKeySequence::Save, this, [this] {
        const QString f = QFileDialog::getSaveFileName(&context_.window, "Save session", session_save_start(),
                                                       "isoscope sessions (*.json)");
        if (!f.isEmpty()) save_session(f);
    });
}

QString Files::session_save_start() const {
    const core::Workspace& w = context_.workspace;
    if (!w.session_path().empty()) return QString::fromStdString(w.session_path());
    return QDir(start_folder("session")).filePath(data_name(QString::fromStdString(w.input())) + ".isoscope.json");
}

void Files::save_session(const QString& path, std::function<void()> then) {
    if (context_.busy(true)) return;
    if (!context_.workspace.has_data()) {
        context_.status("Nothing to save: open a volume or mesh first");
        return;
    }
    auto session = std::make_shared<core::Session>(context_.workspace.session());
    const std::string p = path.toStdString();
    // The input's SHA-256 is computed on the worker (a DICOM folder can be large).
    context_.jobs.run(
        "Saving the session " + path, false, [session, p](const ProgressFn&) { core::save_session(*session, p); },
        [this, path, then](std::exception_ptr e) {
            if (e) {
                context_.error("Cannot save the session", "Cannot save the session " + path, e);
                return;
            }
            remember_folder("session", path);
            context_.status("Saved the session " + path);
            // Nothing unsaved now (the dialog was window-modal: no edit came in meanwhile).
            context_.workspace.mark_saved(path.toStdString());
            if (then) then();
        });
}

void Files::open_session(const QString& path, bool recovered) {
    if (context_.busy(true)) return;
    auto result = std::make_shared<core::OpenedSession>();
    const std::string p = path.toStdString();
    // A fresh scene on the worker, as open_path: the one on screen stays until the session opened.
    context_.jobs.run(
        "Opening the session " + path, true,
        [result, p](const ProgressFn& progress) { *result = core::open_session(p, progress); },
        [this, result, path, recovered](std::exception_ptr e) {
            if (e) {
                context_.error("Cannot open the session", "Cannot open the session " + path, e);
                return;
            }
            const std::vector<std::string> warnings = result->session.warnings;
            dicom_series_.clear();
            context_.workspace.adopt(std::move(*result), recovered ? std::string() : path.toStdString());
            if (!recovered) remember_folder("session", path);
            QString msg =
                (recovered ? "Restored the unsaved work of the last run from " : "Opened the session ") + path;
            for (const auto& w : warnings) msg += "; warning: " + QString::fromStdString(w);
            context_.status(msg);
        });
}

// ---- unsaved work ----------------------------------------------------------------------

void Files::ask_to_save(const QString& doing, std::function<void()> proceed) {
    const core::Workspace& w = context_.workspace;
    if (!w.modified()) {
        proceed();
        return;
    }
    if (context_.window.findChild<QMessageBox*>("unsaved")) return; // asking already
    auto* box = new QMessageBox(QMessageBox::Warning, "Unsaved changes",
                                "The surfaces, volume settings or measurements changed since the session was last "
                                "saved or opened.\nSave them as a session before " +
                                    doing + "?",
                                QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, &context_.window);
    box->setObjectName("unsaved");
    box->setDefaultButton(QMessageBox::Save);
    box->setAttribute(Qt::WA_DeleteOnClose);
    connect(box, &QMessageBox::finished, this, [this, box, doing, proceed](int) {
        const auto answer = box->standardButton(box->clickedButton());
        const core::Workspace& w = context_.workspace;
        if (answer == QMessageBox::Discard) {
            if (discarded) discarded();
            proceed();
        } else if (answer == QMessageBox::Save) {
            const QString path = w.session_path().empty()
                                     ? QFileDialog::getSaveFileName(&context_.window, "Save session",
                                                                    session_save_start(), "isoscope sessions (*.json)")
                                     : QString::fromStdString(w.session_path());
            if (path.isEmpty()) return; // no file chosen: as Cancel
            save_session(path, proceed);
        } else {
            context_.status(doing.left(1).toUpper() + doing.mid(1) + ": cancelled");
        }
    });
    box->open(); // window-modal, not exec(): the event loop (and tests) go on
}

// ---- where files go ----------------------------------------------------------------------

QString Files::start_folder(const char* kind) {
    const QString last = QSettings().value(QString(kind) + "_folder").toString();
    if (!last.isEmpty() && QFileInfo(last).isDir()) return last;
    const QString documents = QStandardPaths::writableLocation(QStandardPaths::DocumentsLocation);
    if (!documents.isEmpty() && QFileInfo(documents).isDir()) return documents;
    return QDir::homePath();
}

void Files::remember_folder(const char* kind, const QString& file_or_folder) {
    const QFileInfo fi(file_or_folder);
    QSettings().setValue(QString(kind) + "_folder", fi.isDir() ? fi.absoluteFilePath() : fi.absolutePath());
}

} // namespace iso::gui
