// Pick and measure in the main window (docs/gui.md "Pick and
// measure"): the 3D view's click and hover readout (LPS, value, surface) in
// the status bar, a 3D click moving the slice views' crosshair; the Ruler,
// Angle and Point tools, which take their points from the 3D view's pick
// (the visible layer) or from a slice view's click, and store the
// measurement as a 3D Slicer markup (Line, Angle, a point list's point)
// in the workspace (one undo step each); and moving a
// placed point by dragging it (point_editing.cpp). Presentation only:
// picking is core::pick_in_frame (through Viewer::pick_at), slice positions
// core::pixel_to_lps / core::lps_to_pixel, values the core's.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <QElapsedTimer>
#include <QObject>
#include <QPointF>
#include <QPointer>
#include <QString>

#include <glm/vec3.hpp>

#include "app/gui/app_context.hpp"
#include "io/markups.hpp"

class QAction;
class QLabel;
class QPainter;
class QShortcut;
class QTimer;

namespace iso::core {
struct PickResult;
}

namespace iso::gui {

class SliceView;
class Viewer;

// A point as the readouts write it: "LPS (x, y, z) mm", 2 decimals.
QString lps_text(const glm::dvec3& p);

class MeasureTools : public QObject {
public:
    enum class Tool { None, Ruler, Angle, Point };

    // Adds the Measure tool bar (Ruler, Angle, Point: checkable, at most one
    // on, and off when another tool is taken) to the context's window.
    explicit MeasureTools(AppContext& context);
    ~MeasureTools() override;

    Tool tool() const { return tool_; }
    // Switching drops the points placed so far.
    void set_tool(Tool t);
    QAction* ruler_action() const { return ruler_; }
    QAction* angle_action() const { return angle_; }
    QAction* point_action() const { return point_; }
    // The points of the measurement being placed (LPS mm).
    const std::vector<glm::dvec3>& pending() const { return pending_; }

    // Takes the 3D view's click, hover and point dragging (call for each new viewer).
    void attach(Viewer& viewer);
    // Takes a slice view's clicks (a point with a tool on; else the
    // crosshair and the readout), point dragging and overlay.
    void attach(SliceView& view);
    // A 3D view click while a Structures tool is on (the window wires it to StructureTools).
    std::function<void(Viewer&, QPointF)> other_tool_click;
    // A press in the 3D view while the Scissors tool is on (true: taken),
    // the drag's moves and its release: the outline being drawn.
    std::function<bool(Viewer&, QPointF)> other_tool_press;
    std::function<void(QPointF)> other_tool_move;
    std::function<void(Viewer&, QPointF, bool dragged)> other_tool_release;
    // A slice view click (LPS mm) while the Grow tool is on: true when taken.
    std::function<bool(const glm::dvec3&)> other_slice_click;
    // A left click on a slice view: true when the active tool took it as a
    // point (then the window does nothing else with it).
    bool slice_click(SliceView& view, QPointF pixel);
    // A markup point is being dragged (a press on it with no tool on).
    bool editing() const { return grab_.has_value(); }
    // The markups as the views draw them: the selected one (the
    // Measurements panel's row) in the highlight colour.
    std::vector<Markup> drawn_markups() const;
    // The highlight colour of the selected markup (sRGB in [0, 1]).
    static glm::dvec3 highlight_color() { return {1.0, 0.3, 1.0}; }
    // How near (pixels) a press must be to a point's projection to grab it.
    static constexpr double kGrabRadiusPx = 8;
    // Draws the markups and the points being placed over a slice view: each
    // point within half a slice of its plane, segments whose ends both are,
    // and the value.
    void paint_slice(SliceView& view, QPainter& p) const;
    // New data: points being placed and a pending hover pick are dropped.
    void reset();
    // Shows the markups and the points being placed: the 3D view's overlay
    // (the points as a point list) and the slice views (the workspace's
    // changes of the markups call it).
    void redraw();

    // The status bar's text for a pick of the 3D view:
    // "LPS (x, y, z) mm, READOUT, surface NAME" (READOUT: core::value_readout,
    // "v HU" for CT, else "value v"; left out where there is none), or "background".
    QString readout(const core::PickResult& r) const;
    // The last click's readout in the 3D view, "Click: " + readout(), kept
    // in a permanent field of the status bar (hover readouts are the status
    // bar's passing messages and leave it alone); empty before a click.
    QString click_readout() const;
    // Hover picks answered so far (throttled: one per interval, the latest position wins).
    int hover_picks() const { return hover_picks_; }
    // The hover interval: at least 80 ms, and at least twice the last pick's time.
    int hover_interval_ms() const;

private:
    void viewer_click(Viewer& v, QPointF pixel);
    void viewer_hover(Viewer& v, QPointF pixel);
    void hover_pick();
    // Picks the visible layer at the pixel and shows the readout; none: background or failure.
    std::optional<glm::dvec3> pick_and_show(Viewer& v, QPointF pixel, bool hover);
    void pick_and_show_later(Viewer& v, QPointF pixel, bool hover, std::function<void(std::optional<glm::dvec3>)> then);
    std::optional<glm::dvec3> show_pick(const core::PickResult* r, const std::string& error, bool hover);
    // `on`: the slice view it was placed on (its slice stays), none: the 3D view.
    void add_point(const glm::dvec3& lps, const SliceView* on = nullptr);
    void add_list_point(const glm::dvec3& lps);
    QString next_name(MarkupType type) const;

    // Dragging a placed point (point_editing.cpp): a press within
    // kGrabRadiusPx of a point's projection grabs it; the moves place it
    // (3D: on the pick's visible layer, throttled to one pick per event
    // loop pass, the latest position winning; a slice: on the plane); the
    // release commits one undo step.
    struct Grab {
        std::size_t markup = 0, point = 0;
        core::MarkupsState before; // the state at the press: what Undo restores
    };
    struct Hit {
        std::size_t markup = 0, point = 0;
    };
    bool grab(const std::optional<Hit>& hit);
    bool viewer_press(Viewer& v, QPointF pixel);
    void viewer_grab_move(QPointF pixel);
    void viewer_grab_pick();
    void viewer_grab_release(Viewer& v, QPointF pixel, bool dragged);
    bool slice_press(SliceView& view, QPointF pixel);
    void slice_grab_move(SliceView& view, QPointF pixel);
    void slice_grab_release(SliceView& view, QPointF pixel, bool dragged);
    void move_grabbed(const glm::dvec3& lps);
    void commit_grab();

    AppContext& context_;
    int observer_ = 0;
    QAction* ruler_ = nullptr;
    QAction* angle_ = nullptr;
    QAction* point_ = nullptr;
    Tool tool_ = Tool::None;
    std::vector<glm::dvec3> pending_;
    QPointer<Viewer> viewer_;
    QTimer* hover_timer_ = nullptr;
    QLabel* click_field_ = nullptr; // the status bar's permanent field: the last click's readout
    QShortcut* escape_ = nullptr;   // on only while points are being placed (it would take Escape from editors)
    std::optional<QPointF> hover_at_;
    QElapsedTimer since_hover_;
    double last_pick_ms_ = 0;
    int hover_picks_ = 0;
    std::uint64_t picks_asked_ = 0, last_click_asked_ = 0;
    std::uint64_t grabs_ = 0; // grabs so far: a drag's pick answers only its own grab
    std::optional<Grab> grab_;
    bool outlining_ = false;         // the press went to the Scissors' outline
    std::optional<QPointF> grab_at_; // the 3D view's latest drag position, not picked yet
    QTimer* grab_timer_ = nullptr;
};

} // namespace iso::gui
