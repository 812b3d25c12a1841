#include "app/gui/viewer.hpp"

#include <QApplication>
#include <QKeyEvent>
#include <QPainter>
#include <QPen>
#include <QPolygonF>
#include <QMouseEvent>
#include <QTimer>
#include <QWheelEvent>

#include <chrono>
#include <cmath>
#include <future>
#include <cstdlib>
#include <iostream>

#include "app/gui/raytraced_refiner.hpp"
#include "app/gui/still_frames.hpp"
#include "io/error.hpp"
#include "renderer/core/legend.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/workspace.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/gl/context.hpp"

namespace iso::gui {

Viewer::Viewer(core::Workspace& workspace, PatientView view, ViewerOptions options, QWidget* parent)
    : QWidget(parent), workspace_(workspace), scene_(workspace.scene()), initial_view_(view), options_(options),
      annotations_(std::make_unique<Annotations>()) {
    setFocusPolicy(Qt::StrongFocus);
    setMinimumSize(320, 240);
    // A large surface's levels of detail are built off the GUI thread; its
    // frames draw every triangle meanwhile (docs/lod.md).
    scene_.set_background_lod(true);
    setMouseTracking(true); // hover readout
    // Each paint covers the whole widget (the picture or the background).
    setAttribute(Qt::WA_OpaquePaintEvent);
    still_timer_ = new QTimer(this);
    still_timer_->setSingleShot(true);
    connect(still_timer_, &QTimer::timeout, this, [this] { schedule_still_frame(); });
    qApp->installEventFilter(this);
}

Viewer::~Viewer() {
    refiner_.reset(); // cancels and waits for its worker before anything it posts to goes
    stills_.reset();  // its frame in progress finishes; it frees its own context's objects
    if (context_) {   // frames drawn here: their GL objects go with this view's context current
        gl::ScopedCurrent current(context_.get());
        scene_.release_gpu();
    }
}

namespace {
const QColor kBackground = QColor::fromRgbF(0.08f, 0.09f, 0.11f);
} // namespace

gl::HeadlessContext& Viewer::gl_context() {
    if (!context_) context_ = std::make_unique<gl::HeadlessContext>();
    return *context_;
}

double Viewer::aspect() const { return double(std::max(1, width())) / double(std::max(1, height())); }

// The same framing as `isoscope render`: the scene's camera for the view.
// A camera set before the first frame (a session) is kept.
// Framed while every visible surface was empty, it frames the first
// surfaces that are not (keeping the direction) once they appear; later
// surfaces leave the camera where the user put it.
void Viewer::initialize() {
    initialized_ = true;
    const bool framed = !camera_set_;
    if (!camera_set_) camera_ = scene_.camera(initial_view_, aspect(), options_.look);
    framed_empty_ = !camera_set_ && scene_.bounds(options_.look).empty();
    if (framed) camera_moved();
}

// The picture (a frame's image, scaled up when a drag's frame was drawn
// smaller) or the background, and the sketch over it: painted by the
// raster engine into the window's backing store.
void Viewer::paintEvent(QPaintEvent*) {
    if (!initialized_) initialize();
    if (error_.empty()) {
        try {
            draw();
        } catch (const std::exception& e) {
            // Nothing escapes into Qt's event loop: report, show the background, stop drawing.
            error_ = e.what();
            std::cerr << "isoscope view: error: " << error_ << "\n";
            setToolTip(QString::fromStdString(error_));
        }
    }
    if (!error_.empty()) shown_ = QImage();
    QPainter p(this);
    if (shown_.isNull()) {
        p.fillRect(rect(), kBackground);
    } else {
        const QSize size = image_size();
        if (shown_.size() != size) p.setRenderHint(QPainter::SmoothPixmapTransform);
        p.drawImage(QRectF(rect()), shown_, QRectF(shown_.rect()));
    }
    paint_sketch(p);
}

// A frame as the view draws it (its picks ride on one of these too).
RenderOptions Viewer::frame_options() const {
    const QSize size = image_size();
    RenderOptions opt;
    opt.width = size.width();
    opt.height = size.height();
    opt.scale = float(devicePixelRatioF());
    opt.annotations = annotations_.get();
    // Read back, not presented: the widget paints the image.
    opt.present = false;
    opt.target_framebuffer = 0;
    // While a drag turns, pans or zooms the view, frames go without AO (on
    // software GL it costs 2-3x a frame, docs/gui.md); the still frames after
    // the release bring it back and accumulate it.
    opt.look = options_.look;
    // The volume is sampled more coarsely while the camera moves
    // (VolumeLook::moving_step); still frames take the full step.
    opt.moving = dragging_;
    // DSRAA's sub-samples cost up to 2.7x a frame without AO on software GL
    // (llvmpipe rasterizes every sub-sample; docs/image_bench.md "What DSRAA
    // costs the live view"): a drag goes without them, as without AO, and the
    // still frames after it are anti-aliased.
    if (dragging_ && !options_.ao_while_dragging) {
        opt.look.ao = AoMethod::Off;
        opt.look.aa.samples = 1;
    }
    // Ray-traced AO: its latest batch for this view; cone AO until the first
    // arrives and while the camera moves.
    if (opt.look.ao == AoMethod::Raytraced) {
        if (raytraced_ && !dragging_)
            opt.ao_image = raytraced_.get();
        else
            opt.look.ao = AoMethod::Cone;
    }
    // Still frames are jittered and averaged (anti-aliasing that converges
    // to exact coverage, translucent surfaces and the overlay included).
    // Any change starts the average again, a new ray-traced AO batch too:
    // while the AO refines, each batch gets one plain frame (a drag's), and
    // the anti-aliasing follows its last batch.
    const bool refining = options_.look.ao == AoMethod::Raytraced && !raytraced_stats_.done;
    if (refining) opt.look.aa.samples = 1;
    opt.accumulate = !dragging_ && !refining && options_.look.aa.view_frames > 1;
    return opt;
}

bool Viewer::converged() const {
    if (frames_ == 0 || !complete_) return false;
    return options_.look.ao != AoMethod::Raytraced || (raytraced_drawn_ && raytraced_stats_.done);
}

int Viewer::still_frames_held() const { return still_frames_held_ + (stills_ ? stills_->held() : 0); }

// Ray-traced AO follows the view: a new camera, size, look or scene drops
// the image and restarts the refinement; while a drag moves the camera
// nothing is traced.
void Viewer::follow_raytraced() {
    if (options_.look.ao != AoMethod::Raytraced || dragging_) {
        if (refiner_) refiner_->cancel();
        raytraced_.reset();
        return;
    }
    if (!refiner_)
        refiner_ = std::make_unique<RaytracedRefiner>(this, [this](const RaytracedBatch& b) { take_batch(b); });
    const QSize size = image_size();
    // What the AO depends on: the workspace's data, surfaces, camera and look
    // (their notifications), the image's size and the view's AO settings.
    const FrameLook& l = options_.look;
    const std::vector<double> key{
        double(workspace_.revision(core::Part::Data | core::Part::Surfaces | core::Part::Camera | core::Part::Look)),
        double(size.width()),
        double(size.height()),
        l.cone.radius_mm,
        l.ao_error,
        double(l.ao_rays),
        double(l.transparency)};
    if (key == refiner_->current_key()) return;
    raytraced_.reset();
    raytraced_stats_ = {};
    refiner_->ensure(key, scene_, camera_, size.width(), size.height(), options_.look);
}

// On the GUI thread, once per batch: keep the image and draw a frame with it.
void Viewer::take_batch(const RaytracedBatch& b) {
    if (!refiner_ || b.job != refiner_->job() || refiner_->current_key().empty()) return; // stale
    raytraced_ = b.image;
    raytraced_stats_ = b.stats;
    ++raytraced_version_;
    update();
}

// The camera moved: the workspace keeps it (sessions, exports), and its
// picture key changes with it.
void Viewer::camera_moved() { workspace_.set_camera(camera_); }

// What the next paint would do to the camera, now: surfaces joining are
// framed when they join, so the workspace's camera (what a session saves,
// what an export draws) is the framed one at once, not after a paint that
// may come later on a busy machine.
void Viewer::frame_now() {
    if (!initialized_) initialize();
    frame_camera();
}

// The camera framed for what is visible now (see initialize): the
// visible surfaces and the volume when it is ray cast (Scene::bounds(look)),
// its near and far planes around them.
void Viewer::frame_camera() {
    const Bounds shown = scene_.bounds(options_.look);
    if (framed_empty_ && !shown.empty()) {
        const glm::dvec3 f = camera_.forward();
        if (std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.z))
            camera_.fit(shown, aspect());
        else
            camera_ = scene_.camera(initial_view_, aspect(), options_.look);
        framed_empty_ = false;
        camera_moved();
    }
    camera_.fit_planes(shown);
}

