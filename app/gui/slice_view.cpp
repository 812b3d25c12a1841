#include "app/gui/slice_view.hpp"

#include <QFont>
#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QWheelEvent>

#include <cmath>
#include <utility>
#include <iostream>

#include "io/color.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::gui {

// Through "#rrggbb", as sessions and the CLI write colours: the colour
// dialog opens on, and gives back, exactly the hex a session saves.
QColor to_qcolor(const glm::vec3& linear) { return QColor(QString::fromStdString(hex_from_linear(linear))); }

glm::vec3 from_qcolor(const QColor& c) { return linear_from_hex(c.name(QColor::HexRgb).toStdString()); }

SliceView::SliceView(core::SliceOrientation orientation, QWidget* parent) : QWidget(parent), orientation_(orientation) {
    setFocusPolicy(Qt::StrongFocus);
    setMinimumSize(160, 160);
    setAttribute(Qt::WA_OpaquePaintEvent);
    setMouseTracking(true); // the hover probe
}

QString slice_readout(const Volume& v, const core::SliceGrid& g, QPointF pixel) {
    const glm::dvec2 px{pixel.x(), pixel.y()};
    const glm::dvec3 lps = core::pixel_to_lps(g, px);
    QString msg = QString("LPS (%1, %2, %3) mm").arg(lps.x, 0, 'f', 2).arg(lps.y, 0, 'f', 2).arg(lps.z, 0, 'f', 2);
    if (const auto s = core::sample_at_pixel(v, g, px))
        return msg + QString(", %1, voxel (%2, %3, %4)")
                         .arg(QString::fromStdString(core::value_readout(s->value, core::value_unit(v))))
                         .arg(s->voxel[0])
                         .arg(s->voxel[1])
                         .arg(s->voxel[2]);
    return msg + ", outside the volume";
}

void SliceView::set_content(const core::Scene* scene, core::SlicePlane* plane) {
    scene_ = scene;
    plane_ = plane;
    fitted_ = user_framed_ = false;
    range_.reset();
    refresh();
}

void SliceView::keep_framing() {
    fitted_ = user_framed_ = true;
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
    update_probe(); // the slice under the pointer moved
    update();
    if (on_refresh) on_refresh(*this);
}

void SliceView::fit() {
    if (!scene_ || !plane_ || !scene_->has_volume()) return;
    core::fit_view(*plane_, scene_->volume(), width(), height());
    fitted_ = true;
    user_framed_ = false; // fitted again: a resize fits it again too
    refresh();
}

void SliceView::update_probe() {
    probe_.clear();
    if (hover_ && !image_.isNull() && scene_ && scene_->has_volume())
        probe_ = slice_readout(scene_->volume(), grid_, *hover_);
}

QString SliceView::edge_letter(core::SliceEdge e) const {
    return image_.isNull() || !plane_ ? QString() : QString::fromStdString(core::slice_edge_letter(*plane_, e));
}

double SliceView::scale_bar_mm() const {
    return image_.isNull() || !plane_ ? 0.0 : core::slice_scale_bar_mm(*plane_, grid_.width);
}

double SliceView::scale_bar_pixels() const { return image_.isNull() ? 0.0 : scale_bar_mm() / grid_.pixel_mm; }

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
    paint_annotations(p);
}

namespace {
// Text readable on any grey: a dark halo under it.
void halo_text(QPainter& p, const QRectF& box, int flags, const QString& text, const QColor& c) {
    p.setPen(QColor(0, 0, 0, 230));
    for (const QPointF d : {QPointF(-1, 0), QPointF(1, 0), QPointF(0, -1), QPointF(0, 1), QPointF(1, 1)})
        p.drawText(box.translated(d), flags, text);
    p.setPen(c);
    p.drawText(box, flags, text);
}
} // namespace

