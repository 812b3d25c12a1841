#include "app/gui/slice_view.hpp"

#include <QApplication>
#include <QFont>
#include <QKeyEvent>
#include <QPointer>
#include <QThread>
#include <QThreadPool>
#include <QMouseEvent>
#include <QPainter>
#include <QTransform>
#include <QWheelEvent>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <iostream>

#include <glm/geometric.hpp>

#include "io/color.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/workspace.hpp"
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

SliceView::~SliceView() { set_workspace(nullptr); }

void SliceView::set_workspace(core::Workspace* workspace) {
    if (workspace_) workspace_->unobserve(observer_);
    workspace_ = workspace;
    fitted_ = user_framed_ = false;
    range_.reset();
    if (workspace_) {
        observer_ = workspace_->observe([this](core::Parts p) {
            if (core::has(p, core::Part::Data)) { // new data: fitted again, its own range
                fitted_ = user_framed_ = false;
                range_.reset();
                drop_slice(); // the slice shown is of the data before
            } else if (core::has(p, core::Part::Slices) && fitted_ && plane() && plane()->pixel_mm != fit_pixel_mm_) {
                user_framed_ = true; // framed elsewhere (a session, an undo): resizes keep it
            }
            if (p & (core::Part::Data | core::Part::Window)) set_window(workspace_->window());
            if (p & (core::Part::Data | core::Part::Slices))
                refresh();
            else if (core::has(p, core::Part::Surfaces))
                refresh_outlines(); // the same slice: its image stays
        });
        window_ = workspace_->window();
    }
    refresh();
}

const core::Scene* SliceView::scene() const { return workspace_ ? &workspace_->scene() : nullptr; }

const core::SlicePlane* SliceView::plane() const {
    return workspace_ && workspace_->scene().has_volume() ? &workspace_->planes()[std::size_t(orientation_)] : nullptr;
}

void SliceView::set_plane(const core::SlicePlane& p) {
    auto planes = workspace_->planes();
    planes[std::size_t(orientation_)] = p;
    workspace_->set_planes(planes); // notifies: every view refreshes
}

void SliceView::keep_framing() {
    fitted_ = user_framed_ = true;
    refresh();
}

void SliceView::scroll(double steps) {
    if (!plane()) return;
    auto planes = workspace_->planes();
    auto& p = planes[std::size_t(orientation_)];
    core::scroll_slices(p, steps);
    // The other views' crosshair lines follow the moved slice.
    core::set_crosshair(planes, p.origin);
    workspace_->set_planes(planes);
}

void SliceView::set_window(const core::WindowLevel& w) {
    window_ = w;
    if (!values_.values.empty()) show_values(image_grid_); // values_ and image_ come and go together
    update();
}

void SliceView::show_values(const core::SliceGrid& grid) {
    grey_ = core::apply_window(values_, window_, core::PixelFormat::Grey8);
    image_ = QImage(grey_.data(), values_.width, values_.height, values_.width, QImage::Format_Grayscale8).copy();
    image_grid_ = grid;
}

std::size_t SliceView::outline_segments() const {
    std::size_t n = 0;
    for (const auto& o : outlines_) n += o.segments.size();
    return n;
}

void SliceView::drop_outlines() {
    outlines_.clear();
    outline_image_ = QImage();
    ++outline_generation_; // outlines asked for before are for another slice or other surfaces
    pending_outlines_.reset();
}

void SliceView::refresh_outlines() {
    if (image_.isNull() || !plane()) {
        refresh();
        return;
    }
    drop_outlines();
    try {
        request_outlines();
    } catch (const std::exception& e) {
        std::cerr << "isoscope gui: " << core::slice_orientation_name(orientation_) << " view: " << e.what() << "\n";
    }
    update();
}

void SliceView::refresh() {
    drop_outlines();
    const core::SlicePlane* plane = this->plane();
    if (!plane || width() < 1 || height() < 1) {
        drop_slice();
        update();
        return;
    }
    try {
        if (!fitted_) {
            fitted_ = true;
            core::SlicePlane fitted = *plane;
            core::zoom_to_fit(fitted, width(), height());
            fit_pixel_mm_ = fitted.pixel_mm;
            if (!(fitted == *plane)) {
                set_plane(fitted); // its notification refreshes
                return;
            }
        }
        grid_ = core::slice_grid(*plane, width(), height());
        request_slice();
        request_outlines();
    } catch (const std::exception& e) {
        // Nothing escapes into Qt's event loop.
        std::cerr << "isoscope gui: " << core::slice_orientation_name(orientation_) << " view: " << e.what() << "\n";
        drop_slice();
    }
    update_probe(); // the slice under the pointer moved
    update();
    if (on_refresh) on_refresh(*this);
}

