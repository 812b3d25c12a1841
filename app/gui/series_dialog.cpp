#include "app/gui/series_dialog.hpp"

#include <algorithm>

#include <QDialogButtonBox>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QTableWidget>
#include <QColor>
#include <QVBoxLayout>

#include "renderer/core/api.hpp"

namespace iso::gui {

namespace {
QString text(const std::string& s) { return QString::fromStdString(s); }
} // namespace

SeriesDialog::SeriesDialog(const QString& folder, std::vector<SeriesInfo> series, QWidget* parent)
    : QDialog(parent), series_(std::move(series)) {
    setObjectName("series_chooser");
    setWindowTitle("Choose a DICOM series");
    auto* col = new QVBoxLayout(this);
    col->addWidget(
        new QLabel(QString("%1 holds %2 series; choose the one to open:").arg(folder).arg(series_.size()), this));

    table_ = new QTableWidget(int(series_.size()), ColumnCount, this);
    table_->setObjectName("series_table");
    table_->setHorizontalHeaderLabels({"Modality", "Description", "Series #", "Dimensions", "Slices", "Warnings"});
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
    table_->setSelectionMode(QAbstractItemView::SingleSelection);
    table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
    table_->verticalHeader()->setVisible(false);
    table_->setWordWrap(true);
    for (int r = 0; r < int(series_.size()); ++r) {
        const SeriesInfo& s = series_[std::size_t(r)];
        QString warnings;
        for (const auto& w : s.warnings) warnings += (warnings.isEmpty() ? "" : "\n") + text(w);
        const QString cells[ColumnCount] = {
            s.modality.empty() ? "?" : text(s.modality),
            text(s.description),
            QString::number(s.number),
            QString("%1 x %2 x %3").arg(s.dims[0]).arg(s.dims[1]).arg(s.dims[2]),
            QString::number(s.files),
            warnings.isEmpty() ? "none" : warnings,
        };
        for (int c = 0; c < ColumnCount; ++c) {
            auto* item = new QTableWidgetItem(cells[c]);
            item->setToolTip(c == Warnings ? warnings : text(s.uid));
            table_->setItem(r, c, item);
        }
        // A series that will not load stands out before it is tried.
        if (!s.warnings.empty()) table_->item(r, Warnings)->setForeground(QColor(200, 120, 0));
    }
    table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
    table_->horizontalHeader()->setStretchLastSection(true);
    table_->resizeRowsToContents();
    // Pre-selected (Enter opens it): the series most fit for 3D, not a scout
    // that the table itself warns about (core::suggested_series).
    if (!series_.empty()) table_->selectRow(std::max(0, core::suggested_series(series_)));
    col->addWidget(table_, 1);

    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Open | QDialogButtonBox::Cancel, this);
    buttons->setObjectName("series_buttons");
    col->addWidget(buttons);
    connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    connect(table_, &QTableWidget::cellDoubleClicked, this, [this](int row, int) { choose(row); });
    connect(this, &QDialog::accepted, this, [this] {
        const auto rows = table_->selectionModel()->selectedRows();
        if (!rows.isEmpty() && on_chosen) on_chosen(rows.front().row());
    });
    resize(900, 160 + 40 * std::min<int>(int(series_.size()), 8));
}

void SeriesDialog::choose(int row) {
    if (row < 0 || row >= int(series_.size())) return;
    table_->selectRow(row);
    accept();
}

} // namespace iso::gui