// Frames whose look needs still frames: AO traced in the frame (cone,
// disk), DSRAA's sub-samples, the jittered average.
namespace {
bool needs_still_frames(const RenderOptions& opt) {
    const bool traced_ao = opt.look.ao != AoMethod::Off && !(opt.look.ao == AoMethod::Raytraced && opt.ao_image);
    return traced_ao || opt.look.aa.samples > 1 || opt.accumulate;
}

} // namespace

// With the frame thread, every frame is drawn there: still frames, a
// drag's frames (150-400 ms on a 32 M-triangle surface or a volume on
// llvmpipe, which held the GUI thread and every input behind them) and the
// one final frame of a look that needs no still frames; so are picks
// (pick_at). The GUI thread shows the frame asked for once it arrives, the
// newest one meanwhile, and holds no GPU copy of the scene. Without the
// thread, every frame is drawn here.
void Viewer::draw() {
    frame_camera();
    follow_raytraced();
    const RenderOptions opt = frame_options();
    annotations_->legend.clear();
    if (options_.legend) annotations_->legend = core::legend_entries(scene_, opt.look);
    if (use_still_thread()) {
        if (show_still(opt) || show_latest()) return;
        // Nothing from the thread yet: the background until its first frame
        // (a frame drawn here would upload the scene to a context here too:
        // a second GPU copy of every mesh, 1.2 GB for 32 M triangles).
        shown_ = QImage();
        return;
    }
    draw_here(opt);
}

