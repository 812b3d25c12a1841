// The 3D view of `isoscope view`: a core::Scene's frames, drawn by the
// renderer off screen (on the frame thread, StillFrames) and painted into a
// plain widget. Presentation only: the scene, its surfaces and the renderer
// are the core's (renderer/core/scene.hpp); the widget owns the camera and
// the interaction.
//
// Not a QOpenGLWidget: one of those in a window makes Qt compose the whole
// window through OpenGL, so every repaint of any widget in it (a label's
// text, a progress dialog closing over it) went through a texture upload
// and a swap; on llvmpipe under X that held the GUI thread 45-180 ms a
// repaint (gui_massive_bench, docs/lod.md "What the stalls are"). The
// frames are read back anyway (the frame thread has its own context), so
// the window stays raster-composed and the view paints them as images.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <QElapsedTimer>
#include <QImage>
#include <QWidget>

#include <glm/vec3.hpp>

#include "io/markups.hpp"
#include "app/gui/pointer_drag.hpp"
#include "renderer/core/drag_pacing.hpp"
#include "renderer/ao/progressive.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"

namespace iso {
struct RenderOptions;
namespace core {
class Scene;
class Workspace;
struct PickRequest;
struct PickResult;
struct SceneSnapshot;
} // namespace core
} // namespace iso

class QPainter;
class QTimer;

namespace iso::gl {
class HeadlessContext;
}

namespace iso::gui {

class RaytracedRefiner;
struct RaytracedBatch;
class StillFrames;
struct StillFrame;

// The 3D view's look is a frame's (FrameLook: cone AO on, 16 still frames
// by default; key O toggles AO between off and cone), plus how it behaves
// while the camera moves. With ray-traced AO the still frames refine it on
// worker threads (to the look's ao_error, 0.02 by default here) and the
// frames that wait for its first batch, or move, use cone AO.
struct ViewerOptions {
    FrameLook look = interactive_look();
    // AO in the frames drawn while a mouse drag moves the camera (off: those
    // frames go without it and the still frames after the release bring it back).
    bool ao_while_dragging = false;
    // Frames drawn on a thread of their own (StillFrames): the still frames
    // (AO, anti-aliasing) and a drag's frames; the GUI thread paints the
    // newest one that arrived (the background before the first); off: drawn
    // on the GUI thread between events, in a context of the view's own (the
    // way to compare, and the fallback when that thread has no GL context).
    bool still_thread = true;
    // The legend in the overlay: the visible surfaces' names, colours,
    // opacities and iso values (core/legend.hpp), as exports draw it.
    bool legend = true;

    static FrameLook interactive_look() {
        FrameLook l;
        l.ao = AoMethod::Cone;
        l.ao_frames = 16;  // still frames accumulating new jitter sets while nothing moves
        l.ao_error = 0.02; // ray-traced AO: the standard error a still view refines to
        return l;
    }
};

class Viewer : public QWidget {
public:
    // The 3D view of the workspace's scene (the workspace, and that scene,
    // must outlive the widget). The camera it draws with is the workspace's:
    // each move of its own goes there.
    explicit Viewer(core::Workspace& workspace, PatientView view, ViewerOptions options = {},
                    QWidget* parent = nullptr);
    ~Viewer() override;
    int frames() const { return frames_; }
    // True once the picture stopped changing: no cone AO, or its still
    // frames all accumulated; ray-traced AO: its last batch drawn; and the
    // anti-aliasing's still frames all accumulated.
    bool converged() const;
    int ao_frames() const { return ao_frames_; }
    int aa_frames() const { return aa_frames_; }
    // Ray-traced AO: the image the last frame was lit with (null: none yet,
    // cone AO stood in) and how far its refinement got.
    const Image* raytraced_ao() const { return raytraced_drawn_ ? raytraced_.get() : nullptr; }
    const ProgressiveAoStats& raytraced_stats() const { return raytraced_stats_; }
    // A mouse drag is moving the camera now.
    bool dragging() const { return dragging_; }
    // The still frames that accumulate AO and anti-aliasing wait while the
    // user works anywhere in the application: after any key, button, wheel
    // or pointer move (an application-wide event filter) the next one waits
    // until the input has been quiet this long (a still frame takes
    // hundreds of milliseconds on a software GL and holds the GUI thread;
    // the input keeps the processors meanwhile). 0: no waiting.
    static constexpr int kInputQuietMs = 300;
    void set_input_quiet_ms(int ms) { input_quiet_ms_ = ms; }
    // Still frames held back by input so far.
    int still_frames_held() const;
    // Frames the still-frame thread delivered and this view showed (0 with
    // ViewerOptions::still_thread off), and the last one's render time.
    int thread_frames() const { return thread_frames_; }
    double last_thread_frame_ms() const { return last_thread_ms_; }
    // GL objects the renderer drawing the view (the frame thread's, with it)
    // made after its first frame (0 in a steady view: resources live across frames).
    std::size_t gl_objects_since_first_frame() const { return objects_since_first_frame_; }
    // The volume's ray casting in the frame on screen (VolumeStats::drawn:
    // the volume was drawn).
    const VolumeStats& volume_stats() const { return volume_stats_; }
    // The last rendering error (empty: none). A paint never lets one escape:
    // it shows the background, reports it here and on stderr, and stops.
    const std::string& error() const { return error_; }
    // The GL renderer and version the view draws with (empty before its first frame).
    const std::string& gl_renderer() const { return gl_renderer_; }

