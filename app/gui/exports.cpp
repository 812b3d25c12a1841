// Files (files.hpp): File > Export image, Export to DICOM and Save surfaces,
// each from the workspace's session, rendered and written off the GUI thread.
#include <QAction>
#include <QCoreApplication>
#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QMainWindow>
#include <QMenu>

#include <cstdio>
#include <memory>

#include "app/gui/app_context.hpp"
#include "app/gui/export_dialog.hpp"
#include "app/gui/files.hpp"
#include "app/gui/jobs.hpp"
#include "app/gui/viewer.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mesh.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/structures.hpp"

namespace iso::gui {

namespace {

// The session file an export names: the current one when it holds this
// state, else one written next to the image.
QString export_session_path(const std::string& session, const core::Session& now, const QString& image, bool& write) {
    write = false;
    if (!session.empty()) {
        try {
            if (core::same_state(core::read_session(session), now)) return QString::fromStdString(session);
        } catch (const Error&) {
            // Gone or damaged since: a fresh one next to the image.
        }
    }
    write = true;
    return image + ".session.json";
}

QSize view_size(const AppContext& c) {
    const Viewer* v = c.viewer();
    return v ? v->image_size() : QSize(1024, 1024);
}

} // namespace

bool Files::data_open() const {
    if (context_.workspace.has_data()) return true;
    context_.status("Open a volume or mesh first");
    return false;
}

void Files::add_export_actions(QMenu* file) {
    file->addAction("&Export image...", this, [this] { export_image_dialog(); });
    file->addAction("Export to &DICOM...", this, [this] { export_dicom_dialog(); });
    file->addAction("Save s&urfaces...", this, [this] { save_surfaces_dialog(); });
    QAction* labels = file->addAction("Export &label map...", this, [this] { export_label_map_dialog(); });
    labels->setObjectName("export_label_map");
    labels->setToolTip("The visible surfaces as a label map on the volume's grid (NIfTI, LPS) with a colour table: "
                       "3D Slicer loads it as a segmentation");
}

void Files::export_image_dialog() {
    const core::Workspace& w = context_.workspace;
    if (!data_open()) return;
    bool write = false;
    const QString image = QDir(start_folder("export")).filePath(data_name(QString::fromStdString(w.input())) + ".png");
    const QString named = export_session_path(w.session_path(), w.session(), image, write);
    const QString note =
        write ? "The state is also saved as a session next to the image (IMAGE.session.json); the image's "
                "metadata names it, so `isoscope render --session` can make it again."
              : "The image's metadata names the current session, " + named + " (unchanged since saved).";
    auto* d = new ExportDialog(view_size(context_), w.session().ao, image, note, &context_.window);
    d->setAttribute(Qt::WA_DeleteOnClose);
    connect(d, &QDialog::accepted, this, [this, d] { export_image(d->path(), d->frame(), d->parts()); });
    d->open();
}

void Files::export_dicom_dialog() {
    const core::Workspace& w = context_.workspace;
    if (!data_open()) return;
    const bool dicom_source = w.scene().has_volume() && w.scene().volume().meta.format == "DICOM";
    const QString note =
        QString(dicom_source ? "The figure joins the study of the DICOM series open (same patient and Study "
                               "Instance UID)"
                             : "The figure starts a new study (the data open is not from DICOM)") +
        ", as a Secondary Capture in the series \"isoscope 3D\" (one per session: later exports add "
        "images to it), annotations burned in, the settings that made it in its Image Comments.";
    auto* d =
        new ExportDialog(view_size(context_), w.session().ao,
                         QDir(start_folder("dicom")).filePath(data_name(QString::fromStdString(w.input())) + "-dicom"),
                         note, &context_.window, ExportDialog::Kind::Dicom);
    d->setAttribute(Qt::WA_DeleteOnClose);
    connect(d, &QDialog::accepted, this, [this, d] { export_dicom(d->path(), d->frame(), d->parts()); });
    d->open();
}

void Files::save_surfaces_dialog() {
    const core::Workspace& w = context_.workspace;
    if (w.scene().surfaces().empty()) {
        context_.status("No surface to save: add one in the Surfaces panel");
        return;
    }
    auto* d = new SaveSurfacesDialog(w.scene(), start_folder("surface"), data_name(QString::fromStdString(w.input())),
                                     &context_.window);
    d->setAttribute(Qt::WA_DeleteOnClose);
    connect(d, &QDialog::accepted, this, [this, d] { save_surface(d->surface(), d->path()); });
    d->open();
}

void Files::export_label_map_dialog() {
    const core::Workspace& w = context_.workspace;
    if (!w.scene().has_volume() || w.scene().surfaces().empty()) {
        context_.status("A label map needs a volume and a surface: open a volume and add a surface first");
        return;
    }
    auto* d = new QFileDialog(
        &context_.window, "Export label map",
        QDir(start_folder("labels")).filePath(data_name(QString::fromStdString(w.input())) + "-labels.nii.gz"),
        "NIfTI label map (*.nii.gz *.nii)");
    d->setAcceptMode(QFileDialog::AcceptSave);
    d->setOption(QFileDialog::DontUseNativeDialog);
    d->setAttribute(Qt::WA_DeleteOnClose);
    connect(d, &QFileDialog::fileSelected, this, [this](const QString& path) { export_label_map(path); });
    d->open();
}

void Files::export_label_map(const QString& path) {
    if (context_.busy(true)) return;
    const core::Scene* scene = &context_.workspace.scene();
    std::vector<core::SurfaceId> ids;
    for (const auto id : scene->surfaces())
        if (scene->info(id).visible) ids.push_back(id);
    const std::string p = path.toStdString();
    auto table = std::make_shared<std::string>();
    auto count = std::make_shared<std::size_t>(0);
    context_.jobs.run(
        "Exporting the label map " + path, false,
        [scene, ids, p, table, count](const ProgressFn&) {
            core::label_map_table(p, "label map"); // refused before any work when not .nii or .nii.gz
            const core::LabelMap m = core::structures_label_map(*scene, ids);
            *count = m.entries.size();
            *table = core::save_label_map(m, p);
        },
        [this, path, table, count](std::exception_ptr e) {
            if (e) {
                context_.error("Cannot export the label map", "Cannot export " + path, e);
                return;
            }
            remember_folder("labels", path);
            context_.status(QString("Exported %1 structures as labels 1-%1 to %2 (colour table %3)")
                                .arg(*count)
                                .arg(path, QString::fromStdString(*table)));
        });
}

void Files::export_image(const QString& path, const core::RenderRequest& frame, const core::SessionParts& take) {
    if (context_.busy(true)) return;
    const core::Workspace& w = context_.workspace;
    if (!data_open()) return;
    auto now = std::make_shared<core::Session>(w.session());
    bool write = false;
    const QString session = export_session_path(w.session_path(), *now, path, write);
    const std::string image = path.toStdString(), session_file = session.toStdString();
    // Exactly `isoscope render --session SESSION`: the session file is read
    // back and opened into a scene of its own (the workspace's scene and its
    // GL objects belong to the 3D view), rendered headlessly and written.
    context_.jobs.run(
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
                context_.error("Cannot export the image", "Cannot export " + path, e);
                return;
            }
            remember_folder("export", path);
            context_.status("Exported " + path + " (session " + session + ")");
        });
}

