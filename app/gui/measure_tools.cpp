#include "app/gui/measure_tools.hpp"

#include <QAction>
#include <QActionGroup>
#include <QFontMetricsF>
#include <QKeySequence>
#include <QLabel>
#include <QMainWindow>
#include <QPainter>
#include <QShortcut>
#include <QStatusBar>
#include <QTimer>
#include <QToolBar>
#include <QUndoStack>

#include <algorithm>
#include <cmath>
#include <functional>

#include "app/gui/app_context.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/frame/annotations.hpp"

namespace iso::gui {

QString lps_text(const glm::dvec3& p) {
    return QString("LPS (%1, %2, %3) mm").arg(p.x, 0, 'f', 2).arg(p.y, 0, 'f', 2).arg(p.z, 0, 'f', 2);
}

namespace {

constexpr int kHoverMinMs = 80;

std::size_t points_needed(MeasureTools::Tool t) {
    return t == MeasureTools::Tool::Point ? 1 : t == MeasureTools::Tool::Ruler ? 2 : 3;
}

QString tool_name(MeasureTools::Tool t) {
    return t == MeasureTools::Tool::Point ? "Point" : t == MeasureTools::Tool::Ruler ? "Ruler" : "Angle";
}

// markup_color gives sRGB components in [0, 1], as Slicer stores them.
QColor srgb(const glm::vec3& c) { return QColor::fromRgbF(c.r, c.g, c.b); }

void draw_cross(QPainter& p, QPointF at, const QColor& c) {
    constexpr double r = 6;
    for (const auto& [pen, width] : {std::pair{QColor(0, 0, 0, 200), 3.5}, std::pair{c, 1.5}}) {
        p.setPen(QPen(pen, width));
        p.drawLine(at - QPointF(r, 0), at + QPointF(r, 0));
        p.drawLine(at - QPointF(0, r), at + QPointF(0, r));
    }
}

void draw_segment(QPainter& p, QPointF a, QPointF b, const QColor& c) {
    p.setPen(QPen(QColor(0, 0, 0, 200), 4.0));
    p.drawLine(a, b);
    p.setPen(QPen(c, 2.0));
    p.drawLine(a, b);
}

// A label at `at` (its baseline's left end), kept inside the view: one that
// would run past the right edge goes to the left of its point (`anchor`)
// instead, and one past the top or bottom edge moves in (labels near the
// edge used to be cut off).
void draw_text(QPainter& p, QPointF at, const QString& text, const QColor& c, QPointF anchor) {
    const QRectF view = p.viewport();
    const QFontMetricsF fm(p.font());
    const double w = fm.horizontalAdvance(text);
    if (at.x() + w > view.right() - 2) at.setX(std::max(view.left() + 2, 2 * anchor.x() - at.x() - w));
    at.setX(std::max(at.x(), view.left() + 2));
    at.setY(std::clamp(at.y(), view.top() + fm.ascent() + 2, view.bottom() - fm.descent() - 2));
    p.setPen(QColor(0, 0, 0, 220));
    p.drawText(at + QPointF(1, 1), text);
    p.setPen(c);
    p.drawText(at, text);
}

} // namespace

MeasureTools::MeasureTools(AppContext& context) : QObject(&context.window), context_(context) {
    QMainWindow& window = context.window;
    auto* bar = window.addToolBar("Measure");
    bar->setObjectName("measure");
    auto* group = new QActionGroup(this);
    group->setExclusionPolicy(QActionGroup::ExclusionPolicy::ExclusiveOptional);
    ruler_ = bar->addAction("Ruler");
    ruler_->setObjectName("ruler");
    ruler_->setToolTip("Measure a distance: click two points in the 3D view (on the visible surface) or on a slice");
    angle_ = bar->addAction("Angle");
    angle_->setObjectName("angle");
    angle_->setToolTip("Measure an angle: click three points (arm, vertex, arm) in the 3D view or on a slice");
    point_ = bar->addAction("Point");
    point_->setObjectName("point");
    point_->setToolTip("Place points (a point list, F-1, F-2, ...): each click in the 3D view or on a slice adds one");
    for (auto* a : {ruler_, angle_, point_}) {
        a->setCheckable(true);
        group->addAction(a);
    }
    connect(group, &QActionGroup::triggered, this, [this](QAction*) {
        set_tool(ruler_->isChecked()   ? Tool::Ruler
                 : angle_->isChecked() ? Tool::Angle
                 : point_->isChecked() ? Tool::Point
                                       : Tool::None);
    });
    // Escape drops the points placed so far (the tool stays on).
    escape_ = new QShortcut(QKeySequence(Qt::Key_Escape), &window);
    escape_->setEnabled(false);
    connect(escape_, &QShortcut::activated, this, [this] {
        if (pending_.empty()) return;
        pending_.clear();
        redraw();
        context_.status(tool_name(tool_) + ": points dropped");
    });
    click_field_ = new QLabel(&window);
    click_field_->setTextInteractionFlags(Qt::TextSelectableByMouse); // copy the coordinates
    click_field_->setToolTip("The last click in the 3D view: what is there (hovering shows its readout to the left)");
    window.statusBar()->addPermanentWidget(click_field_);
    hover_timer_ = new QTimer(this);
    hover_timer_->setSingleShot(true);
    connect(hover_timer_, &QTimer::timeout, this, [this] { hover_pick(); });
    grab_timer_ = new QTimer(this);
    grab_timer_->setSingleShot(true);
    connect(grab_timer_, &QTimer::timeout, this, [this] { viewer_grab_pick(); });
    // An undo or redo while a point is held (the keyboard) ends the drag: the state it started from is gone.
    connect(&context.undo, &QUndoStack::indexChanged, this, [this] { grab_.reset(); });
    // One tool at a time across the window: another one taken turns these off.
    context.tool_changed.push_back([this](AppContext::Tool t) {
        if (t != AppContext::Tool::Ruler && t != AppContext::Tool::Angle && t != AppContext::Tool::Point &&
            tool_ != Tool::None)
            set_tool(Tool::None);
    });
    context.editing_markup = [this] { return editing(); };
    // The views draw the markups as the workspace has them.
    observer_ = context.workspace.observe([this](core::Parts p) {
        if (core::has(p, core::Part::Data)) reset();
        if (p & (core::Part::Data | core::Part::Markups | core::Part::Selection)) redraw();
    });
}

MeasureTools::~MeasureTools() { context_.workspace.unobserve(observer_); }

void MeasureTools::set_tool(Tool t) {
    tool_ = t;
    // One tool at a time across the window.
    if (t != Tool::None)
        context_.set_tool(t == Tool::Ruler   ? AppContext::Tool::Ruler
                          : t == Tool::Angle ? AppContext::Tool::Angle
                                             : AppContext::Tool::Point);
    else if (context_.tool() == AppContext::Tool::Ruler || context_.tool() == AppContext::Tool::Angle ||
             context_.tool() == AppContext::Tool::Point)
        context_.set_tool(AppContext::Tool::None);
    ruler_->setChecked(t == Tool::Ruler);
    angle_->setChecked(t == Tool::Angle);
    point_->setChecked(t == Tool::Point);
    pending_.clear();
    redraw();
    if (t == Tool::None)
        context_.status(
            "Measuring off: a click shows what is there and moves the crosshair; drag a placed point to move it");
    else if (t == Tool::Point)
        context_.status("Point: each click in the 3D view (on the visible surface) or on a slice "
                        "adds a point to the point list");
    else
        context_.status(QString("%1: click %2 points in the 3D view (on the visible surface) or on a slice%3")
                            .arg(tool_name(t))
                            .arg(points_needed(t))
                            .arg(t == Tool::Angle ? " (arm, vertex, arm)" : ""));
}

void MeasureTools::attach(Viewer& viewer) {
    viewer_ = &viewer;
    viewer.on_click = [this](Viewer& v, QPointF p) { viewer_click(v, p); };
    viewer.on_hover = [this](Viewer& v, QPointF p) { viewer_hover(v, p); };
    viewer.on_press = [this](Viewer& v, QPointF p) { return viewer_press(v, p); };
    viewer.on_grab_move = [this](Viewer&, QPointF p) { viewer_grab_move(p); };
    viewer.on_grab_release = [this](Viewer& v, QPointF p, bool dragged) { viewer_grab_release(v, p, dragged); };
}

void MeasureTools::attach(SliceView& view) {
    // A click places a point with a tool on; without, it moves the crosshair there and says what is there.
    view.on_click = [this](SliceView& v, QPointF p) {
        if (!context_.workspace.scene().has_volume() || slice_click(v, p)) return;
        if (context_.tool() == AppContext::Tool::Grow && other_slice_click && v.has_image() &&
            other_slice_click(core::pixel_to_lps(v.grid(), {p.x(), p.y()})))
            return; // the Structures tools' Grow seeds there
        context_.status(slice_readout(context_.workspace.scene().volume(), v.grid(), p));
        context_.workspace.set_crosshair(core::pixel_to_lps(v.grid(), {p.x(), p.y()}));
    };
    view.add_overlay([this](SliceView& v, QPainter& p) { paint_slice(v, p); });
    view.add_grabber({[this](SliceView& v, QPointF p) { return slice_press(v, p); },
                      [this](SliceView& v, QPointF p) { slice_grab_move(v, p); },
                      [this](SliceView& v, QPointF p, bool dragged) { slice_grab_release(v, p, dragged); }});
}

void MeasureTools::reset() {
    click_field_->clear(); // a click on the scene that went
    hover_timer_->stop();
    hover_at_.reset();
    grab_timer_->stop();
    grab_at_.reset();
    grab_.reset();
    viewer_ = nullptr;
    pending_.clear();
    escape_->setEnabled(false);
}

QString MeasureTools::click_readout() const { return click_field_->text(); }

int MeasureTools::hover_interval_ms() const { return std::max(kHoverMinMs, int(std::ceil(2.0 * last_pick_ms_))); }

// ---- the 3D view -------------------------------------------------------------------

QString MeasureTools::readout(const core::PickResult& r) const {
    if (!r.visible) return "background";
    const core::PickLayer& l = r.layers[*r.visible];
    QString s = lps_text(l.lps);
    if (l.value) s += ", " + QString::fromStdString(core::value_readout(*l.value, l.unit));
    // The ray-cast volume's layer (where its accumulated opacity reaches 0.5) is no surface.
    if (l.volume) return s + ", in the volume";
    return s + ", surface " + QString::fromStdString(l.name);
}

// The readout of a pick (or why there is none); the visible layer's point.
std::optional<glm::dvec3> MeasureTools::show_pick(const core::PickResult* r, const std::string& error, bool hover) {
    if (!r) {
        // A pointer at the very edge, a view that cannot draw: say so, nothing else.
        if (!hover && !error.empty()) context_.status(QString("3D pick: ") + QString::fromStdString(error));
        return std::nullopt;
    }
    last_pick_ms_ = r->frame_ms;
    context_.status(readout(*r));
    if (!hover) click_field_->setText("Click: " + readout(*r));
    if (!r->visible) return std::nullopt;
    return r->layers[*r->visible].lps;
}

std::optional<glm::dvec3> MeasureTools::pick_and_show(Viewer& v, QPointF pixel, bool hover) {
    try {
        const core::PickResult r = v.pick_at(pixel);
        return show_pick(&r, {}, hover);
    } catch (const std::exception& e) {
        return show_pick(nullptr, e.what(), hover);
    }
}

// The same, answered later (Viewer::pick_later: the GUI thread does not
// wait for the pick's frame); `then` gets the point, or none. A hover's
// answer that arrives after a later click's question is dropped: the
// click's readout is the newer one.
void MeasureTools::pick_and_show_later(Viewer& v, QPointF pixel, bool hover,
                                       std::function<void(std::optional<glm::dvec3>)> then) {
    const std::uint64_t asked = ++picks_asked_;
    if (!hover) last_click_asked_ = asked;
    QPointer<MeasureTools> self(this);
    v.pick_later(
        pixel,
        [self, asked, hover, then = std::move(then)](const core::PickResult* r, const std::string& error) {
            if (!self || (hover && asked < self->last_click_asked_)) return;
            const auto lps = self->show_pick(r, error, hover);
            if (then && (r || !error.empty())) then(lps); // a replaced hover pick has neither
        },
        hover);
}

void MeasureTools::viewer_click(Viewer& v, QPointF pixel) {
    if (context_.busy()) return; // a worker is changing the scene
    hover_timer_->stop();        // the click's readout is the newer one
    hover_at_.reset();
    if (context_.tool() == AppContext::Tool::Isolate || context_.tool() == AppContext::Tool::Distance ||
        context_.tool() == AppContext::Tool::Grow) {
        if (other_tool_click) other_tool_click(v, pixel); // the Structures tools
        return;
    }
    // The answer is acted on with the tool that was on at the click, if it still is.
    const Tool tool = tool_;
    pick_and_show_later(v, pixel, false, [this, tool](std::optional<glm::dvec3> lps) {
        if (tool != tool_ || context_.busy()) return;
        if (tool_ == Tool::None) {
            if (lps) context_.workspace.set_crosshair(*lps);
            return;
        }
        if (!lps) {
            context_.status(context_.status_text() + ": " + tool_name(tool_) + " needs a point on a visible surface");
            return;
        }
        add_point(*lps);
    });
}

void MeasureTools::viewer_hover(Viewer&, QPointF pixel) {
    hover_at_ = pixel;
    if (hover_timer_->isActive()) return; // the latest position wins when it fires
    const qint64 since = since_hover_.isValid() ? since_hover_.elapsed() : hover_interval_ms();
    hover_timer_->start(int(std::max<qint64>(0, hover_interval_ms() - since)));
}

void MeasureTools::hover_pick() {
    if (!hover_at_ || !viewer_ || context_.busy() || viewer_ != context_.viewer() || !viewer_->isVisible()) return;
    const QPointF at = *hover_at_;
    hover_at_.reset();
    // The interval counts from the pick's answer: the view keeps the time between.
    since_hover_.restart();
    pick_and_show_later(*viewer_, at, true, [this](std::optional<glm::dvec3>) {
        ++hover_picks_;
        since_hover_.restart();
    });
}

// ---- slice views --------------------------------------------------------------------

bool MeasureTools::slice_click(SliceView& view, QPointF pixel) {
    if (tool_ == Tool::None || !context_.workspace.scene().has_volume() || !view.has_image()) return false;
    add_point(core::pixel_to_lps(view.grid(), {pixel.x(), pixel.y()}), &view);
    return true;
}

namespace {

// One markup over a slice view: each point within half a slice of the
// plane (`project` says where and whether), segments whose ends both are,
// the value where the whole measurement is, and the name by its first point.
void paint_markup(QPainter& p, const Markup& m, const std::function<std::pair<QPointF, bool>(glm::dvec3)>& project) {
    std::vector<std::pair<QPointF, bool>> pts; // only Defined points have a position
    bool all_defined = true;
    for (const auto& cp : m.points) {
        if (cp.status != PositionStatus::Defined) {
            all_defined = false;
            continue;
        }
        pts.push_back(project(cp.position));
    }
    const QColor c = srgb(markup_color(m));
    const bool joined = m.type != MarkupType::Fiducial;
    if (joined && all_defined) {
        for (std::size_t i = 0; i + 1 < pts.size(); ++i)
            if (pts[i].second && pts[i + 1].second) draw_segment(p, pts[i].first, pts[i + 1].first, c);
        if (m.type == MarkupType::ClosedCurve && pts.size() > 2 && pts.back().second && pts.front().second)
            draw_segment(p, pts.back().first, pts.front().first, c);
    }
    std::size_t k = 0;
    bool all_near = !pts.empty();
    for (std::size_t i = 0; i < m.points.size(); ++i) {
        if (m.points[i].status != PositionStatus::Defined) continue;
        const auto& [at, near] = pts[k++];
        all_near &= near;
        if (!near || !m.points[i].visible) continue;
        const QColor pc = srgb(markup_color(m, int(i)));
        draw_cross(p, at, pc);
        // A point list's point: its label, else the list's name (as exports label it: markup_label_text).
        if (const std::string label = m.type == MarkupType::Fiducial ? markup_label_text(m, int(i)) : std::string();
            !label.empty())
            draw_text(p, at + QPointF(9, 4), QString::fromStdString(label), pc, at);
    }
    // The name below-right of the first point (a point list's points carry their own labels).
    if (m.type != MarkupType::Fiducial && !m.name.empty() && !pts.empty() && pts[0].second)
        draw_text(p, pts[0].first + QPointF(9, 16), QString::fromStdString(m.name), c, pts[0].first);
    // The value where the whole measurement lies on this slice.
    const std::string value = markup_measurement_text(m);
    if (all_near && all_defined && !value.empty()) {
        const QPointF at = m.type == MarkupType::Line ? (pts[0].first + pts[1].first) / 2.0 : pts[1].first;
        draw_text(p, at + QPointF(8, -8), QString::fromStdString(value), c, at);
    }
}

} // namespace

void MeasureTools::paint_slice(SliceView& view, QPainter& p) const {
    if (!context_.workspace.scene().has_volume() || !view.has_image()) return;
    const core::SliceGrid& g = view.grid();
    // Within half a slice of the plane: on the slice the view shows.
    const double half = 0.5 * core::slice_step_mm(context_.workspace.scene().volume(), g.normal);
    const auto project = [&](const glm::dvec3& lps) {
        const core::SlicePoint s = core::lps_to_pixel(g, lps);
        return std::pair{QPointF(s.pixel.x, s.pixel.y), std::abs(s.distance_mm) <= half};
    };
    p.setRenderHint(QPainter::Antialiasing);
    for (const Markup& m : drawn_markups()) paint_markup(p, m, project);
    // The measurement being placed.
    const QColor placing(255, 230, 80);
    std::vector<std::pair<QPointF, bool>> pts;
    for (const auto& q : pending_) pts.push_back(project(q));
    for (std::size_t i = 0; i + 1 < pts.size(); ++i)
        if (pts[i].second && pts[i + 1].second) draw_segment(p, pts[i].first, pts[i + 1].first, placing);
    for (const auto& [at, near] : pts)
        if (near) draw_cross(p, at, placing);
}

// ---- placing points ---------------------------------------------------------------------

QString MeasureTools::next_name(MarkupType type) const {
    const auto& all = context_.workspace.markups();
    const auto taken = [&](const QString& name) {
        return std::any_of(all.begin(), all.end(),
                           [&](const Markup& m) { return QString::fromStdString(m.name) == name; });
    };
    // Slicer's names: point lists F, F_1, F_2, ...
    if (type == MarkupType::Fiducial) {
        QString name = "F";
        for (int n = 1; taken(name); ++n) name = QString("F_%1").arg(n);
        return name;
    }
    const QString base = type == MarkupType::Line ? "Line" : "Angle";
    int n = 1 + int(std::count_if(all.begin(), all.end(), [&](const Markup& m) { return m.type == type; }));
    while (taken(QString("%1 %2").arg(base).arg(n))) ++n;
    return QString("%1 %2").arg(base).arg(n);
}

void MeasureTools::add_point(const glm::dvec3& lps, const SliceView* on) {
    // The slice views show where the point lies (the view it was placed on
    // keeps its slice, so the next point lands there too).
    context_.workspace.set_crosshair(lps, on ? std::optional(on->orientation()) : std::nullopt);
    if (tool_ == Tool::Point) {
        add_list_point(lps);
        return;
    }
    pending_.push_back(lps);
    const std::size_t need = points_needed(tool_);
    if (pending_.size() < need) {
        redraw();
        context_.status(QString("%1: point %2 of %3 at %4")
                            .arg(tool_name(tool_))
                            .arg(pending_.size())
                            .arg(need)
                            .arg(lps_text(lps)));
        return;
    }
    Markup m;
    m.type = tool_ == Tool::Ruler ? MarkupType::Line : MarkupType::Angle;
    m.name = next_name(m.type).toStdString();
    for (std::size_t i = 0; i < pending_.size(); ++i) {
        MarkupControlPoint cp;
        cp.id = std::to_string(i + 1);
        cp.position = pending_[i];
        m.points.push_back(std::move(cp));
    }
    pending_.clear();
    MarkupsState s = context_.workspace.markups_state();
    s.markups.push_back(m);
    s.sources.emplace_back();
    context_.edit("Add " + QString::fromStdString(m.name), core::Parts(core::Part::Markups),
                  [&] { context_.workspace.set_markups(std::move(s)); }); // the views and the panel follow
    const std::string value = markup_measurement_text(m);
    context_.status(QString::fromStdString(m.name) + ": " +
                    (value.empty() ? QString("no value (an arm has no length)") : QString::fromStdString(value)));
}

// 3D Slicer's active point list: the one selected in the panel, else the
// last one, else a new one ("F"); its points are labelled NAME-1, NAME-2, ...
void MeasureTools::add_list_point(const glm::dvec3& lps) {
    MarkupsState s = context_.workspace.markups_state();
    std::optional<std::size_t> list;
    if (const auto sel = context_.workspace.selected(); sel && s.markups[*sel].type == MarkupType::Fiducial) list = sel;
    for (std::size_t i = s.markups.size(); !list && i-- > 0;)
        if (s.markups[i].type == MarkupType::Fiducial) list = i;
    if (!list) {
        Markup m;
        m.type = MarkupType::Fiducial;
        m.name = next_name(MarkupType::Fiducial).toStdString();
        s.markups.push_back(std::move(m));
        s.sources.emplace_back();
        list = s.markups.size() - 1;
    }
    Markup& m = s.markups[*list];
    const auto taken = [&](const std::string& label, const std::string& id) {
        return std::any_of(m.points.begin(), m.points.end(),
                           [&](const MarkupControlPoint& p) { return p.label == label || p.id == id; });
    };
    int n = int(m.points.size()) + 1;
    const std::string prefix = (m.name.empty() ? std::string("F") : m.name) + "-";
    while (taken(prefix + std::to_string(n), std::to_string(n))) ++n;
    MarkupControlPoint cp;
    cp.id = std::to_string(n);
    cp.label = prefix + std::to_string(n);
    cp.position = lps;
    m.points.push_back(cp);
    context_.edit("Add point " + QString::fromStdString(cp.label), core::Parts(core::Part::Markups),
                  [&] { context_.workspace.set_markups(std::move(s)); });
    QString msg = QString::fromStdString(cp.label) + ": " + lps_text(lps);
    if (context_.workspace.scene().has_volume()) {
        const auto v = core::value_at(context_.workspace.scene(), lps);
        msg += ", " +
               (v ? QString::fromStdString(core::value_readout(v->value, core::value_unit(context_.workspace.scene())))
                  : QString("outside the volume"));
    }
    context_.status(msg);
}

std::vector<Markup> MeasureTools::drawn_markups() const {
    std::vector<Markup> drawn = context_.workspace.markups();
    if (const auto sel = context_.workspace.selected(); sel && *sel < drawn.size()) {
        Markup& m = drawn[*sel];
        m.selected_color = highlight_color();
        for (auto& p : m.points) p.selected = true;
    }
    return drawn;
}

void MeasureTools::redraw() {
    escape_->setEnabled(!pending_.empty());
    // The 3D view draws the placed points as a point list next to the markups.
    if (auto* v = context_.viewer()) {
        std::vector<Markup> drawn = drawn_markups();
        // Each line's and angle's name (the overlay labels a point list's
        // points itself) by its point furthest right in the view now: the
        // label runs to the right, away from the segments and the value.
        std::vector<std::pair<glm::dvec3, std::string>> names;
        for (const Markup& m : drawn) {
            if (m.type == MarkupType::Fiducial || m.name.empty()) continue;
            std::optional<std::pair<double, glm::dvec3>> right;
            for (const auto& p : m.points) {
                const auto px = p.status == PositionStatus::Defined ? v->image_pixel(p.position) : std::nullopt;
                if (px && (!right || px->x() > right->first)) right = std::pair{px->x(), p.position};
            }
            if (right) names.emplace_back(right->second, m.name);
        }
        v->set_labels(std::move(names));
        if (!pending_.empty()) {
            Markup placing;
            placing.type = MarkupType::Fiducial;
            placing.name = "placing";
            for (std::size_t i = 0; i < pending_.size(); ++i) {
                MarkupControlPoint cp;
                cp.label = std::to_string(i + 1);
                cp.position = pending_[i];
                placing.points.push_back(std::move(cp));
            }
            placing.selected_color = glm::dvec3(1.0, 0.9, 0.3);
            drawn.push_back(std::move(placing));
        }
        v->set_markups(std::move(drawn));
    }
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal})
        context_.slice_view(o)->update();
}

} // namespace iso::gui
