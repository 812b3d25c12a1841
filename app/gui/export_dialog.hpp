// File > Export image and File > Save surfaces (docs/gui.md, "Export"):
// dialogs that only collect the user's choices. What they choose is done by
// Files::export_image / save_surface (files.hpp) through the core
// (core::session_request, core::render_image, core::export_image,
// core::Scene::export_mesh).
#pragma once

#include <cstdint>

#include <QDialog>
#include <QString>

#include "renderer/core/session.hpp"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QLineEdit;
class QSpinBox;

namespace iso::gui {

// Size, annotation scale, annotations, transparent background, markups,
// AO (off / cone / disk) and the file (.png, .tif, .exr). Widgets are named
// (width, height, scale, annotations, transparent, markups, ao, file) for
// tests; OK refuses an empty name or another extension, saying why.
// File > Export to DICOM uses it too (Kind::Dicom): a folder instead of the
// file (the DICOM figure's name is the writer's), no transparent background
// (a Secondary Capture is RGB).
class ExportDialog : public QDialog {
public:
    enum class Kind { Image, Dicom };
    // `ao`: the method the AO box starts at (the 3D view's).
    ExportDialog(QSize size, AoMethod ao, const QString& file, const QString& session_note, QWidget* parent = nullptr,
                 Kind kind = Kind::Image);
    // The frame chosen (size, scale, annotations, background, AO method)
    // and what of it the session gives (its camera, markups if chosen).
    core::RenderRequest frame() const;
    core::SessionParts parts() const;
    QString path() const;
    void accept() override;

private:
    QSpinBox *width_, *height_;
    QDoubleSpinBox* scale_;
    QCheckBox *annotations_, *legend_, *transparent_, *markups_;
    QComboBox* ao_;
    QLineEdit* file_;
    QLabel* problem_;
    Kind kind_;
};

// The data's name: the file's without its extensions ("headsq" for
// headsq.nhdr, "ct" for ct.nii.gz), a folder's own name; "untitled" for none.
QString data_name(const QString& data);
// A surface's part of its file name: its name without spaces ("iso 500" ->
// "iso500"), other characters unfit for file names as '-'.
QString surface_file_stem(const QString& surface_name);

// A surface of the scene (named by its row: name, triangles) and a format
// (STL, PLY, OBJ, VTP); the file name (in `folder`) is `stem`-surface.format
// (surface_file_stem) and follows the choices. Widgets: surface, format, file.
class SaveSurfacesDialog : public QDialog {
public:
    SaveSurfacesDialog(const core::Scene& scene, const QString& folder, const QString& stem, QWidget* parent = nullptr);
    std::uint32_t surface() const;
    QString path() const;
    void accept() override;

private:
    QComboBox *surface_, *format_;
    QLineEdit* file_;
    QLabel* problem_;
};

} // namespace iso::gui
