#include "app/gui/export_dialog.hpp"

#include <algorithm>

#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QDir>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSpinBox>
#include <QVBoxLayout>

namespace iso::gui {

namespace {
// A file name (a folder with an empty filter) and its Browse button.
QLineEdit* file_row(QWidget* parent, QFormLayout* form, const QString& file, const QString& filter) {
    auto* row = new QHBoxLayout;
    auto* edit = new QLineEdit(file, parent);
    edit->setObjectName("file");
    edit->setMinimumWidth(360);
    auto* browse = new QPushButton("Browse...", parent);
    browse->setObjectName("browse");
    row->addWidget(edit, 1);
    row->addWidget(browse);
    form->addRow(filter.isEmpty() ? "Folder:" : "File:", row);
    QObject::connect(browse, &QPushButton::clicked, parent, [parent, edit, filter] {
        const QString f = filter.isEmpty() ? QFileDialog::getExistingDirectory(parent, "Export into", edit->text())
                                           : QFileDialog::getSaveFileName(parent, "Save as", edit->text(), filter);
        if (!f.isEmpty()) edit->setText(f);
    });
    return edit;
}

QLabel* problem_label(QWidget* parent) {
    auto* l = new QLabel(parent);
    l->setObjectName("problem");
    l->setStyleSheet("color: #c03030");
    l->setWordWrap(true);
    l->hide();
    return l;
}

QDialogButtonBox* buttons(QDialog* d, const QString& ok) {
    auto* b = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, d);
    b->button(QDialogButtonBox::Ok)->setText(ok);
    QObject::connect(b, &QDialogButtonBox::accepted, d, &QDialog::accept);
    QObject::connect(b, &QDialogButtonBox::rejected, d, &QDialog::reject);
    return b;
}
} // namespace

// ---- Export image ----------------------------------------------------------------------

ExportDialog::ExportDialog(QSize size, AoMethod ao, const QString& file, const QString& session_note, QWidget* parent,
                           Kind kind)
    : QDialog(parent), kind_(kind) {
    const bool dicom = kind == Kind::Dicom;
    setWindowTitle(dicom ? "Export to DICOM" : "Export image");
    setObjectName(dicom ? "export_dicom_dialog" : "export_dialog");
    auto* col = new QVBoxLayout(this);
    auto* form = new QFormLayout;
    auto* size_row = new QHBoxLayout;
    width_ = new QSpinBox(this);
    height_ = new QSpinBox(this);
    for (auto* s : {width_, height_}) s->setRange(16, 16384);
    width_->setObjectName("width");
    height_->setObjectName("height");
    width_->setValue(size.width());
    height_->setValue(size.height());
    size_row->addWidget(width_);
    size_row->addWidget(new QLabel("x", this));
    size_row->addWidget(height_);
    size_row->addStretch(1);
    form->addRow("Size (pixels):", size_row);
    scale_ = new QDoubleSpinBox(this);
    scale_->setObjectName("scale");
    scale_->setRange(0.1, 20.0);
    scale_->setSingleStep(0.5);
    scale_->setValue(1.0);
    scale_->setToolTip("Scale of text, lines and glyphs (2 for an image twice the view's size)");
    form->addRow("Annotation scale:", scale_);
    annotations_ = new QCheckBox("Scale bar and orientation letters", this);
    annotations_->setObjectName("annotations");
    annotations_->setChecked(true);
    form->addRow("Annotations:", annotations_);
    legend_ = new QCheckBox("Legend: the surfaces' names, colours and iso values", this);
    legend_->setObjectName("legend");
    legend_->setChecked(true);
    form->addRow("", legend_);
    connect(annotations_, &QCheckBox::toggled, legend_, &QWidget::setEnabled); // drawn only with annotations
    markups_ = new QCheckBox("Points, rulers and angles", this);
    markups_->setObjectName("markups");
    markups_->setChecked(true);
    form->addRow("Markups:", markups_);
    transparent_ = new QCheckBox("Transparent background", this);
    transparent_->setObjectName("transparent");
    if (dicom)
        transparent_->hide(); // a Secondary Capture is RGB
    else
        form->addRow("Background:", transparent_);
    ao_ = new QComboBox(this);
    ao_->setObjectName("ao");
    ao_->addItem("off", "off");
    ao_->addItem("cone traced", "cone");
    // The disk hierarchy (docs/ao.md, "Disk AO on the GPU"): slower, closer to ray tracing; for stills.
    ao_->addItem("high quality (disk)", "disk");
    // Embree ray tracing to a standard error of 0.005 per pixel (docs/ao.md): the ground truth; slowest.
    ao_->addItem("ray traced (reference)", "raytraced");
    ao_->setCurrentIndex(std::max(0, ao_->findData(QString(ao_method_name(ao)))));
    form->addRow("Ambient occlusion:", ao_);
    file_ = file_row(this, form, file, dicom ? QString() : "PNG (*.png);;TIFF (*.tif *.tiff);;OpenEXR (*.exr)");
    col->addLayout(form);
    auto* note = new QLabel(session_note, this);
    note->setObjectName("session_note");
    note->setWordWrap(true);
    col->addWidget(note);
    problem_ = problem_label(this);
    col->addWidget(problem_);
    col->addWidget(buttons(this, dicom ? "Export to DICOM" : "Export"));
}