    // The camera the view draws with (LPS mm); setting it redraws. Until it
    // is set, a view that first drew only empty surfaces frames the first
    // ones that are not, once they appear (the view's direction kept).
    const Camera& camera() const { return camera_; }
    void set_camera(const Camera& c);
    // The view's patient-view framing (as `isoscope render --view`), fitted to the widget.
    void set_view(PatientView v);
    // Frames the camera as the next paint would (the first paint's framing;
    // surfaces that appeared after only empty ones were drawn), now: the
    // 3D view calls it when surfaces join, so that the workspace's camera
    // (what a session saves, what an export draws) is the framed one at once.
    void frame_now();
    const ViewerOptions& options() const { return options_; }
    void set_options(const ViewerOptions& o);

    // A left click (press and release within a few pixels, no drag) and the
    // pointer moving with no button held, at the image pixel (device pixels
    // from the top-left, the pixel render_image / core::pick use).
    std::function<void(Viewer&, QPointF)> on_click;
    std::function<void(Viewer&, QPointF)> on_hover;
    // A left press: true when the handler takes it (a markup point grabbed).
    // Then the moves until the release go to on_grab_move and the release to
    // on_grab_release (`dragged`: the pointer went beyond the click slop;
    // a release without a drag is also a click), and the camera stays.
    std::function<bool(Viewer&, QPointF)> on_press;
    std::function<void(Viewer&, QPointF)> on_grab_move;
    std::function<void(Viewer&, QPointF, bool dragged)> on_grab_release;
    // The view changed its own options (the O key toggled AO), so a tool bar can follow.
    std::function<void(Viewer&)> on_options_changed;
    // The size of the image the view draws (device pixels).
    QSize image_size() const;

    // What the view shows at an image pixel (as on_click / on_hover give
    // it): core::pick_in_frame on a frame of the view's own (its camera,
    // size and surfaces; its context, the scene staying uploaded), without
    // AO and overlay and not presented: the picture and its AO
    // accumulation stay. Throws iso::Error: a pixel outside the image, a
    // view that has not drawn yet or failed to.
    // With the frame thread (ViewerOptions::still_thread), the pick's frame
    // is drawn there, on its GPU copy of the scene (this view's context
    // holds none), and this thread waits for it and resolves its lists.
    // With `rect` (image pixels, not empty), every triangle visible in it is
    // listed too (PickResult::triangles).
    core::PickResult pick_at(QPointF image_pixel, PickRegion rect = {0, 0, 0, 0});
    // The same pick, answered later: `done` runs on the GUI thread with the
    // result, or with null and why there is none. The GUI thread does not
    // wait for the pick's frame (a hover's or a click's: on a 32 M-triangle
    // surface it would hold the input). A `hover` pick waiting to be drawn
    // is replaced by a newer one (`done` is then called with null and an
    // empty reason). Without the frame thread it is drawn here, and `done`
    // runs before this returns.
    using PickDone = std::function<void(const core::PickResult*, const std::string& error)>;
    void pick_later(QPointF image_pixel, PickDone done, bool hover = false);
    // pick_later picks not answered yet.
    int picks_waiting() const { return picks_waiting_; }
    // Markups (LPS mm) drawn over the view by the renderer's overlay, as
    // `isoscope render --markups` draws them.
    void set_markups(std::vector<Markup> markups);
    // Lines (each in its colour) and points (LPS mm) drawn over the view by
    // the overlay: the slice planes' outlines and the crosshair (View >
    // Slice planes in 3D). Empty: none.
    void set_guides(std::vector<Annotations::Line> lines, std::vector<glm::dvec3> points);
    // An outline being drawn on the view (image pixels; the Scissors
    // tool's), painted over the picture at once (not part of any frame or
    // export). Empty: none.
    void set_sketch(std::vector<QPointF> image_pixels);
    // Text drawn by the overlay next to LPS points (the markups' names).
    void set_labels(std::vector<std::pair<glm::dvec3, std::string>> labels);
    // The overlay's labels as the last frame placed them (boxes in image
    // pixels, their masks): what a test reads the window's contrast with.
    const std::vector<LabelBox>& drawn_labels() const { return labels_; }
    // Where `lps` projects in the image (as the overlay draws it, image
    // pixels from the top-left); none behind the eye.
    std::optional<QPointF> image_pixel(const glm::dvec3& lps) const;