// What a frame shows apart from its jitter and its look (compared on its
// own): the workspace's picture key (its surfaces, camera, look, markups,
// ... : every change the picture depends on notifies it), the image, the
// overlay drawn on top and the ray-traced AO batch lighting it.
std::vector<double> Viewer::frame_key(const RenderOptions& opt) const {
    return {double(workspace_.picture_key()),
            double(opt.width),
            double(opt.height),
            double(opt.scale),
            double(opt.accumulate),
            double(annotations_version_),
            double(opt.ao_image ? raytraced_version_ : 0)};
}

bool Viewer::use_still_thread() {
    if (!options_.still_thread || stills_failed_) return false;
    if (!stills_) {
        stills_ = std::make_unique<StillFrames>(this, [this](const StillFrame& f) { take_still(f); });
    }
    return true;
}

// Still frames from the thread: a view it was not asked for yet is asked
// for; its latest frame for this view is shown (true). False: none yet,
// the caller shows the newest frame or the background.
bool Viewer::show_still(const RenderOptions& opt) {
    std::vector<double> key = frame_key(opt);
    if (key != still_key_ || !(opt.look == still_look_)) {
        StillRequest r;
        r.id = ++still_id_;
        r.scene = scene_.snapshot();
        r.camera = camera_;
        r.opt = opt;
        r.annotations = std::make_shared<const Annotations>(*annotations_);
        if (opt.ao_image) r.ao_image = raytraced_;
        const bool stills = needs_still_frames(opt);
        r.ao_frames =
            stills && opt.look.ao == AoMethod::Cone && options_.look.ao == AoMethod::Cone ? options_.look.ao_frames : 0;
        r.aa_frames = opt.accumulate ? options_.look.aa.view_frames : 1;
        r.interactive = dragging_;
        const double scale = drag_pacing_.scale();
        if (dragging_ && scale < 1.0) {
            r.opt.width = std::max(1, int(std::lround(opt.width * scale)));
            r.opt.height = std::max(1, int(std::lround(opt.height * scale)));
            r.opt.scale = float(opt.scale * scale); // the overlay's text keeps its size on screen
        }
        if (dragging_) r.opt.look.lod.moving_error_px *= drag_pacing_.coarsen();
        stills_->request(std::move(r));
        still_key_ = key;
        still_look_ = opt.look;
        still_.reset();
    }
    if (!still_ || !still_->image) return false;
    show_frame(*still_, opt);
    complete_ = still_->last && !dragging_;
    return true;
}

