// A slice view with its controls under it (docs/gui.md "Slice views"): a
// slider with one step per slice (core::slice_range, core::slice_index:
// one step is what core::scroll_slices moves), the slice's number and
// offset in mm, and a Fit button (SliceView::fit). The slider follows the
// plane whatever moved it (wheel, PageUp/PageDown, the crosshair), and
// moving it scrolls the view (SliceView::scroll) as the wheel does.
#pragma once

#include <QWidget>

#include "renderer/core/slices.hpp"

class QLabel;
class QSlider;
class QToolButton;

namespace iso::gui {

class SliceView;

class SlicePanel : public QWidget {
public:
    SlicePanel(core::SliceOrientation orientation, QWidget* parent = nullptr);

    SliceView* view() const { return view_; }
    QSlider* slider() const { return slider_; }
    QLabel* offset_label() const { return offset_; }
    QToolButton* fit_button() const { return fit_; }

private:
    void sync(); // the slider and label from the view's plane
    SliceView* view_ = nullptr;
    QSlider* slider_ = nullptr;
    QLabel* offset_ = nullptr;
    QToolButton* fit_ = nullptr;
    core::SliceRange range_;
    bool syncing_ = false;
};

} // namespace iso::gui
