// Moving a placed markup point by dragging it (docs/gui.md "Pick and
// measure", "Editing"): member functions of MeasureTools kept out of
// measure_tools.cpp. With no tool on, a left press within kGrabRadiusPx of a
// point's projection grabs it; in the 3D view the point then follows the
// visible surface under the pointer (the click's pick: Viewer::pick_at,
// core::pick_in_frame; over the background it stays), on a slice view the
// slice's plane (core::pixel_to_lps). The views and the Measurements panel
// follow every step; the release makes one undo step, "Move point".
#include <QStatusBar>
#include <QTimer>

#include <cmath>
#include <limits>

#include "app/gui/app_context.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/frame/annotations.hpp"

namespace iso::gui {

namespace {

// The point whose projection (`at`: where, or none when not shown) is
// nearest to `pixel`, within `radius`.
template <class Project>
std::optional<std::pair<std::size_t, std::size_t>> nearest_point(const std::vector<Markup>& markups, QPointF pixel,
                                                                 double radius, Project at) {
    std::optional<std::pair<std::size_t, std::size_t>> best;
    double best_d = radius;
    for (std::size_t i = 0; i < markups.size(); ++i)
        for (std::size_t k = 0; k < markups[i].points.size(); ++k) {
            const MarkupControlPoint& p = markups[i].points[k];
            if (p.status != PositionStatus::Defined || !p.visible) continue;
            const std::optional<QPointF> q = at(p.position);
            if (!q) continue;
            const double d = std::hypot(q->x() - pixel.x(), q->y() - pixel.y());
            if (d <= best_d) {
                best_d = d;
                best = std::pair{i, k};
            }
        }
    return best;
}

QString point_name(const Markup& m, std::size_t point) {
    const auto& label = m.points[point].label;
    return QString::fromStdString(m.name) + " point " +
           (label.empty() ? QString::number(point + 1) : QString::fromStdString(label));
}

} // namespace

bool MeasureTools::grab(const std::optional<Hit>& hit) {
    if (!hit) return false;
    ++grabs_;
    grab_ = Grab{hit->markup, hit->point, context_.workspace.markups_state()};
    context_.status("Moving " + point_name(context_.workspace.markups()[hit->markup], hit->point) +
                    ": release to place it (Edit > Undo puts it back)");
    return true;
}

void MeasureTools::move_grabbed(const glm::dvec3& lps) {
    if (!grab_) return;
    MarkupsState s = context_.workspace.markups_state();
    if (grab_->markup >= s.markups.size() || grab_->point >= s.markups[grab_->markup].points.size()) return;
    s.markups[grab_->markup].points[grab_->point].position = lps;
    context_.workspace.set_markups(std::move(s)); // the views and the panel's value follow
}

void MeasureTools::commit_grab() {
    if (!grab_) return;
    Grab g = std::move(*grab_);
    grab_.reset();
    // The markups may have changed under the drag (Edit > Undo from the keyboard): nothing to commit then.
    const auto& now = context_.workspace.markups();
    if (g.markup >= now.size() || g.point >= now[g.markup].points.size() || now.size() != g.before.markups.size() ||
        now[g.markup].points.size() != g.before.markups[g.markup].points.size())
        return;
    const bool moved = g.before.markups[g.markup].points[g.point].position != now[g.markup].points[g.point].position;
    if (!moved) {
        context_.workspace.set_markups(
            context_.workspace.markups_state()); // the panel's columns left out while dragging
        return;
    }
    const Markup& m = context_.workspace.markups()[g.markup];
    const std::string value = markup_measurement_text(m);
    const QString msg = "Moved " + point_name(m, g.point) + " to " + lps_text(m.points[g.point].position) +
                        (value.empty() ? QString() : ": " + QString::fromStdString(value));
    // One undo step from the state at the press to the state now (the drag's steps were shown unrecorded).
    core::WorkspaceEdit e;
    e.text = "Move point";
    e.parts = core::Parts(core::Part::Markups);
    e.before.markups = std::move(g.before);
    e.after.markups = context_.workspace.markups_state();
    context_.push(std::move(e));
    context_.status(msg);
}

// ---- the 3D view -------------------------------------------------------------------

bool MeasureTools::viewer_press(Viewer& v, QPointF pixel) {
    // The Structures tools' Scissors draws an outline with the press's drag.
    if (context_.tool() == AppContext::Tool::Scissors) {
        outlining_ = other_tool_press && other_tool_press(v, pixel);
        return outlining_;
    }
    if (tool_ != Tool::None || context_.busy()) return false;
    const double radius = kGrabRadiusPx * v.devicePixelRatioF();
    const auto hit = nearest_point(context_.workspace.markups(), pixel, radius,
                                   [&](const glm::dvec3& p) { return v.image_pixel(p); });
    return grab(hit ? std::optional<Hit>(Hit{hit->first, hit->second}) : std::nullopt);
}

void MeasureTools::viewer_grab_move(QPointF pixel) {
    if (outlining_) {
        if (other_tool_move) other_tool_move(pixel);
        return;
    }
    grab_at_ = pixel;
    // A pick is a frame: at most one per pass of the event loop, for the
    // latest position (the moves queued meanwhile only replace it).
    if (!grab_timer_->isActive()) grab_timer_->start(0);
}

void MeasureTools::viewer_grab_pick() {
    if (!grab_ || !grab_at_ || !viewer_ || context_.busy()) return;
    const QPointF at = *grab_at_;
    grab_at_.reset();
    // Answered later (the GUI thread does not wait for the pick's frame),
    // and only while the same grab goes on: the release places the point
    // where the pointer was let go.
    const std::uint64_t grab = grabs_;
    pick_and_show_later(*viewer_, at, true, [this, grab](std::optional<glm::dvec3> lps) {
        if (!grab_ || grab != grabs_) return;
        if (lps)
            move_grabbed(*lps);
        else
            context_.status("Background: the point stays where it was");
    });
}

void MeasureTools::viewer_grab_release(Viewer& v, QPointF pixel, bool dragged) {
    if (outlining_) {
        outlining_ = false;
        if (other_tool_release) other_tool_release(v, pixel, dragged);
        return;
    }
    grab_timer_->stop();
    grab_at_.reset();
    if (!grab_) return;
    if (!dragged) { // a click on the point: the view's click does what a click does
        grab_.reset();
        return;
    }
    // Where the pointer was let go, exactly (the throttled steps may lag behind);
    // a readout, not a click: the last click's field keeps what was clicked.
    if (const auto lps = pick_and_show(v, pixel, true)) move_grabbed(*lps);
    commit_grab();
}

// ---- slice views --------------------------------------------------------------------

bool MeasureTools::slice_press(SliceView& view, QPointF pixel) {
    if (tool_ != Tool::None || context_.busy() || !context_.workspace.scene().has_volume() || !view.has_image())
        return false;
    const core::SliceGrid& g = view.grid();
    // Only the points the view draws: within half a slice of its plane.
    const double half = 0.5 * core::slice_step_mm(context_.workspace.scene().volume(), g.normal);
    const auto hit = nearest_point(context_.workspace.markups(), pixel, kGrabRadiusPx, [&](const glm::dvec3& p) {
        const core::SlicePoint s = core::lps_to_pixel(g, p);
        return std::abs(s.distance_mm) <= half ? std::optional<QPointF>(QPointF(s.pixel.x, s.pixel.y)) : std::nullopt;
    });
    return grab(hit ? std::optional<Hit>(Hit{hit->first, hit->second}) : std::nullopt);
}

void MeasureTools::slice_grab_move(SliceView& view, QPointF pixel) {
    if (!grab_ || !view.has_image()) return;
    const glm::dvec3 lps = core::pixel_to_lps(view.grid(), {pixel.x(), pixel.y()});
    move_grabbed(lps);
    context_.status("Moving to " + lps_text(lps));
}

void MeasureTools::slice_grab_release(SliceView& view, QPointF pixel, bool dragged) {
    if (!grab_) return;
    if (!dragged) {
        grab_.reset();
        return;
    }
    slice_grab_move(view, pixel); // where the pointer was let go
    commit_grab();
}

} // namespace iso::gui