// What an outline job reads: shared, never changed in place.
struct SliceView::OutlineJob {
    struct Surface {
        std::shared_ptr<const Mesh> mesh;
        std::shared_ptr<const core::OutlineIndex> index;
        QColor color;
    };
    core::SliceGrid grid;
    std::vector<Surface> surfaces;
    std::uint64_t generation = 0;
    std::vector<Outline> run() const {
        std::vector<Outline> out;
        for (const auto& s : surfaces) out.push_back({core::mesh_outline(*s.mesh, grid, *s.index), s.color});
        return out;
    }
};

namespace {
// The outlines as the view paints them (antialiased, 1.5 px).
void paint_outlines(QPainter& p, const std::vector<SliceView::Outline>& outlines) {
    p.setRenderHint(QPainter::Antialiasing);
    std::vector<QLineF> lines;
    for (const auto& o : outlines) {
        p.setPen(QPen(o.color, 1.5));
        lines.clear();
        lines.reserve(o.segments.size());
        for (const auto& s : o.segments) lines.emplace_back(s.a.x, s.a.y, s.b.x, s.b.y);
        p.drawLines(lines.data(), int(lines.size()));
    }
}

// Painted once into an image of the view's size (a slice through a
// 30 M-triangle surface has 10^5 segments: 90 ms of antialiased strokes,
// which the pool thread pays instead of every paint of the GUI thread).
QImage outline_image(const std::vector<SliceView::Outline>& outlines, int width, int height) {
    QImage image(std::max(1, width), std::max(1, height), QImage::Format_ARGB32_Premultiplied);
    image.fill(Qt::transparent);
    QPainter p(&image);
    paint_outlines(p, outlines);
    return image;
}
} // namespace

void SliceView::request_outlines() {
    const core::Scene& scene = workspace_->scene();
    auto job = std::make_shared<OutlineJob>();
    job->grid = grid_;
    job->generation = ++outline_generation_;
    std::size_t triangles = 0;
    for (auto id : scene.surfaces()) {
        const auto& info = scene.info(id);
        if (!info.visible) continue;
        job->surfaces.push_back({scene.shared_mesh(id), scene.outline_index(id), to_qcolor(info.color)});
        triangles += scene.mesh(id).triangles.size();
    }
    pending_outlines_.reset();
    if (triangles <= inline_triangles_) {
        outlines_ = job->run();
        return;
    }
    pending_outlines_ = std::move(job);
    start_outlines();
}

namespace {
// The slice views' own threads (two per kind of job, below the GUI
// thread's priority), not Qt's global pool: the raster engine draws large
// images with the global pool's threads and waits for them, so a paint
// waited behind outline jobs.
QThreadPool* view_pool(QPointer<QThreadPool>& pool, const char* name) {
    if (!pool) {
        pool = new QThreadPool(qApp); // waited for when the application goes
        pool->setObjectName(name);
        pool->setMaxThreadCount(2);
        pool->setThreadPriority(QThread::LowPriority);
    }
    return pool;
}
QThreadPool* outline_pool() {
    static QPointer<QThreadPool> pool;
    return view_pool(pool, "slice_outlines");
}
QThreadPool* slice_pool() {
    static QPointer<QThreadPool> pool;
    return view_pool(pool, "slice_images");
}
} // namespace

void SliceView::start_outlines() {
    if (outlining_ || !pending_outlines_) return;
    outlining_ = true;
    std::shared_ptr<const OutlineJob> job = std::move(pending_outlines_);
    outline_pool()->start([job, self = QPointer<SliceView>(this)] {
        auto out = std::make_shared<std::vector<Outline>>();
        auto image = std::make_shared<QImage>();
        try {
            *out = job->run();
            *image = outline_image(*out, job->grid.width, job->grid.height);
        } catch (const std::exception& e) {
            std::cerr << "isoscope gui: slice outlines: " << e.what() << "\n";
        }
        // Back on the GUI thread (the application outlives the view; the view may not).
        QMetaObject::invokeMethod(
            qApp,
            [self, job, out, image] {
                if (!self) return;
                self->outlining_ = false;
                if (job->generation == self->outline_generation_) {
                    self->outlines_ = std::move(*out);
                    self->outline_image_ = std::move(*image);
                    self->update();
                }
                self->start_outlines();
            },
            Qt::QueuedConnection);
    });
}