    // The picture on screen (image pixels; null before the first frame):
    // the last frame shown, without the sketch.
    const QImage& picture() const { return shown_; }

protected:
    void paintEvent(QPaintEvent* e) override;
    void initialize();
    void draw();
    void frame_camera();
    void draw_here(const RenderOptions& opt);
    bool show_still(const RenderOptions& opt);
    bool show_latest();
    void show_frame(const StillFrame& f, const RenderOptions& opt);
    std::vector<double> frame_key(const RenderOptions& opt) const;
    void camera_moved();
    RenderOptions frame_options() const;
    void mousePressEvent(QMouseEvent* e) override;
    void mouseMoveEvent(QMouseEvent* e) override;
    void mouseReleaseEvent(QMouseEvent* e) override;
    void wheelEvent(QWheelEvent* e) override;
    void keyPressEvent(QKeyEvent* e) override;
    bool eventFilter(QObject* watched, QEvent* e) override;

private:
    core::Workspace& workspace_;
    core::Scene& scene_; // the workspace's (a new scene: a new viewer)
    PatientView initial_view_;
    ViewerOptions options_;
    std::string error_;
    std::string gl_renderer_;
    std::unique_ptr<Annotations> annotations_;
    Camera camera_;
    bool camera_set_ = false;
    bool framed_empty_ = false; // framed before any visible surface had a triangle
    PointerDrag drag_;
    bool grabbing_ = false; // on_press took the press
    bool dragging_ = false; // a drag is moving the camera (AO may wait, ViewerOptions::ao_while_dragging)
    QPointF to_image(QPointF widget) const;
    double aspect() const;
    int frames_ = 0;
    int ao_frames_ = 0;
    int aa_frames_ = 0;
    std::size_t objects_after_first_frame_ = 0, objects_since_first_frame_ = 0;
    std::vector<LabelBox> labels_;
    VolumeStats volume_stats_;
    // Ray-traced AO: the refiner's latest batch for the view as it is.
    std::unique_ptr<RaytracedRefiner> refiner_;
    std::shared_ptr<const Image> raytraced_;
    ProgressiveAoStats raytraced_stats_;
    bool raytraced_drawn_ = false;         // the last frame was lit with raytraced_
    std::uint64_t raytraced_version_ = 0;  // batches taken so far
    AoMethod ao_when_on_ = AoMethod::Cone; // what the O key turns AO back on with
    void follow_raytraced();
    void take_batch(const RaytracedBatch& b);
    // The next still frame: now, or when the input has been quiet input_quiet_ms_.
    void schedule_still_frame();
    QTimer* still_timer_ = nullptr;
    QElapsedTimer last_input_;
    int input_quiet_ms_ = kInputQuietMs;
    int still_frames_held_ = 0;
    // The picture stopped changing (Viewer::converged's test, with the
    // ray-traced AO's own).
    bool complete_ = false;
    // Still frames on their own thread: what was asked of it (key and look
    // of the view it is for), its latest frame for that, the picture on screen.
    std::unique_ptr<StillFrames> stills_;
    bool stills_failed_ = false;
    std::uint64_t still_id_ = 0;
    std::vector<double> still_key_;
    FrameLook still_look_;
    std::shared_ptr<const StillFrame> still_;
    // The newest frame the thread drew, whatever it was asked for: shown
    // while the frame asked for is on its way (a drag's camera has moved on,
    // a still frame for a new look is being drawn), instead of a frame drawn
    // here on the GUI thread.
    std::shared_ptr<const StillFrame> latest_;
    std::uint64_t latest_shown_ = 0; // the request of the newest frame on screen
    // A drag's frames on the frame thread: their size and level of detail,
    // from the frames' own times (core::DragPacing).
    core::DragPacing drag_pacing_;
    std::uint64_t annotations_version_ = 0;
    std::vector<QPointF> sketch_;
    void paint_sketch(QPainter& p);
    bool initialized_ = false; // the first paint framed the camera
    QImage shown_;             // the picture on screen (null: the background)
    // Frames and picks drawn here, on the GUI thread (without the frame
    // thread): a headless context of the view's own, made on first use.
    std::unique_ptr<gl::HeadlessContext> context_;
    gl::HeadlessContext& gl_context();
    std::size_t thread_objects_first_ = 0; // the frame thread's GL objects after its first frame
    int thread_frames_ = 0;
    double last_thread_ms_ = 0;
    int picks_waiting_ = 0;
    bool use_still_thread();
    void take_still(const StillFrame& f);
    bool has_massive_surface() const;
    // The frame a pick rides on: the view's, without AO and overlay, not presented.
    RenderOptions pick_options(const core::PickRequest& p);
    core::PickRequest pick_request(QPointF image_pixel, PickRegion rect = {0, 0, 0, 0}) const;
    core::PickResult resolve(const core::SceneSnapshot& scene, const Camera& camera, const RenderOptions& opt,
                             const PickList& list, double ms, const core::PickRequest& p) const;
};

} // namespace iso::gui
