// Pick and measure in the main window (docs/gui.md "Pick and
// measure"): the 3D view's click and hover readout (LPS, value, surface) in
// the status bar, a 3D click moving the slice views' crosshair, and the Ruler
// and Angle tools, which take their points from the 3D view's pick (the
// visible layer) or from a slice view's click, and store the finished
// measurement as a 3D Slicer markup (Line, Angle) through
// MainWindow::set_markups. Presentation only: picking is core::pick_in_frame
// (through Viewer::pick_at), slice positions core::pixel_to_lps /
// core::lps_to_pixel, values the core's.
#pragma once

#include <optional>
#include <vector>

#include <QElapsedTimer>
#include <QObject>
#include <QPointF>
#include <QPointer>
#include <QString>

#include <glm/vec3.hpp>

#include "io/markups.hpp"

class QAction;
class QPainter;
class QShortcut;
class QTimer;

namespace iso::core {
struct PickResult;
}

namespace iso::gui {

class MainWindow;
class SliceView;
class Viewer;

class MeasureTools : public QObject {
public:
    enum class Tool { None, Ruler, Angle };

    // Adds the Measure tool bar (Ruler, Angle: checkable, at most one on) to `window`.
    explicit MeasureTools(MainWindow& window);

    Tool tool() const { return tool_; }
    // Switching drops the points placed so far.
    void set_tool(Tool t);
    QAction* ruler_action() const { return ruler_; }
    QAction* angle_action() const { return angle_; }
    // The points of the measurement being placed (LPS mm).
    const std::vector<glm::dvec3>& pending() const { return pending_; }

    // Takes the 3D view's on_click and on_hover (call for each new viewer).
    void attach(Viewer& viewer);
    // A left click on a slice view: true when the active tool took it as a
    // point (then the window does nothing else with it).
    bool slice_click(SliceView& view, QPointF pixel);
    // Draws the markups and the points being placed over a slice view: each
    // point within half a slice of its plane, segments whose ends both are,
    // and the value.
    void paint_slice(SliceView& view, QPainter& p) const;
    // A new scene: points being placed and a pending hover pick are dropped.
    void reset();
    // Shows the markups and the points being placed: the 3D view's overlay
    // (the points as a point list) and the slice views (the window calls it
    // when its markups change).
    void redraw();

    // The status bar's text for a pick of the 3D view:
    // "LPS (x, y, z) mm, READOUT, surface NAME" (READOUT: core::value_readout,
    // "v HU" for CT, else "value v"; left out where there is none), or "background".
    QString readout(const core::PickResult& r) const;
    // Hover picks made so far (throttled: one per interval, the latest position wins).
    int hover_picks() const { return hover_picks_; }
    // The hover interval: at least 80 ms, and at least twice the last pick's time.
    int hover_interval_ms() const;

private:
    void viewer_click(Viewer& v, QPointF pixel);
    void viewer_hover(Viewer& v, QPointF pixel);
    void hover_pick();
    // Picks the visible layer at the pixel and shows the readout; none: background or failure.
    std::optional<glm::dvec3> pick_and_show(Viewer& v, QPointF pixel, bool hover);
    void add_point(const glm::dvec3& lps);
    QString next_name(MarkupType type) const;

    MainWindow& window_;
    QAction* ruler_ = nullptr;
    QAction* angle_ = nullptr;
    Tool tool_ = Tool::None;
    std::vector<glm::dvec3> pending_;
    QPointer<Viewer> viewer_;
    QTimer* hover_timer_ = nullptr;
    QShortcut* escape_ = nullptr; // on only while points are being placed (it would take Escape from editors)
    std::optional<QPointF> hover_at_;
    QElapsedTimer since_hover_;
    double last_pick_ms_ = 0;
    int hover_picks_ = 0;
};

} // namespace iso::gui