// The newest frame the thread drew, while the one asked for is on its way.
bool Viewer::show_latest() {
    if (!latest_ || !latest_->image) return false;
    show_frame(*latest_, frame_options());
    complete_ = false;
    return true;
}

void Viewer::show_frame(const StillFrame& f, const RenderOptions& opt) {
    shown_ = f.picture;
    latest_shown_ = std::max(latest_shown_, f.request);
    if (f.image->width == opt.width) labels_ = f.labels; // a reduced drag frame's are in its own pixels
    volume_stats_ = f.volume;
    raytraced_drawn_ = opt.ao_image != nullptr;
    ao_frames_ = f.ao_frames;
    aa_frames_ = f.aa_frames;
    ++frames_;
}

// On the GUI thread, for each frame the thread drew: kept and shown if it
// is for the view as it is; an error makes the view draw its still frames
// itself from now on (and report the error if it has it too).
void Viewer::take_still(const StillFrame& f) {
    if (!f.error.empty()) {
        if (f.request != still_id_) return; // stale: the view changed since
        std::cerr << "isoscope view: still frames drawn on the GUI thread: " << f.error << "\n";
        stills_failed_ = true;
        still_key_.clear();
        update();
        return;
    }
    auto frame = std::make_shared<const StillFrame>(f);
    ++thread_frames_;
    last_thread_ms_ = f.ms;
    if (gl_renderer_.empty()) gl_renderer_ = f.gl_renderer;
    if (thread_frames_ == 1) thread_objects_first_ = f.gl_objects;
    objects_since_first_frame_ = f.gl_objects - std::min(f.gl_objects, thread_objects_first_);
    // A drag frame's time paces the next ones (their size and detail).
    if (f.interactive && f.image) drag_pacing_.frame(f.request, f.ms, f.image->width < image_size().width(), still_id_);
    // A frame for an older view is kept as the newest and shown if nothing
    // newer is: a drag's frames arrive after its camera moved on.
    const bool newer = !latest_ || f.request >= latest_->request;
    if (newer) latest_ = frame;
    if (f.request == still_id_) {
        still_ = std::move(frame);
        update();
    } else if (newer && f.request > latest_shown_) {
        update();
    }
}

// A frame drawn here, on the GUI thread (the view without the frame thread).
void Viewer::draw_here(const RenderOptions& opt) {
    RenderResult r;
    {
        gl::ScopedCurrent current(&gl_context());
        r = scene_.render(camera_, opt);
    }
    shown_ = screen_image(r.image);
    raytraced_drawn_ = opt.ao_image != nullptr;
    labels_ = std::move(r.labels);
    volume_stats_ = r.volume;
    if (gl_renderer_.empty()) gl_renderer_ = r.gl_renderer;
    ++frames_;
    // GL objects made after the first frame: none while the view is steady.
    const std::size_t objects = scene_.renderer().gl_objects_created();
    if (frames_ == 1) objects_after_first_frame_ = objects;
    objects_since_first_frame_ = objects - objects_after_first_frame_;
    // Cone AO accumulates still frames; the other methods are done in one
    // (cone AO standing in for ray-traced AO draws one frame: the tracer
    // gets the processors).
    const bool accumulates = opt.look.ao == AoMethod::Cone && options_.look.ao == AoMethod::Cone;
    ao_frames_ = accumulates ? r.ao_frames : 0;
    aa_frames_ = r.aa_frames;
    // Progressive AO and anti-aliasing without the thread: while the camera
    // and the scene stay still, keep drawing so new jitter sets (of the AO,
    // of the sub-pixel offset) accumulate; any interaction restarts the
    // accumulation (the renderer sees the change).
    const bool ao_more = accumulates && ao_frames_ < options_.look.ao_frames;
    const bool aa_more = opt.accumulate && aa_frames_ < options_.look.aa.view_frames;
    complete_ = !dragging_ && !ao_more && !aa_more;
    if (ao_more || aa_more) still_timer_->start(0);
}