core::RenderRequest ExportDialog::frame() const {
    core::RenderRequest r;
    r.width = width_->value();
    r.height = height_->value();
    r.scale = float(scale_->value());
    r.annotations = annotations_->isChecked();
    r.legend = legend_->isChecked();
    r.look.transparent_background = transparent_->isChecked();
    r.look.ao = ao_method_from_name(ao_->currentData().toString().toStdString());
    return r;
}

core::SessionParts ExportDialog::parts() const {
    core::SessionParts p;
    p.markups = markups_->isChecked();
    p.ao = false; // the dialog's AO box chooses
    return p;
}

QString ExportDialog::path() const { return file_->text().trimmed(); }

void ExportDialog::accept() {
    const QString suffix = QFileInfo(path()).suffix().toLower();
    if (path().isEmpty()) {
        problem_->setText(kind_ == Kind::Dicom ? "Choose a folder." : "Choose a file name.");
    } else if (kind_ == Kind::Dicom) {
        QDialog::accept();
        return;
    } else if (suffix != "png" && suffix != "tif" && suffix != "tiff" && suffix != "exr") {
        problem_->setText("The file name must end in .png, .tif or .exr.");
    } else {
        QDialog::accept();
        return;
    }
    problem_->show();
}

// ---- default file names ----------------------------------------------------------------

QString data_name(const QString& data) {
    if (data.isEmpty()) return "untitled";
    const QFileInfo fi(data);
    if (fi.isDir()) return QDir(fi.absoluteFilePath()).dirName();
    QString name = fi.fileName();
    if (name.endsWith(".gz", Qt::CaseInsensitive)) name.chop(3);
    const int dot = name.lastIndexOf('.');
    if (dot > 0) name.truncate(dot);
    return name.isEmpty() ? "untitled" : name;
}

QString surface_file_stem(const QString& surface_name) {
    QString stem;
    for (const QChar c : surface_name.trimmed()) {
        if (c.isSpace()) continue;
        stem += c.isLetterOrNumber() || c == '.' || c == '_' || c == '-' ? c : QChar('-');
    }
    return stem.isEmpty() ? "surface" : stem;
}

// ---- Save surfaces ---------------------------------------------------------------------

namespace {
const char* const kMeshFormats[][2] = {{"STL", "stl"}, {"PLY", "ply"}, {"OBJ", "obj"}, {"VTP (VTK XML)", "vtp"}};
}

SaveSurfacesDialog::SaveSurfacesDialog(const core::Scene& scene, const QString& folder, const QString& stem,
                                       QWidget* parent)
    : QDialog(parent) {
    setWindowTitle("Save surfaces");
    setObjectName("save_surfaces_dialog");
    auto* col = new QVBoxLayout(this);
    auto* form = new QFormLayout;
    surface_ = new QComboBox(this);
    surface_->setObjectName("surface");
    for (const auto id : scene.surfaces())
        surface_->addItem(QString("%1 (%2 triangles)")
                              .arg(QString::fromStdString(scene.info(id).name))
                              .arg(scene.mesh(id).triangles.size()),
                          id);
    form->addRow("Surface:", surface_);
    format_ = new QComboBox(this);
    format_->setObjectName("format");
    for (const auto& f : kMeshFormats) format_->addItem(f[0], f[1]);
    form->addRow("Format:", format_);
    file_ = file_row(this, form, QDir(folder).filePath("surface.stl"), "Meshes (*.stl *.ply *.obj *.vtp)");
    col->addLayout(form);
    auto* note = new QLabel("Positions in LPS millimetres, tagged LPS in the file.", this);
    col->addWidget(note);
    problem_ = problem_label(this);
    col->addWidget(problem_);
    col->addWidget(buttons(this, "Save"));
    // The file name follows the surface (iso 500 of headsq -> headsq-iso500.stl) and the format.
    const auto rename = [this, stem] {
        QFileInfo fi(file_->text());
        const QString surface = surface_file_stem(surface_->currentText().section(" (", 0, 0));
        file_->setText(fi.dir().filePath(stem + "-" + surface + "." + format_->currentData().toString()));
    };
    connect(surface_, &QComboBox::currentIndexChanged, this, rename);
    connect(format_, &QComboBox::currentIndexChanged, this, rename);
    rename();
}

std::uint32_t SaveSurfacesDialog::surface() const { return surface_->currentData().toUInt(); }

QString SaveSurfacesDialog::path() const { return file_->text().trimmed(); }

void SaveSurfacesDialog::accept() {
    const QString suffix = QFileInfo(path()).suffix().toLower();
    if (surface_->count() == 0) {
        problem_->setText("There is no surface to save.");
    } else if (path().isEmpty()) {
        problem_->setText("Choose a file name.");
    } else if (suffix != format_->currentData().toString()) {
        problem_->setText("The file name must end in ." + format_->currentData().toString() + " for " +
                          format_->currentText() + ".");
    } else {
        QDialog::accept();
        return;
    }
    problem_->show();
}

} // namespace iso::gui
