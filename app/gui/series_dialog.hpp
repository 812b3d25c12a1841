// The series chooser (docs/gui.md): when a DICOM folder holds
// several series, the main window lists them first (core::list_series, on a
// worker thread) and shows this table to choose one from: modality,
// description, series number, dimensions, slices and what loading would warn
// about (missing slices, uneven spacing, gantry tilt, a scout, a series that
// cannot be loaded). The row pre-selected is the series most fit for 3D
// (core::suggested_series). Presentation only: the list is the DICOM reader's
// (io/volume.hpp SeriesInfo).
#pragma once

#include <functional>
#include <vector>

#include <QDialog>
#include <QString>

#include "io/volume.hpp"

class QTableWidget;

namespace iso::gui {

class SeriesDialog : public QDialog {
public:
    // The table's columns, in order.
    enum Column { Modality, Description, Number, Dimensions, Slices, Warnings, ColumnCount };

    SeriesDialog(const QString& folder, std::vector<SeriesInfo> series, QWidget* parent = nullptr);

    const std::vector<SeriesInfo>& series() const { return series_; }
    QTableWidget* table() const { return table_; }
    // Chooses row `row` as the Open button does (accepts the dialog).
    void choose(int row);
    // Called with the chosen row when the dialog is accepted (Open, a
    // double click, Enter); Cancel or closing calls nothing.
    std::function<void(int)> on_chosen;

private:
    std::vector<SeriesInfo> series_;
    QTableWidget* table_ = nullptr;
};

} // namespace iso::gui