// Input anywhere in the application (this view's own included) holds the
// still frames drawn on the GUI thread back until it has been quiet for
// input_quiet_ms_ (a frame there holds the thread for hundreds of ms). The
// still-frame thread runs below the GUI thread's priority, so it goes on
// through clicks, keys and the wheel (holding it after each input made the
// picture converge about a fifth slower, measured with gui_latency_bench,
// for the same input latency); only a drag (a move with a button held) holds
// it, whose frames need the processors.
bool Viewer::eventFilter(QObject* watched, QEvent* e) {
    switch (e->type()) {
    case QEvent::KeyPress:
    case QEvent::MouseButtonPress:
    case QEvent::MouseButtonRelease:
    case QEvent::Wheel: last_input_.restart(); break;
    case QEvent::MouseMove:
        last_input_.restart();
        if (stills_ && static_cast<QMouseEvent*>(e)->buttons() != Qt::NoButton) stills_->hold_for(input_quiet_ms_);
        break;
    default: break;
    }
    return QWidget::eventFilter(watched, e);
}

void Viewer::schedule_still_frame() {
    const qint64 quiet = last_input_.isValid() ? last_input_.elapsed() : input_quiet_ms_;
    if (quiet < input_quiet_ms_) {
        ++still_frames_held_;
        still_timer_->start(int(input_quiet_ms_ - quiet));
        return;
    }
    update();
}

void Viewer::set_camera(const Camera& c) {
    const bool moved = !(c == camera_);
    camera_ = c;
    camera_set_ = true;
    framed_empty_ = false;
    update();
    if (moved) camera_moved();
}

void Viewer::set_view(PatientView v) { set_camera(scene_.camera(v, aspect(), options_.look)); }

void Viewer::set_options(const ViewerOptions& o) {
    options_ = o;
    update();
}

QSize Viewer::image_size() const {
    const qreal dpr = devicePixelRatioF();
    return {std::max(1, int(width() * dpr)), std::max(1, int(height() * dpr))};
}

core::PickRequest Viewer::pick_request(QPointF image_pixel, PickRegion rect) const {
    if (!error_.empty()) throw Error("3D view pick", "the view cannot draw: " + error_);
    if (frames_ == 0) throw Error("3D view pick", "the view has not drawn a frame yet");
    core::PickRequest p;
    p.x = int(std::floor(image_pixel.x()));
    p.y = int(std::floor(image_pixel.y()));
    p.rect = rect;
    return p;
}

// The view's frame (camera, size, surfaces) without what the lists do not
// depend on: no AO, no overlay, and read back rather than presented, so the
// picture on screen and its AO accumulation stay as they are.
RenderOptions Viewer::pick_options(const core::PickRequest& p) {
    RenderOptions opt = frame_options();
    opt.look.ao = AoMethod::Off;
    opt.ao_image = nullptr;
    opt.accumulate = false;
    opt.annotations = nullptr;
    opt.present = false;
    opt.target_framebuffer = 0;
    opt.pick = core::pick_region(p);
    opt.image = false; // the lists are the output
    camera_.fit_planes(scene_.bounds(options_.look));
    return opt;
}

// The lists of a pick frame the thread drew from `scene`, resolved against
// the scene as it is now: they name triangles of the snapshot's meshes, so
// a mesh replaced meanwhile makes the pick stale (an error, not a wrong point).
core::PickResult Viewer::resolve(const core::SceneSnapshot& scene, const Camera& camera, const RenderOptions& opt,
                                 const PickList& list, double ms, const core::PickRequest& p) const {
    const core::SceneSnapshot now = scene_.snapshot();
    bool same = now.surfaces.size() == scene.surfaces.size();
    for (std::size_t i = 0; same && i < now.surfaces.size(); ++i) same = now.surfaces[i].mesh == scene.surfaces[i].mesh;
    if (!same) throw Error("3D view pick", "the surfaces changed while the pick was drawn: pick again");
    core::PickResult r = core::resolve_pick(scene_, camera, opt.width, opt.height, list, p, &opt.look);
    r.frame_ms = ms;
    return r;
}

