#include "app/gui/tf_editor.hpp"

#include <QColorDialog>
#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>

#include <algorithm>
#include <cmath>

#include "io/color.hpp"

namespace iso::gui {

namespace {
constexpr double kPickRadius = 7; // pixels around a marker that grab it
constexpr double kMarker = 5;     // a marker's radius

QColor qcolor(const std::string& hex) { return QColor(QString::fromStdString(hex)); }

// The smallest of 0.05, 0.1, 0.2, 0.5 and 1 above the function's largest
// opacity with some room (the curve is not flattened at the floor).
double nice_top(const TransferFunction& tf) {
    double m = 0;
    for (const auto& p : tf.points()) m = std::max(m, p.opacity);
    for (double t : {0.05, 0.1, 0.2, 0.5})
        if (m * 1.25 <= t) return t;
    return 1.0;
}
} // namespace

TfEditor::TfEditor(QWidget* parent) : QWidget(parent) {
    setMinimumSize(240, 150);
    setFocusPolicy(Qt::ClickFocus);
    setMouseTracking(false);
    setToolTip("Transfer function: drag a point (value, opacity per mm); double-click empty space to add one, "
               "a point to choose its colour; right-click or Delete removes one");
}

void TfEditor::set_histogram(std::vector<double> counts, double lo, double hi) {
    counts_ = std::move(counts);
    hist_lo_ = lo;
    hist_hi_ = hi > lo ? hi : lo + 1;
    fit_axes();
    update();
}

void TfEditor::set_tf(const TransferFunction& tf) {
    tf_ = tf;
    if (selected_ && *selected_ >= tf_.points().size()) selected_.reset();
    if (!dragging_) fit_axes();
    update();
}

// The value axis spans the histogram and the points; the opacity axis
// rises to nice_top. Fixed while a point is dragged.
void TfEditor::fit_axes() {
    lo_ = hist_lo_;
    hi_ = hist_hi_;
    for (const auto& p : tf_.points()) {
        lo_ = std::min(lo_, p.value);
        hi_ = std::max(hi_, p.value);
    }
    if (!(hi_ > lo_)) hi_ = lo_ + 1;
    top_ = nice_top(tf_);
}

QRectF TfEditor::plot_rect() const {
    const QFontMetrics fm(font());
    const double left = fm.horizontalAdvance("0.00") + 8, bottom = 10 + fm.height() + 4;
    return QRectF(left, 6, std::max(10.0, width() - left - 8), std::max(10.0, height() - 6 - bottom));
}

QPointF TfEditor::to_widget(double value, double opacity) const {
    const QRectF r = plot_rect();
    return {r.left() + (value - lo_) / (hi_ - lo_) * r.width(), r.bottom() - opacity / top_ * r.height()};
}

std::pair<double, double> TfEditor::from_widget(QPointF p) const {
    const QRectF r = plot_rect();
    return {lo_ + (p.x() - r.left()) / r.width() * (hi_ - lo_), (r.bottom() - p.y()) / r.height() * top_};
}

std::optional<std::size_t> TfEditor::point_at(QPointF p) const {
    std::optional<std::size_t> best;
    double best_d = kPickRadius;
    const auto& pts = tf_.points();
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const QPointF d = to_widget(pts[i].value, pts[i].opacity) - p;
        const double dist = std::hypot(d.x(), d.y());
        if (dist <= best_d) {
            best_d = dist;
            best = i;
        }
    }
    return best;
}

// ---- painting ---------------------------------------------------------------------------

void TfEditor::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.setRenderHint(QPainter::Antialiasing);
    p.fillRect(rect(), palette().window());
    const QRectF r = plot_rect();
    p.fillRect(r, QColor(24, 26, 30));
    paint_histogram(p, r);
    paint_function(p, r);
    paint_axes(p, r);
}

