#include "app/gui/slice_panel.hpp"

#include <QHBoxLayout>
#include <QLabel>
#include <QSlider>
#include <QToolButton>
#include <QVBoxLayout>

#include "app/gui/slice_view.hpp"
#include "renderer/core/scene.hpp"

namespace iso::gui {

SlicePanel::SlicePanel(core::SliceOrientation orientation, QWidget* parent) : QWidget(parent) {
    const QString name = core::slice_orientation_name(orientation);
    setObjectName(name + "_panel");
    auto* col = new QVBoxLayout(this);
    col->setContentsMargins(0, 0, 0, 0);
    col->setSpacing(1);
    view_ = new SliceView(orientation, this);
    view_->setObjectName(name);
    col->addWidget(view_, 1);
    auto* row = new QHBoxLayout;
    row->setContentsMargins(2, 0, 2, 0);
    slider_ = new QSlider(Qt::Horizontal, this);
    slider_->setObjectName(name + "_slider");
    slider_->setToolTip(
        QString("The %1 slice: one step per slice, as the wheel and Page Up / Page Down move it").arg(name));
    slider_->setEnabled(false);
    row->addWidget(slider_, 1);
    offset_ = new QLabel(this);
    offset_->setObjectName(name + "_offset");
    offset_->setToolTip("The slice's number of the slices along the view's normal, and its position in LPS mm");
    offset_->setMinimumWidth(offset_->fontMetrics().horizontalAdvance("888 / 888  -8888.8 mm"));
    row->addWidget(offset_);
    fit_ = new QToolButton(this);
    fit_->setObjectName(name + "_fit");
    fit_->setText("Fit");
    fit_->setToolTip("Fit (F, or double-click the view): re-centre on the volume and zoom it to fit the view, "
                     "undoing pan and zoom; the slice stays");
    fit_->setEnabled(false);
    row->addWidget(fit_);
    col->addLayout(row);
    connect(fit_, &QToolButton::clicked, this, [this] { view_->fit(); });
    connect(slider_, &QSlider::valueChanged, this, [this](int value) {
        const core::SlicePlane* p = view_->plane();
        if (syncing_ || !p) return;
        // The steps from the slice shown now: the plane keeps its place between slices.
        const int steps = value - core::slice_index(range_, p->offset_mm());
        if (steps != 0) view_->scroll(double(steps));
    });
    view_->on_refresh = [this](SliceView&) { sync(); };
    sync();
}

void SlicePanel::sync() {
    const core::SlicePlane* p = view_->plane();
    const bool volume = p != nullptr;
    syncing_ = true;
    slider_->setEnabled(volume);
    fit_->setEnabled(volume);
    if (!volume) {
        slider_->setRange(0, 0);
        offset_->setText("no volume");
    } else {
        range_ = core::slice_range(view_->scene()->volume(), *p);
        const int index = core::slice_index(range_, p->offset_mm());
        slider_->setRange(0, range_.count - 1);
        slider_->setValue(index);
        offset_->setText(QString("%1 / %2  %3 mm").arg(index + 1).arg(range_.count).arg(p->offset_mm(), 0, 'f', 1));
    }
    syncing_ = false;
}

} // namespace iso::gui