core::PickResult Viewer::pick_at(QPointF image_pixel, PickRegion rect) {
    const core::PickRequest p = pick_request(image_pixel, rect);
    const auto t0 = std::chrono::steady_clock::now();
    if (!use_still_thread()) {
        const RenderOptions opt = pick_options(p); // pick_in_frame sets the pick region and image again
        gl::ScopedCurrent current(&gl_context());
        return core::pick_in_frame(scene_, camera_, opt, p);
    }
    PickJob job{scene_.snapshot(), camera_, pick_options(p), false};
    auto answer = std::make_shared<std::promise<PickFrame>>();
    std::future<PickFrame> frame = answer->get_future();
    const core::SceneSnapshot scene = job.scene;
    const Camera camera = job.camera;
    const RenderOptions opt = job.opt;
    stills_->pick(std::move(job), [answer](PickFrame f) { answer->set_value(std::move(f)); });
    const PickFrame f = frame.get(); // the thread never waits for this one: no deadlock
    if (!f.error.empty()) throw Error("3D view pick", f.error);
    return resolve(scene, camera, opt, f.list,
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(), p);
}

void Viewer::pick_later(QPointF image_pixel, PickDone done, bool hover) {
    core::PickRequest p;
    try {
        p = pick_request(image_pixel);
        if (!use_still_thread()) {
            const core::PickResult r = pick_at(image_pixel);
            done(&r, {});
            return;
        }
    } catch (const std::exception& e) {
        done(nullptr, e.what());
        return;
    }
    PickJob job{scene_.snapshot(), camera_, pick_options(p), hover};
    const auto t0 = std::chrono::steady_clock::now();
    // Back on the GUI thread through this widget's event queue (dropped
    // with the widget): resolved there, against the scene as it is then.
    auto answer = [this, p, t0, scene = job.scene, camera = job.camera, opt = job.opt,
                   done = std::move(done)](const PickFrame& f) {
        --picks_waiting_;
        if (f.replaced) return done(nullptr, {});
        try {
            if (!f.error.empty()) throw Error("3D view pick", f.error);
            const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            const core::PickResult r = resolve(scene, camera, opt, f.list, ms, p);
            done(&r, {});
        } catch (const std::exception& e) {
            done(nullptr, e.what());
        }
    };
    ++picks_waiting_;
    stills_->pick(std::move(job), [this, answer = std::move(answer)](PickFrame f) {
        QMetaObject::invokeMethod(
            this, [answer, f = std::move(f)] { answer(f); }, Qt::QueuedConnection);
    });
}

void Viewer::set_markups(std::vector<Markup> markups) {
    annotations_->markups = std::move(markups);
    ++annotations_version_;
    update();
}

void Viewer::set_guides(std::vector<Annotations::Line> lines, std::vector<glm::dvec3> points) {
    // None before and none now: no new frame (the still frames' accumulation goes on).
    if (lines.empty() && points.empty() && annotations_->lines.empty() && annotations_->points.empty()) return;
    annotations_->lines = std::move(lines);
    annotations_->points = std::move(points);
    ++annotations_version_; // the still frames' picture changed
    update();
}

void Viewer::set_sketch(std::vector<QPointF> image_pixels) {
    sketch_ = std::move(image_pixels);
    update();
}

// The outline over the picture, closed back to its start (a dashed segment): in widget pixels.
void Viewer::paint_sketch(QPainter& p) {
    if (sketch_.size() < 2) return;
    p.setRenderHint(QPainter::Antialiasing);
    QPolygonF line;
    for (const QPointF& q : sketch_) line << q / devicePixelRatioF();
    p.setPen(QPen(QColor(255, 220, 60), 2.0));
    p.drawPolyline(line);
    p.setPen(QPen(QColor(255, 220, 60), 1.5, Qt::DashLine));
    p.drawLine(line.back(), line.front());
}

void Viewer::set_labels(std::vector<std::pair<glm::dvec3, std::string>> labels) {
    annotations_->labels.clear();
    ++annotations_version_;
    for (auto& [at, text] : labels) annotations_->labels.push_back({at, std::move(text)});
    update();
}

