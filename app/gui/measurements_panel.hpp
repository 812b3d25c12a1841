// The Measurements dock (docs/gui.md "Pick and measure"): a table
// of the window's markups (MainWindow::markups(): rulers, angles, and what a
// loaded .mrk.json holds) with the name (editable), the kind, the value
// (mm or degrees, computed by the core from the points each time the
// markups change) and a delete button; and File > Save markups... / Load
// markups... through io/markups.hpp (3D Slicer's .mrk.json, LPS), errors in
// a dialog naming the file. Presentation only.
#pragma once

#include <QDockWidget>
#include <QString>

class QTableWidget;

namespace iso::gui {

class MainWindow;

class MeasurementsPanel : public QDockWidget {
public:
    enum Column { Name = 0, Kind = 1, Value = 2, Delete = 3 };

    explicit MeasurementsPanel(MainWindow& window);

    // Rebuilds the table from MainWindow::markups() (the window calls it
    // whenever they change).
    void refresh();
    QTableWidget* table() const { return table_; }

    // The file dialogs of File > Save markups... / Load markups....
    void save_dialog();
    void load_dialog();
    // Writes every markup to `path` (replaced whole or not at all) / adds the
    // markups of `path` to the window's. False on failure, after an error
    // dialog that names the file and the reason.
    bool save(const QString& path);
    bool load(const QString& path);

private:
    void rename(int row, const QString& name);
    void remove(int row);
    void show_error(const QString& what, const QString& reason);

    MainWindow& window_;
    QTableWidget* table_ = nullptr;
    bool filling_ = false;  // the table is being rebuilt: its item changes are not edits
    bool renaming_ = false; // a rename from the table: the table already shows it
};

} // namespace iso::gui