// Log counts, as a grey area over the values the volume has.
void TfEditor::paint_histogram(QPainter& p, const QRectF& r) const {
    if (counts_.empty()) return;
    const double top = std::log1p(*std::max_element(counts_.begin(), counts_.end()));
    if (!(top > 0)) return;
    QPainterPath path;
    const double bin = (hist_hi_ - hist_lo_) / double(counts_.size());
    path.moveTo(to_widget(hist_lo_, 0));
    for (std::size_t i = 0; i < counts_.size(); ++i) {
        const double y = r.bottom() - std::log1p(counts_[i]) / top * r.height() * 0.95;
        path.lineTo(to_widget(hist_lo_ + bin * double(i), 0).x(), y);
        path.lineTo(to_widget(hist_lo_ + bin * double(i + 1), 0).x(), y);
    }
    path.lineTo(to_widget(hist_hi_, 0));
    path.closeSubpath();
    p.setPen(Qt::NoPen);
    p.setBrush(QColor(110, 115, 125));
    p.drawPath(path);
}

// The opacity polyline (flat beyond the first and last points), the
// markers in their colours, and the colour strip under the plot.
void TfEditor::paint_function(QPainter& p, const QRectF& r) const {
    const auto& pts = tf_.points();
    if (pts.empty()) return;
    p.save();
    p.setClipRect(r.adjusted(-kMarker - 1, -kMarker - 1, kMarker + 1, kMarker + 1));
    QPolygonF line;
    line << QPointF(r.left(), to_widget(lo_, pts.front().opacity).y());
    for (const auto& pt : pts) line << to_widget(pt.value, pt.opacity);
    line << QPointF(r.right(), to_widget(hi_, pts.back().opacity).y());
    p.setPen(QPen(QColor(235, 235, 235), 1.5));
    p.setBrush(Qt::NoBrush);
    p.drawPolyline(line);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const bool sel = selected_ && *selected_ == i;
        p.setPen(QPen(sel ? QColor(255, 210, 60) : QColor(20, 20, 20), sel ? 2.5 : 1.5));
        p.setBrush(qcolor(pts[i].color));
        p.drawEllipse(to_widget(pts[i].value, pts[i].opacity), kMarker + (sel ? 1 : 0), kMarker + (sel ? 1 : 0));
    }
    p.restore();
    const QRectF strip(r.left(), r.bottom() + 3, r.width(), 7);
    for (int x = 0; x < int(strip.width()); ++x) {
        const double v = lo_ + (x + 0.5) / strip.width() * (hi_ - lo_);
        const glm::dvec4 c = tf_.at(v);
        p.fillRect(QRectF(strip.left() + x, strip.top(), 1.0, strip.height()),
                   qcolor(hex_from_linear(glm::vec3(c.r, c.g, c.b))));
    }
}

void TfEditor::paint_axes(QPainter& p, const QRectF& r) const {
    p.setPen(palette().color(QPalette::WindowText));
    p.setBrush(Qt::NoBrush);
    p.drawRect(r);
    const QFontMetrics fm(font());
    const double y = r.bottom() + 12 + fm.ascent();
    const QString lo = QString::number(lo_, 'g', 5), hi = QString::number(hi_, 'g', 5);
    p.drawText(QPointF(r.left(), y), lo);
    p.drawText(QPointF(r.right() - fm.horizontalAdvance(hi), y), hi);
    const QString mid = "value";
    p.drawText(QPointF(r.center().x() - fm.horizontalAdvance(mid) / 2.0, y), mid);
    const QString top = QString::number(top_, 'f', 2);
    p.drawText(QPointF(r.left() - fm.horizontalAdvance(top) - 4, r.top() + fm.ascent()), top);
    p.drawText(QPointF(r.left() - fm.horizontalAdvance("0") - 4, r.bottom()), "0");
}

// ---- editing ----------------------------------------------------------------------------

void TfEditor::finish(const QString& text, TransferFunction before, std::vector<TfPoint> points) {
    tf_ = TransferFunction(std::move(points));
    fit_axes();
    update();
    if (on_edit) on_edit(text, before, tf_);
}

void TfEditor::mousePressEvent(QMouseEvent* e) {
    const auto hit = point_at(e->position());
    if (e->button() == Qt::RightButton) {
        if (hit) remove_point(*hit);
        return;
    }
    if (e->button() != Qt::LeftButton) return;
    selected_ = hit;
    dragging_ = hit;
    drag_before_ = tf_;
    moved_ = false;
    update();
}

