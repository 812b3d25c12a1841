#include "app/gui/crop_box.hpp"

#include <QMainWindow>
#include <QPainter>
#include <QPen>
#include <QUndoStack>

#include <array>
#include <memory>
#include <cmath>
#include <vector>

#include "app/gui/app_context.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/slices.hpp"

namespace iso::gui {

namespace {

const char* const kAxes[] = {"L", "P", "S"};

// One side of the box's section with a view's plane: its ends (image
// pixels) and the face of the box it lies on (none: it lies on no single face).
struct Side {
    QPointF a, b;
    std::optional<CropBoxTool::Face> face;
};

std::vector<Side> section(const std::pair<glm::dvec3, glm::dvec3>& box, const core::SliceGrid& g) {
    const auto poly = core::plane_box_section(core::box_corners(box), g.normal, g.offset_mm);
    std::vector<Side> sides;
    const double eps = 1e-6 * (1.0 + glm::length(box.second - box.first));
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const glm::dvec3 &p = poly[i], &q = poly[(i + 1) % poly.size()];
        Side s;
        const auto pa = core::lps_to_pixel(g, p).pixel, pb = core::lps_to_pixel(g, q).pixel;
        s.a = {pa.x, pa.y};
        s.b = {pb.x, pb.y};
        for (int a = 0; a < 3 && !s.face; ++a)
            for (const bool max : {false, true}) {
                const double v = max ? box.second[a] : box.first[a];
                if (std::abs(p[a] - v) <= eps && std::abs(q[a] - v) <= eps) s.face = CropBoxTool::Face{a, max};
            }
        sides.push_back(s);
    }
    return sides;
}

double distance_to_segment(QPointF p, QPointF a, QPointF b) {
    const QPointF ab = b - a;
    const double len2 = QPointF::dotProduct(ab, ab);
    const double t = len2 > 0 ? std::clamp(QPointF::dotProduct(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    const QPointF d = p - (a + t * ab);
    return std::hypot(d.x(), d.y());
}

} // namespace

CropBoxTool::CropBoxTool(AppContext& context) : QObject(&context.window), context_(context) {
    // The views draw the box as the workspace has it (an undo, the panel's numbers).
    observer_ = context_.workspace.observe([this](core::Parts p) {
        if (!(p & (core::Part::Look | core::Part::Data))) return;
        if (core::has(p, core::Part::Data)) grab_.reset();
        for (SliceView* v : context_.slices)
            if (v) v->update();
    });
    // An undo or redo during a drag (the keyboard) ends it: the state it started from is gone.
    connect(&context.undo, &QUndoStack::indexChanged, this, [this] { grab_.reset(); });
}

CropBoxTool::~CropBoxTool() { context_.workspace.unobserve(observer_); }

std::optional<CropBoxTool::Face> CropBoxTool::dragging() const {
    return grab_ ? std::optional<Face>(grab_->face) : std::nullopt;
}

void CropBoxTool::attach(SliceView& view) {
    view.add_overlay([this](SliceView& v, QPainter& p) {
        const auto& box = context_.workspace.look().clip.box;
        if (!box || !v.has_image()) return;
        for (const Side& s : section(*box, v.grid())) {
            const bool held = grab_ && s.face && s.face->axis == grab_->face.axis && s.face->max == grab_->face.max;
            p.setPen(QPen(QColor(0, 0, 0, 160), held ? 5.0 : 3.5));
            p.drawLine(s.a, s.b);
            p.setPen(QPen(QColor(255, 140, 26), held ? 3.0 : 1.5, held ? Qt::SolidLine : Qt::DashLine));
            p.drawLine(s.a, s.b);
        }
    });
    view.add_grabber({[this](SliceView& v, QPointF p) { return press(v, p); },
                      [this](SliceView& v, QPointF p) { move(v, p); },
                      [this](SliceView& v, QPointF p, bool dragged) { release(v, p, dragged); }});
}

bool CropBoxTool::press(SliceView& view, QPointF pixel) {
    const auto& box = context_.workspace.look().clip.box;
    if (!box || !view.has_image() || context_.busy() || context_.tool() != AppContext::Tool::None) return false;
    std::optional<Face> best;
    double best_d = kGrabRadiusPx;
    for (const Side& s : section(*box, view.grid()))
        if (const double d = distance_to_segment(pixel, s.a, s.b); s.face && d <= best_d) {
            best_d = d;
            best = s.face;
        }
    if (!best) return false;
    grab_ = Grab{*best, context_.workspace.look()};
    context_.status(QString("Moving the crop box's %1 %2: release to place it (Edit > Undo puts it back)")
                        .arg(kAxes[best->axis])
                        .arg(best->max ? "max" : "min"));
    for (SliceView* v : context_.slices) v->update();
    return true;
}

void CropBoxTool::move(SliceView& view, QPointF pixel) {
    if (!grab_ || !view.has_image()) return;
    move_face(core::pixel_to_lps(view.grid(), {pixel.x(), pixel.y()})[grab_->face.axis]);
}

void CropBoxTool::move_face(double value) {
    FrameLook look = context_.workspace.look();
    if (!grab_ || !look.clip.box || !std::isfinite(value)) return;
    auto& [lo, hi] = *look.clip.box;
    const int a = grab_->face.axis;
    // Never past the opposite face: the box stays a box.
    if (grab_->face.max)
        hi[a] = std::max(value, lo[a]);
    else
        lo[a] = std::min(value, hi[a]);
    context_.workspace.set_look(look); // shown at once; the release makes the undo step
    context_.status(QString("Crop box %1 %2: %3 mm")
                        .arg(kAxes[a])
                        .arg(grab_->face.max ? "max" : "min")
                        .arg(grab_->face.max ? hi[a] : lo[a], 0, 'f', 1));
}

void CropBoxTool::release(SliceView& view, QPointF pixel, bool dragged) {
    if (!grab_) return;
    if (dragged) move(view, pixel); // where the pointer was let go
    finish();
}

void CropBoxTool::finish() {
    if (!grab_) return;
    const Grab g = *grab_;
    grab_.reset();
    core::WorkspaceEdit e;
    e.text = QString("Move crop box %1 %2").arg(kAxes[g.face.axis]).arg(g.face.max ? "max" : "min").toStdString();
    e.parts = core::Parts(core::Part::Look);
    e.before.look = g.before;
    e.after.look = context_.workspace.look();
    context_.push(std::move(e)); // nothing when it did not move
    for (SliceView* v : context_.slices) v->update();
}

// ---- the 3D view ------------------------------------------------------------------------

void CropBoxTool::attach(Viewer& viewer) {
    // After the hooks set before (a markup point under the pointer first).
    auto press = viewer.on_press;
    auto move = viewer.on_grab_move;
    auto release = viewer.on_grab_release;
    auto mine = std::make_shared<bool>(false);
    viewer.on_press = [this, press, mine](Viewer& v, QPointF p) {
        *mine = false;
        if (press && press(v, p)) return true;
        return *mine = press_3d(v, p);
    };
    viewer.on_grab_move = [this, move, mine](Viewer& v, QPointF p) {
        if (*mine)
            move_3d(v, p);
        else if (move)
            move(v, p);
    };
    viewer.on_grab_release = [this, release, mine](Viewer& v, QPointF p, bool dragged) {
        if (!*mine) {
            if (release) release(v, p, dragged);
            return;
        }
        if (dragged) move_3d(v, p);
        finish();
    };
}

bool CropBoxTool::press_3d(Viewer& v, QPointF pixel) {
    const auto& box = context_.workspace.look().clip.box;
    if (!box || context_.busy() || context_.tool() != AppContext::Tool::None) return false;
    std::optional<Face> best;
    double best_d = kHandleRadiusPx * v.devicePixelRatioF();
    for (const auto& [face, centre] : face_centres(*box)) {
        const auto at = v.image_pixel(centre);
        if (!at) continue;
        if (const double d = std::hypot(at->x() - pixel.x(), at->y() - pixel.y()); d <= best_d) {
            best_d = d;
            best = face;
        }
    }
    if (!best) return false;
    grab_ = Grab{*best, context_.workspace.look()};
    context_.status(QString("Moving the crop box's %1 %2: release to place it (Edit > Undo puts it back)")
                        .arg(kAxes[best->axis])
                        .arg(best->max ? "max" : "min"));
    return true;
}

// The face's axis through the grabbed handle, and the ray under the
// pointer: the axis point nearest the ray is where the face goes (none when
// the view looks along the axis).
void CropBoxTool::move_3d(Viewer& v, QPointF pixel) {
    const auto& box = context_.workspace.look().clip.box;
    if (!grab_ || !box) return;
    const int a = grab_->face.axis;
    glm::dvec3 centre = 0.5 * (box->first + box->second), axis(0.0);
    axis[a] = 1.0;
    const QSize size = v.image_size();
    const Ray r = v.camera().pixel_ray(pixel.x(), pixel.y(), size.width(), size.height());
    const glm::dvec3 d = glm::normalize(r.dir), w0 = centre - r.origin;
    const double b = glm::dot(axis, d), denom = 1.0 - b * b;
    if (denom < 1e-6) return; // looking along the axis: no point is nearer than another
    const double t = (b * glm::dot(d, w0) - glm::dot(axis, w0)) / denom;
    move_face(centre[a] + t);
}

std::vector<std::pair<CropBoxTool::Face, glm::dvec3>>
CropBoxTool::face_centres(const std::pair<glm::dvec3, glm::dvec3>& box) {
    std::vector<std::pair<Face, glm::dvec3>> out;
    const glm::dvec3 mid = 0.5 * (box.first + box.second);
    for (int a = 0; a < 3; ++a)
        for (const bool max : {false, true}) {
            glm::dvec3 c = mid;
            c[a] = max ? box.second[a] : box.first[a];
            out.push_back({Face{a, max}, c});
        }
    return out;
}

} // namespace iso::gui
