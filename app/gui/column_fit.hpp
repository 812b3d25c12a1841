// A table's columns kept within its width (the Measurements dock's tables):
// each column at its contents' width, and when they do not all fit, the
// widest give way first (down to a floor), their text elided (whole in the
// cells' tooltips), so that no column hides behind a horizontal scroll bar
// at the dock's width. Refitted when the table is resized and when its
// owner calls refit() after changing the rows.
#pragma once

#include <QObject>

class QTableWidget;

namespace iso::gui {

class ColumnFit : public QObject {
public:
    // Attached to `table` (its child: it goes with it).
    explicit ColumnFit(QTableWidget* table, int floor_px = 48);
    void refit();

protected:
    bool eventFilter(QObject* watched, QEvent* e) override;

private:
    QTableWidget* table_;
    QObject* viewport_; // compared, never called: it outlives the table's destructor's start
    int floor_;
};

} // namespace iso::gui