void TfEditor::mouseMoveEvent(QMouseEvent* e) {
    if (!dragging_ || !(e->buttons() & Qt::LeftButton)) return;
    auto [value, opacity] = from_widget(e->position());
    std::vector<TfPoint> pts = tf_.points();
    const std::size_t i = *dragging_;
    // Between its neighbours (a step where they are equal), on the axes.
    const double below = i > 0 ? pts[i - 1].value : lo_;
    const double above = i + 1 < pts.size() ? pts[i + 1].value : hi_;
    pts[i].value = std::clamp(value, std::min(below, above), std::max(below, above));
    pts[i].opacity = std::clamp(opacity, 0.0, std::min(1.0, top_));
    tf_ = TransferFunction(std::move(pts));
    moved_ = true;
    update();
    if (on_live) on_live(tf_);
}

void TfEditor::mouseReleaseEvent(QMouseEvent* e) {
    if (e->button() != Qt::LeftButton || !dragging_) return;
    dragging_.reset();
    if (!moved_) return;
    moved_ = false;
    finish("Move transfer function point", drag_before_, tf_.points());
}

void TfEditor::mouseDoubleClickEvent(QMouseEvent* e) {
    if (e->button() != Qt::LeftButton) return;
    dragging_.reset();
    if (const auto hit = point_at(e->position()))
        choose_color(*hit);
    else if (plot_rect().contains(e->position()))
        add_point(e->position());
}

void TfEditor::keyPressEvent(QKeyEvent* e) {
    if ((e->key() == Qt::Key_Delete || e->key() == Qt::Key_Backspace) && selected_) {
        remove_point(*selected_);
        return;
    }
    QWidget::keyPressEvent(e);
}

// One point stays: a transfer function has at least one.
void TfEditor::remove_point(std::size_t i) {
    if (tf_.points().size() <= 1 || i >= tf_.points().size()) return;
    const TransferFunction before = tf_;
    std::vector<TfPoint> pts = tf_.points();
    pts.erase(pts.begin() + std::ptrdiff_t(i));
    selected_.reset();
    dragging_.reset();
    finish("Remove transfer function point", before, std::move(pts));
}

// At the pointer's value and opacity, in the function's colour there.
void TfEditor::add_point(QPointF at) {
    auto [value, opacity] = from_widget(at);
    TfPoint pt;
    pt.value = value;
    pt.opacity = std::clamp(opacity, 0.0, 1.0);
    const glm::dvec4 c = tf_.empty() ? glm::dvec4(1.0) : tf_.at(value);
    pt.color = hex_from_linear(glm::vec3(c.r, c.g, c.b));
    std::vector<TfPoint> pts = tf_.points();
    const auto where =
        std::upper_bound(pts.begin(), pts.end(), value, [](double v, const TfPoint& p) { return v < p.value; });
    selected_ = std::size_t(where - pts.begin());
    pts.insert(where, pt);
    finish("Add transfer function point", tf_, std::move(pts));
}

// A colour dialog (window-modal, not exec()); the choice is one edit.
void TfEditor::choose_color(std::size_t i) {
    selected_ = i;
    update();
    if (!color_dialog_) {
        color_dialog_ = new QColorDialog(this);
        color_dialog_->setObjectName("tf_color");
        color_dialog_->setWindowTitle("Transfer function point colour");
    }
    color_dialog_->disconnect(this);
    color_dialog_->setCurrentColor(qcolor(tf_.points()[i].color));
    connect(color_dialog_, &QColorDialog::colorSelected, this, [this, i](const QColor& c) {
        if (!c.isValid() || i >= tf_.points().size()) return;
        std::vector<TfPoint> pts = tf_.points();
        pts[i].color = c.name(QColor::HexRgb).toStdString();
        if (pts == tf_.points()) return;
        finish("Colour of a transfer function point", tf_, std::move(pts));
    });
    color_dialog_->open();
}

} // namespace iso::gui
