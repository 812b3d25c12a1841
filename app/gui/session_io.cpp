// MainWindow's sessions and export (docs/sessions.md, docs/gui.md
// "Sessions and export"): File > Save session, Open session, Export image,
// Save surfaces. Member functions of MainWindow kept out of main_window.cpp;
// what they do is the core's (renderer/core/session.hpp, api.hpp, scene.hpp).
#include <QAction>
#include <QCoreApplication>
#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QMenu>
#include <QSettings>
#include <QStatusBar>
#include <QUndoStack>

#include "app/gui/export_dialog.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/view_toolbar.hpp"
#include "app/gui/viewer.hpp"
#include "app/gui/volume_panel.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"

namespace iso::gui {

namespace {
QString settings_folder(const char* key) {
    const QString f = QSettings().value(key).toString();
    return f.isEmpty() ? QDir::homePath() : f;
}

// The folder last saved to of a kind (empty: none yet).
QString last_folder(const char* key) { return QSettings().value(key).toString(); }

void remember_folder(const char* key, const QString& file) {
    QSettings().setValue(key, QFileInfo(file).absolutePath());
}

// The session file an export names: the current one when it holds this
// state, else one written next to the image.
QString export_session_path(const QString& session, const core::Session& now, const QString& image, bool& write) {
    write = false;
    if (!session.isEmpty()) {
        try {
            if (core::same_state(core::read_session(session.toStdString()), now)) return session;
        } catch (const Error&) {
            // Gone or damaged since: a fresh one next to the image.
        }
    }
    write = true;
    return image + ".session.json";
}
} // namespace

core::Session MainWindow::current_session() const {
    std::optional<Camera> camera;
    // The viewer's camera once it drew or was set (before, it holds the
    // default Camera, which frames nothing: the anterior view stands in).
    if (viewer_) {
        const Camera& c = viewer_->camera();
        const Camera unset;
        if (viewer_->frames() > 0 || c.eye != unset.eye || c.target != unset.target || c.up != unset.up) camera = c;
    }
    std::optional<core::WindowLevel> window;
    if (scene_->has_volume()) window = window_;
    // The 3D view's toggles (the view bar keeps them across scenes).
    FrameLook look = viewer_ ? viewer_->options().look : view_bar_->look();
    // The Volume panel's look and crop box (kept while the view is not made).
    if (scene_->has_volume()) {
        look.volume = volume_->state().look;
        look.clip = volume_->state().clip();
    }
    core::Session s = core::capture_session(*scene_, path_.toStdString(), series_.toStdString(), camera, window, look,
                                            state_.markups);
    // The layout and the slice views (layouts.cpp).
    s.layout = layout();
    s.slice_planes_in_3d = slice_planes_in_3d();
    if (scene_->has_volume()) s.slice_views = core::capture_slice_views(planes_);
    return s;
}

void MainWindow::add_session_actions(QMenu* file) {
    file->addAction("Open &session...", this, [this] {
        ask_to_save("opening another session", [this] {
            const QString f = QFileDialog::getOpenFileName(this, "Open session", settings_folder("session_folder"),
                                                           "isoscope sessions (*.json);;All files (*)");
            if (!f.isEmpty()) open_session(f);
        });
    });
    file->addAction("Sa&ve session...", QKeySequence::Save, this, [this] {
        const QString start = session_path_.isEmpty()
                                  ? suggested_save_path(path_, last_folder("session_folder"), ".isoscope.json")
                                  : session_path_;
        const QString f = QFileDialog::getSaveFileName(this, "Save session", start, "isoscope sessions (*.json)");
        if (!f.isEmpty()) save_session(f);
    });
    file->addSeparator();
    file->addAction("&Export image...", this, [this] {
        if (path_.isEmpty()) {
            statusBar()->showMessage("Open a volume or mesh first");
            return;
        }
        bool write = false;
        const QString image = suggested_save_path(path_, last_folder("export_folder"), ".png");
        const QString named = export_session_path(session_path_, current_session(), image, write);
        const QString note =
            write ? "The state is also saved as a session next to the image (IMAGE.session.json); the image's "
                    "metadata names it, so `isoscope render --session` can make it again."
                  : "The image's metadata names the current session, " + named + " (unchanged since saved).";
        auto* d = new ExportDialog(viewer_ ? viewer_->image_size() : QSize(1024, 1024), current_session().ao, image,
                                   note, this);
        d->setAttribute(Qt::WA_DeleteOnClose);
        connect(d, &QDialog::accepted, this, [this, d] { export_image(d->path(), d->frame(), d->parts()); });
        d->open();
    });
    file->addAction("Export to &DICOM...", this, [this] {
        if (path_.isEmpty()) {
            statusBar()->showMessage("Open a volume or mesh first");
            return;
        }
        const bool dicom_source = scene_->has_volume() && scene_->volume().meta.format == "DICOM";
        const QString note =
            QString(dicom_source ? "The figure joins the study of the DICOM series open (same patient and Study "
                                   "Instance UID)"
                                 : "The figure starts a new study (the data open is not from DICOM)") +
            ", as a Secondary Capture in the series \"isoscope 3D\" (one per session: later exports add "
            "images to it), annotations burned in, the settings that made it in its Image Comments.";
        auto* d = new ExportDialog(viewer_ ? viewer_->image_size() : QSize(1024, 1024), current_session().ao,
                                   suggested_save_path(path_, last_folder("dicom_folder"), "-dicom"), note, this,
                                   ExportDialog::Kind::Dicom);
        d->setAttribute(Qt::WA_DeleteOnClose);
        connect(d, &QDialog::accepted, this, [this, d] { export_dicom(d->path(), d->frame(), d->parts()); });
        d->open();
    });
    file->addAction("Save s&urfaces...", this, [this] {
        if (scene_->surfaces().empty()) {
            statusBar()->showMessage("No surface to save: add one in the Surfaces panel");
            return;
        }
        auto* d =
            new SaveSurfacesDialog(*scene_, save_folder(path_, last_folder("surface_folder")), data_name(path_), this);
        d->setAttribute(Qt::WA_DeleteOnClose);
        connect(d, &QDialog::accepted, this, [this, d] { save_surface(d->surface(), d->path()); });
        d->open();
    });
}

void MainWindow::save_session(const QString& path, std::function<void()> then) {
    if (busy()) {
        statusBar()->showMessage("Busy: wait for the current task or cancel it");
        return;
    }
    if (path_.isEmpty()) {
        statusBar()->showMessage("Nothing to save: open a volume or mesh first");
        return;
    }
    auto session = std::make_shared<core::Session>(current_session());
    const std::string p = path.toStdString();
    // The input's SHA-256 is computed on the worker (a DICOM folder can be large).
    run_job(
        "Saving the session " + path, false, [session, p](const ProgressFn&) { core::save_session(*session, p); },
        [this, path, then](std::exception_ptr e) {
            if (e) {
                show_error("Cannot save the session", "Cannot save the session " + path, e);
                return;
            }
            session_path_ = path;
            remember_folder("session_folder", path);
            statusBar()->showMessage("Saved the session " + path);
            // Saved: nothing unsaved, nothing to recover.
            undo_->setClean();
            wait_for_autosave();
            remove_recovery_file();
            if (then) then();
        });
}

void MainWindow::open_session(const QString& path, bool recovered) {
    if (busy()) {
        statusBar()->showMessage("Busy: wait for the current task or cancel it");
        return;
    }
    auto result = std::make_shared<core::OpenedSession>();
    const std::string p = path.toStdString();
    // A fresh scene on the worker, as open_path: the one on screen stays
    // until the session opened.
    run_job(
        "Opening the session " + path, true,
        [result, p](const ProgressFn& progress) { *result = core::open_session(p, progress); },
        [this, result, path, recovered](std::exception_ptr e) {
            if (e) {
                show_error("Cannot open the session", "Cannot open the session " + path, e);
                return;
            }
            const core::Session& s = result->session;
            set_scene(std::move(result->scene), QString::fromStdString(s.input), QString::fromStdString(s.series));
            if (recovered) {
                undo_->resetClean(); // unsaved work again, saved nowhere else
                // The next autosave writes the recovery file again, from what this window shows.
                edited_since_autosave_ = true;
            } else {
                session_path_ = path;
                remember_folder("session_folder", path);
            }
            if (s.window) set_window_level(*s.window);
            // An older session has no layout or slice views: the window's layout and the default planes stay.
            if (s.layout) set_layout(*s.layout);
            if (s.slice_views) set_slice_views(*s.slice_views);
            set_slice_planes_in_3d(s.slice_planes_in_3d);
            set_markups(s.markups);
            restore_volume(s);
            // Through the view bar, which keeps its toggles for later views and gives them to this one.
            view_bar_->set_ao(s.ao);
            view_bar_->transparency_action()->setChecked(s.transparency);
            if (viewer_) {
                view_bar_->attach(*viewer_);
                if (s.camera) viewer_->set_camera(*s.camera);
            }
            QString msg =
                (recovered ? "Restored the unsaved work of the last run from " : "Opened the session ") + path;
            for (const auto& w : s.warnings) msg += "; warning: " + QString::fromStdString(w);
            statusBar()->showMessage(msg);
        });
}

void MainWindow::export_image(const QString& path, const core::RenderRequest& frame, const core::SessionParts& take) {
    if (busy()) {
        statusBar()->showMessage("Busy: wait for the current task or cancel it");
        return;
    }
    if (path_.isEmpty()) {
        statusBar()->showMessage("Open a volume or mesh first");
        return;
    }
    auto now = std::make_shared<core::Session>(current_session());
    bool write = false;
    const QString session = export_session_path(session_path_, *now, path, write);
    const std::string image = path.toStdString(), session_file = session.toStdString();
    // Exactly `isoscope render --session SESSION`: the session file is read
    // back and opened into a scene of its own (the window's scene and its GL
    // objects belong to the 3D view), rendered headlessly and written.
    run_job(
        "Exporting " + path, false,
        [now, write, image, session_file, frame, take](const ProgressFn& progress) {
            check_writable_destination(image);
            if (write) core::save_session(*now, session_file);
            const auto opened = core::open_session(session_file, progress);
            core::RenderRequest req = core::session_request(opened.session, session_file, frame, take);
            req.progress = progress; // disk AO's gather reports and can be cancelled
            const auto out = core::render_image(*opened.scene, req);
            core::export_image(out.image, out.meta, image);
        },
        [this, path, session](std::exception_ptr e) {
            if (e) {
                show_error("Cannot export the image", "Cannot export " + path, e);
                return;
            }
            remember_folder("export_folder", path);
            statusBar()->showMessage("Exported " + path + " (session " + session + ")");
        });
}

void MainWindow::export_dicom(const QString& folder, const core::RenderRequest& frame, const core::SessionParts& take) {
    if (busy()) {
        statusBar()->showMessage("Busy: wait for the current task or cancel it");
        return;
    }
    if (path_.isEmpty()) {
        statusBar()->showMessage("Open a volume or mesh first");
        return;
    }
    // As Export image, from the session: the saved one when it is the state
    // on screen (the figure's provenance names it), else a temporary one (not
    // named: it would not outlive the export).
    auto now = std::make_shared<core::Session>(current_session());
    bool write = false;
    const QString saved = export_session_path(session_path_, *now, QString(), write);
    const std::string session_file =
        write ? QDir::temp()
                    .filePath(QString("isoscope-dicom-export-%1.isoscope.json").arg(QCoreApplication::applicationPid()))
                    .toStdString()
              : saved.toStdString();
    const std::string dir = folder.toStdString();
    DicomCaptureOptions opt;
    opt.series_uid = dicom_series_.toStdString();
    auto result = std::make_shared<DicomCaptureResult>();
    run_job(
        "Exporting to DICOM in " + folder, false,
        [now, write, session_file, dir, frame, take, opt, result](const ProgressFn& progress) {
            if (write) core::save_session(*now, session_file);
            struct Remove {
                std::string f;
                ~Remove() {
                    if (!f.empty()) std::remove(f.c_str());
                }
            } remove{write ? session_file : std::string()};
            const auto opened = core::open_session(session_file, progress);
            core::RenderRequest req = core::session_request(opened.session, session_file, frame, take);
            req.progress = progress;
            auto out = core::render_image(*opened.scene, req);
            if (write) out.meta.text.erase("isoscope:session"), out.meta.text.erase("isoscope:session_sha256");
            *result = core::export_dicom(*opened.scene, out.image, out.meta, dir, opt);
        },
        [this, folder, result](std::exception_ptr e) {
            if (e) {
                show_error("Cannot export to DICOM", "Cannot export to DICOM in " + folder, e);
                return;
            }
            dicom_series_ = QString::fromStdString(result->series_uid);
            remember_folder("dicom_folder", folder + "/");
            statusBar()->showMessage(QString("Exported to DICOM: %1 (series %2 \"isoscope 3D\", image %3; %4)")
                                         .arg(QString::fromStdString(result->file))
                                         .arg(result->series_number)
                                         .arg(result->instance_number)
                                         .arg(result->source_study ? "in the source's study" : "a new study"));
        });
}

void MainWindow::save_surface(std::uint32_t id, const QString& path) {
    if (busy()) {
        statusBar()->showMessage("Busy: wait for the current task or cancel it");
        return;
    }
    const core::Scene* s = scene_.get();
    const std::string p = path.toStdString();
    // The worker only reads the mesh; nothing edits meshes while the
    // window-modal progress dialog is up.
    run_job(
        "Saving " + path, false, [s, id, p](const ProgressFn&) { s->export_mesh(id, p); },
        [this, path](std::exception_ptr e) {
            if (e) {
                show_error("Cannot save the surface", "Cannot save " + path, e);
                return;
            }
            remember_folder("surface_folder", path);
            statusBar()->showMessage("Saved " + path + " (LPS mm)");
        });
}

} // namespace iso::gui