// What a slice job reads: the volume as the scene shares it (a volume
// opened meanwhile replaces it there; this one stays until the job ends).
struct SliceView::SliceJob {
    std::shared_ptr<const Volume> volume;
    core::SliceGrid grid;
    std::uint64_t generation = 0;
};

void SliceView::drop_slice() {
    image_ = QImage();
    values_ = {};
    pending_slice_.reset();
    ++slice_generation_; // a slice on its way is for data or a plane no longer shown
}

void SliceView::request_slice() {
    auto job = std::make_shared<SliceJob>();
    job->volume = workspace_->scene().shared_volume();
    job->grid = grid_;
    job->generation = ++slice_generation_;
    pending_slice_.reset();
    if (std::size_t(job->volume->voxel_count()) <= inline_voxels_) {
        // Here: an arena of one, so the GUI thread never waits on a TBB worker.
        core::reslice_here(*job->volume, grid_, core::Interp::Linear, values_);
        show_values(grid_);
        return;
    }
    pending_slice_ = std::move(job);
    start_slice();
}

void SliceView::start_slice() {
    if (reslicing_ || !pending_slice_) return;
    reslicing_ = true;
    std::shared_ptr<const SliceJob> job = std::move(pending_slice_);
    slice_pool()->start([job, self = QPointer<SliceView>(this)] {
        auto values = std::make_shared<core::SliceImage>();
        std::string error;
        try {
            core::reslice_here(*job->volume, job->grid, core::Interp::Linear, *values);
        } catch (const std::exception& e) {
            error = e.what();
        }
        // Back on the GUI thread (the application outlives the view; the view may not).
        QMetaObject::invokeMethod(
            qApp,
            [self, job, values, error] {
                if (!self) return;
                self->reslicing_ = false;
                if (job->generation == self->slice_generation_) {
                    if (error.empty()) {
                        self->values_ = std::move(*values);
                        self->show_values(job->grid);
                    } else {
                        std::cerr << "isoscope gui: " << core::slice_orientation_name(self->orientation_)
                                  << " view: " << error << "\n";
                        self->drop_slice();
                    }
                    self->update_probe();
                    self->update();
                }
                self->start_slice();
            },
            Qt::QueuedConnection);
    });
}

void SliceView::fit() {
    const core::SlicePlane* plane = this->plane();
    if (!plane) return;
    core::SlicePlane p = *plane;
    core::fit_view(p, workspace_->scene().volume(), width(), height());
    fit_pixel_mm_ = p.pixel_mm;
    fitted_ = true;
    user_framed_ = false; // fitted again: a resize fits it again too
    set_plane(p);
    refresh(); // unchanged planes notify nothing
}

void SliceView::update_probe() {
    probe_.clear();
    if (hover_ && !image_.isNull() && plane()) probe_ = slice_readout(workspace_->scene().volume(), grid_, *hover_);
}

QString SliceView::edge_letter(core::SliceEdge e) const {
    const core::SlicePlane* plane = this->plane();
    return image_.isNull() || !plane ? QString() : QString::fromStdString(core::slice_edge_letter(*plane, e));
}

double SliceView::scale_bar_mm() const {
    const core::SlicePlane* plane = this->plane();
    return image_.isNull() || !plane ? 0.0 : core::slice_scale_bar_mm(*plane, grid_.width);
}

double SliceView::scale_bar_pixels() const { return image_.isNull() ? 0.0 : scale_bar_mm() / grid_.pixel_mm; }

namespace {
bool same_grid(const core::SliceGrid& a, const core::SliceGrid& b) {
    return a.width == b.width && a.height == b.height && a.corner == b.corner && a.dx == b.dx && a.dy == b.dy;
}

// Pixels of grid `from` to pixels of grid `to`, where the planes are
// parallel (each point taken along the normal onto `to`); none otherwise.
std::optional<QTransform> placed_on(const core::SliceGrid& from, const core::SliceGrid& to) {
    if (std::abs(glm::dot(from.normal, to.normal)) < 1.0 - 1e-9) return std::nullopt;
    const double ux = glm::dot(to.dx, to.dx), uy = glm::dot(to.dy, to.dy);
    if (!(ux > 0) || !(uy > 0)) return std::nullopt;
    const glm::dvec3 c = from.corner - to.corner;
    return QTransform(glm::dot(from.dx, to.dx) / ux, glm::dot(from.dx, to.dy) / uy, glm::dot(from.dy, to.dx) / ux,
                      glm::dot(from.dy, to.dy) / uy, glm::dot(c, to.dx) / ux, glm::dot(c, to.dy) / uy);
}
} // namespace