std::optional<QPointF> Viewer::image_pixel(const glm::dvec3& lps) const {
    const QSize size = image_size();
    const double aspect = double(size.width()) / double(size.height());
    // The overlay's projection (build_overlay): clip space to image pixels, y down.
    const glm::dvec4 c = camera_.projection(aspect) * camera_.view() * glm::dvec4(lps, 1.0);
    if (c.w <= 0) return std::nullopt;
    return QPointF((c.x / c.w + 1) * 0.5 * size.width(), (1 - c.y / c.w) * 0.5 * size.height());
}

QPointF Viewer::to_image(QPointF widget) const { return widget * devicePixelRatioF(); }

void Viewer::mousePressEvent(QMouseEvent* e) {
    drag_.start(e->position());
    grabbing_ = e->button() == Qt::LeftButton && e->buttons() == Qt::LeftButton && on_press &&
                on_press(*this, to_image(e->position()));
}

void Viewer::mouseReleaseEvent(QMouseEvent* e) {
    if (grabbing_ && e->button() == Qt::LeftButton) {
        grabbing_ = false;
        if (on_grab_release) on_grab_release(*this, to_image(e->position()), drag_.dragged);
    }
    if (e->button() == Qt::LeftButton && !drag_.dragged && on_click) on_click(*this, to_image(e->position()));
    if (dragging_ && e->buttons() == Qt::NoButton) {
        dragging_ = false;
        // The still frames, with AO again: the end of the view's own drag
        // does not hold them back (the user waits for them now).
        if (stills_) stills_->release_hold();
        update();
    }
}

void Viewer::mouseMoveEvent(QMouseEvent* e) {
    if (e->buttons() == Qt::NoButton) {
        if (on_hover) on_hover(*this, to_image(e->position()));
        return;
    }
    if (!drag_.follow(e->position())) return;
    if (grabbing_) { // a markup point follows the pointer; the camera stays
        if (on_grab_move) on_grab_move(*this, to_image(e->position()));
        return;
    }
    if (!dragging_ && has_massive_surface()) drag_pacing_.start(last_thread_ms_, still_id_);
    dragging_ = true;
    const QPointF d = drag_.step(e->position());
    // 3D Slicer's mouse: left rotates, middle pans, right drags zoom (up: closer).
    if (e->buttons() & Qt::LeftButton)
        camera_.orbit(-0.4 * d.x(), -0.4 * d.y());
    else if (e->buttons() & Qt::MiddleButton)
        camera_.pan(double(d.x()) / height(), double(d.y()) / height());
    else if (e->buttons() & Qt::RightButton)
        camera_.zoom(core::drag_zoom_factor(-double(d.y()), height()));
    update();
    camera_moved();
}

// A visible surface drawn by clusters and stand-ins (LodSettings::
// min_triangles): where a drag starts paced from slow still frames. Slow
// still frames of a small scene (ray-traced AO, a volume) say nothing of
// its drag frames, which stay at full size and detail.
bool Viewer::has_massive_surface() const {
    const auto snapshot = scene_.snapshot();
    for (const auto& s : snapshot.surfaces)
        if (s.mesh && s.object.visible && s.mesh->triangles.size() >= options_.look.lod.min_triangles) return true;
    return false;
}

void Viewer::wheelEvent(QWheelEvent* e) {
    camera_.zoom(std::pow(1.0015, e->angleDelta().y()));
    update();
    camera_moved();
}

void Viewer::keyPressEvent(QKeyEvent* e) {
    static const std::pair<int, PatientView> keys[] = {
        {Qt::Key_A, PatientView::Anterior}, {Qt::Key_P, PatientView::Posterior}, {Qt::Key_L, PatientView::Left},
        {Qt::Key_R, PatientView::Right},    {Qt::Key_S, PatientView::Superior},  {Qt::Key_I, PatientView::Inferior}};
    if (e->key() == Qt::Key_O) { // ambient occlusion on (the method it had, cone at first) / off
        if (options_.look.ao != AoMethod::Off) ao_when_on_ = options_.look.ao;
        options_.look.ao = options_.look.ao == AoMethod::Off ? ao_when_on_ : AoMethod::Off;
        update();
        if (on_options_changed) on_options_changed(*this);
        return;
    }
    for (auto [k, v] : keys)
        if (e->key() == k) {
            set_view(v);
            return;
        }
    QWidget::keyPressEvent(e);
}

} // namespace iso::gui
