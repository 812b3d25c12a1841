// The Volume panel's transfer-function editor (docs/gui.md "Volume panel"):
// the volume's value histogram (log counts) with the transfer function's
// opacity polyline over it, each point a marker in its colour, and the
// function's colours as a strip below. Drag a point to move its value and
// opacity (it stays between its neighbours: the points keep their order),
// double-click empty space to add a point, right-click a point (or Delete
// on the selected one) to remove it, double-click a point to choose its
// colour. Presentation only: the transfer function is renderer/volume's.
#pragma once

#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include <QString>
#include <QWidget>

#include "renderer/volume/transfer_function.hpp"

class QColorDialog;

namespace iso::gui {

class TfEditor : public QWidget {
public:
    explicit TfEditor(QWidget* parent = nullptr);

    // The histogram drawn behind (counts per equal bin over [lo, hi]).
    void set_histogram(std::vector<double> counts, double lo, double hi);
    // Shows `tf` (no callback); the axes take in its points.
    void set_tf(const TransferFunction& tf);
    const TransferFunction& tf() const { return tf_; }

    // The axes: values [value_lo, value_hi] left to right, opacity per mm
    // [0, opacity_top] bottom to top, over plot_rect() (widget pixels).
    QRectF plot_rect() const;
    double value_lo() const { return lo_; }
    double value_hi() const { return hi_; }
    double opacity_top() const { return top_; }
    QPointF to_widget(double value, double opacity) const;
    std::pair<double, double> from_widget(QPointF p) const; // value, opacity (not clamped)
    // The point whose marker is within a few pixels of `p` (the nearest).
    std::optional<std::size_t> point_at(QPointF p) const;
    std::optional<std::size_t> selected() const { return selected_; }

    // Each step of a drag (the function as it is now, no undo step).
    std::function<void(const TransferFunction&)> on_live;
    // A finished edit (a drag's release, an added or removed point, a
    // colour): one undo step from `before` to `after`.
    std::function<void(const QString& text, const TransferFunction& before, const TransferFunction& after)> on_edit;

protected:
    void paintEvent(QPaintEvent*) override;
    void mousePressEvent(QMouseEvent* e) override;
    void mouseMoveEvent(QMouseEvent* e) override;
    void mouseReleaseEvent(QMouseEvent* e) override;
    void mouseDoubleClickEvent(QMouseEvent* e) override;
    void keyPressEvent(QKeyEvent* e) override;

private:
    void fit_axes();
    void paint_histogram(class QPainter& p, const QRectF& r) const;
    void paint_function(class QPainter& p, const QRectF& r) const;
    void paint_axes(class QPainter& p, const QRectF& r) const;
    void remove_point(std::size_t i);
    void add_point(QPointF at);
    void choose_color(std::size_t i);
    void finish(const QString& text, TransferFunction before, std::vector<TfPoint> points);

    TransferFunction tf_;
    std::vector<double> counts_;
    double hist_lo_ = 0, hist_hi_ = 1;
    double lo_ = 0, hi_ = 1, top_ = 1;
    std::optional<std::size_t> selected_;
    std::optional<std::size_t> dragging_;
    TransferFunction drag_before_;
    bool moved_ = false;
    QColorDialog* color_dialog_ = nullptr;
};

} // namespace iso::gui
