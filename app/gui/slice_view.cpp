#include "app/gui/slice_view.hpp"

#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QWheelEvent>

#include <cmath>
#include <iostream>

#include "io/color.hpp"
#include "renderer/core/scene.hpp"

namespace iso::gui {

// Through "#rrggbb", as sessions and the CLI write colours: the colour
// dialog opens on, and gives back, exactly the hex a session saves.
QColor to_qcolor(const glm::vec3& linear) { return QColor(QString::fromStdString(hex_from_linear(linear))); }

glm::vec3 from_qcolor(const QColor& c) { return linear_from_hex(c.name(QColor::HexRgb).toStdString()); }

SliceView::SliceView(core::SliceOrientation orientation, QWidget* parent) : QWidget(parent), orientation_(orientation) {
    setFocusPolicy(Qt::StrongFocus);
    setMinimumSize(160, 160);
    setAttribute(Qt::WA_OpaquePaintEvent);
}

void SliceView::set_content(const core::Scene* scene, core::SlicePlane* plane) {
    scene_ = scene;
    plane_ = plane;
    fitted_ = false;
    range_.reset();
    refresh();
}

void SliceView::set_window(const core::WindowLevel& w) {
    window_ = w;
    if (!values_.values.empty()) {
        grey_ = core::apply_window(values_, window_, core::PixelFormat::Grey8);
        image_ = QImage(grey_.data(), values_.width, values_.height, values_.width, QImage::Format_Grayscale8).copy();
    }
    update();
}

std::size_t SliceView::outline_segments() const {
    std::size_t n = 0;
    for (const auto& o : outlines_) n += o.segments.size();
    return n;
}

void SliceView::refresh() {
    image_ = QImage();
    outlines_.clear();
    if (!scene_ || !plane_ || !scene_->has_volume() || width() < 1 || height() < 1) {
        update();
        return;
    }
    try {
        if (!fitted_) {
            core::zoom_to_fit(*plane_, width(), height());
            fitted_ = true;
        }
        grid_ = core::slice_grid(*plane_, width(), height());
        core::reslice(scene_->volume(), grid_, core::Interp::Linear, values_);
        grey_ = core::apply_window(values_, window_, core::PixelFormat::Grey8);
        image_ = QImage(grey_.data(), values_.width, values_.height, values_.width, QImage::Format_Grayscale8).copy();
        for (auto id : scene_->surfaces()) {
            const auto& info = scene_->info(id);
            if (!info.visible) continue;
            outlines_.push_back({core::mesh_outline(scene_->mesh(id), grid_), to_qcolor(info.color)});
        }
    } catch (const std::exception& e) {
        // Nothing escapes into Qt's event loop.
        std::cerr << "isoscope gui: " << core::slice_orientation_name(orientation_) << " view: " << e.what() << "\n";
        image_ = QImage();
    }
    update();
}

void SliceView::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.fillRect(rect(), Qt::black);
    if (image_.isNull()) return;
    p.drawImage(0, 0, image_);
    p.setRenderHint(QPainter::Antialiasing);
    for (const auto& o : outlines_) {
        p.setPen(QPen(o.color, 1.5));
        for (const auto& s : o.segments) p.drawLine(QPointF(s.a.x, s.a.y), QPointF(s.b.x, s.b.y));
    }
    const auto c = core::lps_to_pixel(grid_, plane_->origin).pixel;
    p.setPen(QPen(QColor(255, 200, 0, 160), 1.0, Qt::DashLine));
    p.drawLine(QPointF(c.x, 0), QPointF(c.x, height()));
    p.drawLine(QPointF(0, c.y), QPointF(width(), c.y));
    p.setPen(Qt::yellow);
    p.drawText(
        QPointF(6, 16),
        QString("%1  %2 mm").arg(core::slice_orientation_name(orientation_)).arg(plane_->offset_mm(), 0, 'f', 1));
    if (on_paint_overlay) on_paint_overlay(*this, p);
}

void SliceView::resizeEvent(QResizeEvent*) {
    fitted_ = false;
    refresh();
}

void SliceView::mousePressEvent(QMouseEvent* e) {
    drag_.start(e->position());
    window_at_press_ = window_;
    grabbing_ = e->button() == Qt::LeftButton && e->buttons() == Qt::LeftButton && !image_.isNull() && on_press &&
                on_press(*this, e->position());
}

void SliceView::mouseReleaseEvent(QMouseEvent* e) {
    if (grabbing_ && e->button() == Qt::LeftButton) {
        grabbing_ = false;
        if (on_grab_release) on_grab_release(*this, e->position(), drag_.dragged);
    }
    if (e->button() == Qt::LeftButton && !drag_.dragged && on_click && !image_.isNull()) on_click(*this, e->position());
}

void SliceView::mouseMoveEvent(QMouseEvent* e) {
    if (e->buttons() == Qt::NoButton || image_.isNull() || !plane_) return;
    if (!drag_.follow(e->position())) return;
    const QPointF d = drag_.step(e->position());
    if (grabbing_) { // a markup point follows the pointer; the window stays
        if (on_grab_move) on_grab_move(*this, e->position());
        return;
    }
    if (e->buttons() & Qt::LeftButton) {
        if (!range_) range_ = scene_->volume().value_range();
        const QPointF total = e->position() - drag_.press;
        const auto w = core::drag_window(window_at_press_, {total.x(), -total.y()}, *range_);
        set_window(w);
        if (on_window) on_window(*this, w);
    } else if (e->buttons() & Qt::MiddleButton) {
        core::pan_pixels(*plane_, {d.x(), d.y()});
        refresh();
    } else if (e->buttons() & Qt::RightButton) {
        core::zoom_about(*plane_, width(), height(), {drag_.press.x(), drag_.press.y()},
                         core::drag_zoom_factor(-d.y(), height()));
        refresh();
    }
}

void SliceView::wheelEvent(QWheelEvent* e) {
    wheel_ += e->angleDelta().y();
    const double steps = std::trunc(wheel_ / 120.0);
    if (steps != 0 && on_scroll) {
        wheel_ -= steps * 120.0;
        on_scroll(*this, steps);
    }
    e->accept();
}

void SliceView::keyPressEvent(QKeyEvent* e) {
    if ((e->key() == Qt::Key_PageUp || e->key() == Qt::Key_PageDown) && on_scroll) {
        on_scroll(*this, e->key() == Qt::Key_PageUp ? 1.0 : -1.0);
        return;
    }
    QWidget::keyPressEvent(e);
}

} // namespace iso::gui