// The letters at the edges' middles, the scale bar bottom right, the probe bottom left.
void SliceView::paint_annotations(QPainter& p) const {
    const QColor text(235, 235, 235);
    const double w = width(), h = height(), m = 4;
    QFont bold = p.font();
    bold.setBold(true);
    p.setFont(bold);
    const double lh = p.fontMetrics().height();
    halo_text(p, QRectF(m, 0, w - 2 * m, h), Qt::AlignLeft | Qt::AlignVCenter, edge_letter(core::SliceEdge::Left),
              text);
    halo_text(p, QRectF(m, 0, w - 2 * m, h), Qt::AlignRight | Qt::AlignVCenter, edge_letter(core::SliceEdge::Right),
              text);
    halo_text(p, QRectF(0, m, w, h), Qt::AlignHCenter | Qt::AlignTop, edge_letter(core::SliceEdge::Top), text);
    halo_text(p, QRectF(0, 0, w, h - m), Qt::AlignHCenter | Qt::AlignBottom, edge_letter(core::SliceEdge::Bottom),
              text);
    p.setFont(font());
    const double mm = scale_bar_mm(), len = scale_bar_pixels();
    if (mm > 0 && len >= 1) {
        const double x1 = w - 12, x0 = x1 - len, y = h - 12;
        for (const auto& [colour, thick] : {std::pair{QColor(0, 0, 0, 230), 4.0}, std::pair{text, 2.0}}) {
            p.setPen(QPen(colour, thick, Qt::SolidLine, Qt::FlatCap));
            p.drawLine(QPointF(x0, y), QPointF(x1, y));
            p.drawLine(QPointF(x0, y - 5), QPointF(x0, y + 1));
            p.drawLine(QPointF(x1, y - 5), QPointF(x1, y + 1));
        }
        const QString label = QString("%1 mm").arg(mm, 0, 'g', 6);
        halo_text(p, QRectF(x0 - 40, y - 6 - lh, len + 80, lh), Qt::AlignHCenter | Qt::AlignBottom, label, text);
    }
    if (probe_.isEmpty()) return;
    // Two lines above the bottom letter: the point, then the value and voxel.
    const int cut = probe_.indexOf("mm, ");
    const QString first = cut < 0 ? probe_ : probe_.left(cut + 2), second = cut < 0 ? QString() : probe_.mid(cut + 4);
    const QColor probe(255, 230, 120);
    halo_text(p, QRectF(6, h - 8 - 3 * lh, w - 12, lh), Qt::AlignLeft | Qt::AlignBottom, first, probe);
    halo_text(p, QRectF(6, h - 8 - 2 * lh, w - 12, lh), Qt::AlignLeft | Qt::AlignBottom, second, probe);
}

void SliceView::resizeEvent(QResizeEvent*) {
    if (!user_framed_) fitted_ = false;
    refresh();
}

void SliceView::mousePressEvent(QMouseEvent* e) {
    swallow_release_ = false;
    drag_.start(e->position());
    window_at_press_ = window_;
    grabbing_ = e->button() == Qt::LeftButton && e->buttons() == Qt::LeftButton && !image_.isNull() && on_press &&
                on_press(*this, e->position());
}

void SliceView::mouseReleaseEvent(QMouseEvent* e) {
    if (swallow_release_ && e->button() == Qt::LeftButton) {
        swallow_release_ = false; // the double-click's release: no click
        return;
    }
    if (grabbing_ && e->button() == Qt::LeftButton) {
        grabbing_ = false;
        if (on_grab_release) on_grab_release(*this, e->position(), drag_.dragged);
    }
    if (e->button() == Qt::LeftButton && !drag_.dragged && on_click && !image_.isNull()) on_click(*this, e->position());
}

void SliceView::mouseDoubleClickEvent(QMouseEvent* e) {
    mousePressEvent(e); // the second press of the double-click
    if (e->button() != Qt::LeftButton || grabbing_) return;
    fit();
    swallow_release_ = true;
}

void SliceView::leaveEvent(QEvent*) {
    hover_.reset();
    probe_.clear();
    update();
}

void SliceView::mouseMoveEvent(QMouseEvent* e) {
    if (e->buttons() == Qt::NoButton) {
        hover_ = e->position();
        update_probe();
        update();
        return;
    }
    if (image_.isNull() || !plane_) return;
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
        user_framed_ = true;
        refresh();
    } else if (e->buttons() & Qt::RightButton) {
        core::zoom_about(*plane_, width(), height(), {drag_.press.x(), drag_.press.y()},
                         core::drag_zoom_factor(-d.y(), height()));
        user_framed_ = true;
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
    if (e->key() == Qt::Key_F && e->modifiers() == Qt::NoModifier) {
        fit();
        return;
    }
    QWidget::keyPressEvent(e);
}

} // namespace iso::gui
