#include "app/gui/measurements_panel.hpp"

#include <QFileDialog>
#include <QFileInfo>
#include <QHeaderView>
#include <QMessageBox>
#include <QStatusBar>
#include <QTableWidget>
#include <QTimer>
#include <QToolButton>

#include "app/gui/main_window.hpp"
#include "io/markups.hpp"

namespace iso::gui {

namespace {

QString kind_text(MarkupType t) {
    switch (t) {
    case MarkupType::Fiducial: return "Point list";
    case MarkupType::Line: return "Line";
    case MarkupType::Angle: return "Angle";
    case MarkupType::Curve: return "Curve";
    case MarkupType::ClosedCurve: return "Closed curve";
    }
    return {};
}

// Lines and angles: computed from the points (io/markups.hpp, the values the
// writer stores and Slicer shows). Others: their points, and a curve's length
// as the file stored it (isoscope does not rebuild Slicer's spline).
QString value_text(const Markup& m) {
    if (const auto meas = computed_measurement(m)) {
        if (!meas->value) return "-";
        return m.type == MarkupType::Line ? QString("%1 mm").arg(*meas->value, 0, 'f', 2)
                                          : QString("%1%2").arg(*meas->value, 0, 'f', 2).arg(QChar(0x00B0));
    }
    for (const auto& s : m.measurements)
        if (s.name == "length" && s.value)
            return QString("%1 %2 (stored)").arg(*s.value, 0, 'f', 2).arg(QString::fromStdString(s.units));
    return QString("%1 point(s)").arg(m.points.size());
}

} // namespace

MeasurementsPanel::MeasurementsPanel(MainWindow& window) : QDockWidget("Measurements", &window), window_(window) {
    setObjectName("measurements");
    table_ = new QTableWidget(0, 4, this);
    table_->setObjectName("measurements_table");
    table_->setHorizontalHeaderLabels({"Name", "Kind", "Value", ""});
    table_->verticalHeader()->setVisible(false);
    table_->horizontalHeader()->setSectionResizeMode(Name, QHeaderView::Stretch);
    table_->horizontalHeader()->setSectionResizeMode(Kind, QHeaderView::ResizeToContents);
    table_->horizontalHeader()->setSectionResizeMode(Value, QHeaderView::ResizeToContents);
    table_->horizontalHeader()->setSectionResizeMode(Delete, QHeaderView::ResizeToContents);
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
    table_->setEditTriggers(QAbstractItemView::DoubleClicked | QAbstractItemView::EditKeyPressed |
                            QAbstractItemView::AnyKeyPressed);
    connect(table_, &QTableWidget::itemChanged, this, [this](QTableWidgetItem* item) {
        if (filling_ || item->column() != Name) return;
        rename(item->row(), item->text());
    });
    setWidget(table_);
    refresh();
}

void MeasurementsPanel::refresh() {
    if (renaming_) return; // the table shows the new name already
    filling_ = true;
    const auto& markups = window_.markups();
    table_->setRowCount(0);
    table_->setRowCount(int(markups.size()));
    for (int row = 0; row < int(markups.size()); ++row) {
        const Markup& m = markups[std::size_t(row)];
        auto* name = new QTableWidgetItem(QString::fromStdString(m.name));
        name->setToolTip("Double-click to rename");
        table_->setItem(row, Name, name);
        for (const auto& [col, text] :
             {std::pair{int(Kind), kind_text(m.type)}, std::pair{int(Value), value_text(m)}}) {
            auto* item = new QTableWidgetItem(text);
            item->setFlags(item->flags() & ~Qt::ItemIsEditable);
            table_->setItem(row, col, item);
        }
        auto* del = new QToolButton(table_);
        del->setObjectName("delete");
        del->setText(QString(QChar(0x2715)));
        del->setToolTip("Delete this measurement");
        del->setAutoRaise(true);
        // Queued: the button goes with the table's rebuild.
        connect(del, &QToolButton::clicked, this,
                [this, row] { QTimer::singleShot(0, this, [this, row] { remove(row); }); });
        table_->setCellWidget(row, Delete, del);
    }
    filling_ = false;
}

void MeasurementsPanel::rename(int row, const QString& name) {
    std::vector<Markup> m = window_.markups();
    if (row < 0 || row >= int(m.size())) return;
    m[std::size_t(row)].name = name.toStdString();
    renaming_ = true;
    window_.set_markups(std::move(m));
    renaming_ = false;
}

void MeasurementsPanel::remove(int row) {
    std::vector<Markup> m = window_.markups();
    if (row < 0 || row >= int(m.size())) return;
    const QString name = QString::fromStdString(m[std::size_t(row)].name);
    m.erase(m.begin() + row);
    window_.set_markups(std::move(m));
    window_.statusBar()->showMessage("Deleted " + (name.isEmpty() ? QString("the measurement") : name));
}

void MeasurementsPanel::show_error(const QString& what, const QString& reason) {
    window_.statusBar()->showMessage(what + ": failed");
    // Not exec(): the window keeps running (and tests can find and close the box).
    auto* box = new QMessageBox(QMessageBox::Critical, "Markups", what + "\n\n" + reason, QMessageBox::Ok, &window_);
    box->setObjectName("error");
    box->setAttribute(Qt::WA_DeleteOnClose);
    box->open();
}

bool MeasurementsPanel::save(const QString& path) {
    const QString what = "Cannot save markups to " + path;
    if (window_.markups().empty()) {
        show_error(what, "there are no measurements to save");
        return false;
    }
    try {
        MarkupsFile f;
        f.markups = window_.markups();
        save_markups(f, path.toStdString());
    } catch (const std::exception& e) {
        show_error(what, QString::fromStdString(e.what()));
        return false;
    }
    window_.statusBar()->showMessage(QString("Saved %1 measurement(s) to %2").arg(window_.markups().size()).arg(path));
    return true;
}

bool MeasurementsPanel::load(const QString& path) {
    MarkupsFile f;
    try {
        f = load_markups(path.toStdString());
    } catch (const std::exception& e) {
        show_error("Cannot load markups from " + path, QString::fromStdString(e.what()));
        return false;
    }
    // Slicer does not write names: it names a node after its file.
    QString stem = QFileInfo(path).fileName();
    for (const char* suffix : {".mrk.json", ".json"})
        if (stem.endsWith(suffix, Qt::CaseInsensitive)) {
            stem.chop(int(std::string_view(suffix).size()));
            break;
        }
    int unnamed = 0;
    for (auto& m : f.markups)
        if (m.name.empty()) m.name = (unnamed++ ? QString("%1 %2").arg(stem).arg(unnamed) : stem).toStdString();
    std::vector<Markup> all = window_.markups();
    const std::size_t added = f.markups.size();
    for (auto& m : f.markups) all.push_back(std::move(m));
    window_.set_markups(std::move(all));
    QString msg = QString("Loaded %1 measurement(s) from %2").arg(added).arg(path);
    for (const auto& w : f.warnings) msg += "; " + QString::fromStdString(w);
    window_.statusBar()->showMessage(msg);
    return true;
}

void MeasurementsPanel::save_dialog() {
    QString f = QFileDialog::getSaveFileName(&window_, "Save markups", QString(), "3D Slicer markups (*.mrk.json)");
    if (f.isEmpty()) return;
    if (!f.endsWith(".json", Qt::CaseInsensitive)) f += ".mrk.json";
    save(f);
}

void MeasurementsPanel::load_dialog() {
    const QString f = QFileDialog::getOpenFileName(&window_, "Load markups", QString(),
                                                   "3D Slicer markups (*.mrk.json *.json);;All files (*)");
    if (!f.isEmpty()) load(f);
}

} // namespace iso::gui