void Files::export_dicom(const QString& folder, const core::RenderRequest& frame, const core::SessionParts& take) {
    if (context_.busy(true)) return;
    const core::Workspace& w = context_.workspace;
    if (!data_open()) return;
    // As Export image, from the session: the saved one when it is the state
    // on screen (the figure's provenance names it), else a temporary one (not
    // named: it would not outlive the export).
    auto now = std::make_shared<core::Session>(w.session());
    bool write = false;
    const QString saved = export_session_path(w.session_path(), *now, QString(), write);
    const std::string session_file =
        write ? QDir::temp()
                    .filePath(QString("isoscope-dicom-export-%1.isoscope.json").arg(QCoreApplication::applicationPid()))
                    .toStdString()
              : saved.toStdString();
    const std::string dir = folder.toStdString();
    DicomCaptureOptions opt;
    opt.series_uid = dicom_series_.toStdString();
    auto result = std::make_shared<DicomCaptureResult>();
    context_.jobs.run(
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
                context_.error("Cannot export to DICOM", "Cannot export to DICOM in " + folder, e);
                return;
            }
            dicom_series_ = QString::fromStdString(result->series_uid);
            remember_folder("dicom", QFileInfo(folder).absolutePath());
            context_.status(QString("Exported to DICOM: %1 (series %2 \"isoscope 3D\", image %3; %4)")
                                .arg(QString::fromStdString(result->file))
                                .arg(result->series_number)
                                .arg(result->instance_number)
                                .arg(result->source_study ? "in the source's study" : "a new study"));
        });
}

void Files::save_surface(std::uint32_t id, const QString& path) {
    if (context_.busy(true)) return;
    // The worker reads the surface's mesh as it is now (shared, never changed in place).
    const std::shared_ptr<const Mesh> mesh = context_.workspace.scene().shared_mesh(id);
    const std::string p = path.toStdString();
    context_.jobs.run(
        "Saving " + path, false, [mesh, p](const ProgressFn&) { save_mesh(*mesh, p); },
        [this, path](std::exception_ptr e) {
            if (e) {
                context_.error("Cannot save the surface", "Cannot save " + path, e);
                return;
            }
            remember_folder("surface", path);
            context_.status("Saved " + path + " (LPS mm)");
        });
}

} // namespace iso::gui
