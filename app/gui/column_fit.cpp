#include "app/gui/column_fit.hpp"

#include <QEvent>
#include <QHeaderView>
#include <QScrollBar>
#include <QTableWidget>

#include <algorithm>
#include <vector>

namespace iso::gui {

ColumnFit::ColumnFit(QTableWidget* table, int floor_px)
    : QObject(table), table_(table), viewport_(table->viewport()), floor_(floor_px) {
    table_->horizontalHeader()->setSectionResizeMode(QHeaderView::Interactive);
    table_->horizontalHeader()->setStretchLastSection(false);
    table_->setTextElideMode(Qt::ElideRight);
    viewport_->installEventFilter(this);
}

// Only a resize of the viewport (it also sends events while the table is
// being destroyed: nothing of the table is called for those).
bool ColumnFit::eventFilter(QObject* watched, QEvent* e) {
    if (e->type() == QEvent::Resize && watched == viewport_) refit();
    return QObject::eventFilter(watched, e);
}

// The widths: each column's wanted width capped at one cap, the largest
// that makes them fit (water filling), never below the floor.
void ColumnFit::refit() {
    const int n = table_->columnCount();
    if (n == 0) return;
    QHeaderView* h = table_->horizontalHeader();
    const QAbstractItemView* view = table_; // sizeHintForColumn is public there
    std::vector<int> want(static_cast<std::size_t>(n));
    for (int c = 0; c < n; ++c) {
        int w = std::max(view->sizeHintForColumn(c), h->sectionSizeHint(c));
        for (int r = 0; r < table_->rowCount(); ++r) // a cell's widget (a Delete button)
            if (const QWidget* cell = table_->cellWidget(r, c)) w = std::max(w, cell->sizeHint().width());
        want[std::size_t(c)] = w;
    }
    const int avail = table_->viewport()->width();
    const auto total = [&](int cap) {
        int s = 0;
        for (const int w : want) s += std::min(w, std::max(cap, floor_));
        return s;
    };
    int cap = *std::max_element(want.begin(), want.end());
    if (total(cap) > avail) {
        int lo = 0, hi = cap; // the largest cap with total(cap) <= avail
        while (lo < hi) {
            const int mid = (lo + hi + 1) / 2;
            if (total(mid) <= avail)
                lo = mid;
            else
                hi = mid - 1;
        }
        cap = lo;
    }
    for (int c = 0; c < n; ++c) h->resizeSection(c, std::min(want[std::size_t(c)], std::max(cap, floor_)));
}

} // namespace iso::gui