void SliceView::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.fillRect(rect(), Qt::black);
    if (image_.isNull()) return;
    if (same_grid(image_grid_, grid_)) {
        p.drawImage(0, 0, image_);
    } else if (const auto to_view = placed_on(image_grid_, grid_)) {
        // The slice before, until the new one comes (large volumes).
        p.save();
        p.setTransform(*to_view);
        p.setRenderHint(QPainter::SmoothPixmapTransform);
        p.drawImage(0, 0, image_);
        p.restore();
    }
    if (!outline_image_.isNull())
        p.drawImage(0, 0, outline_image_);
    else
        paint_outlines(p, outlines_);
    p.setRenderHint(QPainter::Antialiasing);        // the crosshair, the text and the overlays too
    const core::SlicePlane& plane = *this->plane(); // an image: a plane
    const auto c = core::lps_to_pixel(grid_, plane.origin).pixel;
    p.setPen(QPen(QColor(255, 200, 0, 160), 1.0, Qt::DashLine));
    p.drawLine(QPointF(c.x, 0), QPointF(c.x, height()));
    p.drawLine(QPointF(0, c.y), QPointF(width(), c.y));
    p.setPen(Qt::yellow);
    p.drawText(QPointF(6, 16),
               QString("%1  %2 mm").arg(core::slice_orientation_name(orientation_)).arg(plane.offset_mm(), 0, 'f', 1));
    for (const auto& paint : overlays_) paint(*this, p);
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
    grabbing_ = nullptr;
    if (e->button() == Qt::LeftButton && e->buttons() == Qt::LeftButton && !image_.isNull())
        for (const auto& g : grabbers_)
            if (g.press && g.press(*this, e->position())) {
                grabbing_ = &g;
                break;
            }
}

void SliceView::mouseReleaseEvent(QMouseEvent* e) {
    if (swallow_release_ && e->button() == Qt::LeftButton) {
        swallow_release_ = false; // the double-click's release: no click
        return;
    }
    if (grabbing_ && e->button() == Qt::LeftButton) {
        const Grabber* g = std::exchange(grabbing_, nullptr);
        if (g->release) g->release(*this, e->position(), drag_.dragged);
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
    const core::SlicePlane* plane = this->plane();
    if (image_.isNull() || !plane) return;
    if (!drag_.follow(e->position())) return;
    const QPointF d = drag_.step(e->position());
    if (grabbing_) { // what was grabbed follows the pointer; the window stays
        if (grabbing_->move) grabbing_->move(*this, e->position());
        return;
    }
    if (e->buttons() & Qt::LeftButton) {
        if (!range_) range_ = workspace_->scene().value_range(); // the scene's, worked out once
        const QPointF total = e->position() - drag_.press;
        workspace_->set_window(core::drag_window(window_at_press_, {total.x(), -total.y()}, *range_));
    } else if (e->buttons() & Qt::MiddleButton) {
        core::SlicePlane p = *plane;
        core::pan_pixels(p, {d.x(), d.y()});
        user_framed_ = true;
        set_plane(p);
    } else if (e->buttons() & Qt::RightButton) {
        core::SlicePlane p = *plane;
        core::zoom_about(p, width(), height(), {drag_.press.x(), drag_.press.y()},
                         core::drag_zoom_factor(-d.y(), height()));
        user_framed_ = true;
        set_plane(p);
    }
}

void SliceView::wheelEvent(QWheelEvent* e) {
    wheel_ += e->angleDelta().y();
    const double steps = std::trunc(wheel_ / 120.0);
    if (steps != 0) {
        wheel_ -= steps * 120.0;
        scroll(steps);
    }
    e->accept();
}

void SliceView::keyPressEvent(QKeyEvent* e) {
    if (e->key() == Qt::Key_PageUp || e->key() == Qt::Key_PageDown) {
        scroll(e->key() == Qt::Key_PageUp ? 1.0 : -1.0);
        return;
    }
    if (e->key() == Qt::Key_F && e->modifiers() == Qt::NoModifier) {
        fit();
        return;
    }
    QWidget::keyPressEvent(e);
}

} // namespace iso::gui
