// The click-or-drag rule the 3D view and the slice views share: a press
// becomes a drag once the pointer has gone more than a few pixels from it;
// a release before that is a click.
#pragma once

#include <QPointF>

namespace iso::gui {

struct PointerDrag {
    static constexpr double kClickSlopPx = 3; // Manhattan distance from the press
    QPointF press, last;
    bool dragged = false;

    void start(QPointF at) {
        press = last = at;
        dragged = false;
    }
    // A move with a button held: true once the press has become a drag.
    bool follow(QPointF at) {
        if ((at - press).manhattanLength() > kClickSlopPx) dragged = true;
        return dragged;
    }
    // The motion since the last step (the press, for the drag's first step).
    QPointF step(QPointF at) {
        const QPointF d = at - last;
        last = at;
        return d;
    }
};

} // namespace iso::gui
