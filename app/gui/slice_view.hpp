// One slice view of the main window (docs/gui.md): paints the
// volume resliced on its plane through the window (core::reslice,
// core::apply_window), the surfaces' outlines (core::mesh_outline), the
// crosshair, the patient directions at its edges (core::slice_edge_letter),
// a scale bar (core::slice_scale_bar_mm) and the hover probe's readout
// (core::sample_at_pixel). Its plane, the crosshair and the window/level
// are the workspace's: the view shows them, follows their changes, and its
// own gestures (pan, zoom, fit, scroll, a window drag) change them there.
// The geometry is the core's (renderer/core/slices.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <QColor>
#include <QImage>
#include <QPainter>
#include <QString>
#include <QWidget>

#include "app/gui/pointer_drag.hpp"
#include "renderer/core/slices.hpp"

namespace iso {
class Volume;
namespace core {
class Scene;
class Workspace;
} // namespace core
} // namespace iso

namespace iso::gui {

class SliceView : public QWidget {
public:
    SliceView(core::SliceOrientation orientation, QWidget* parent = nullptr);

    ~SliceView() override;
    // What to show: the workspace's scene (its volume and visible surfaces),
    // this view's plane of its planes, and its window/level (null: nothing).
    // The view follows the workspace's changes from then on.
    void set_workspace(core::Workspace* workspace);
    // Recomputes the image and outlines from the plane (the workspace's
    // changes call it). Above kInlineTriangles in the visible surfaces the
    // outlines are worked out on a pool thread and painted when they come
    // (outlines_waiting()): the GUI thread never scans a 30 M-triangle
    // surface per slice step.
    void refresh();
    static constexpr std::size_t kInlineTriangles = 2'000'000;
    void set_inline_triangles(std::size_t n) { inline_triangles_ = n; } // tests: 0 sends every outline to the pool
    // Above kInlineVoxels the slice itself is resliced on a pool thread too
    // (the newest plane next) and shown when it comes (slice_waiting()): on
    // a 1024^3 volume a view's slice is 100-150 ms of cache misses, and a
    // ruler's click moves the crosshair, so all three views' slices. The
    // slice shown before stays meanwhile (has_image(), image()), painted
    // where its pixels lie on the new grid when the planes are parallel
    // (a scroll, a pan, a zoom; a slice of a volume no longer open goes).
    static constexpr std::size_t kInlineVoxels = std::size_t(1) << 24;
    void set_inline_voxels(std::size_t n) { inline_voxels_ = n; } // tests: 0 sends every slice to the pool
    bool slice_waiting() const { return reslicing_ || pending_slice_; }
    // The outlines alone, on the slice shown (the surfaces changed, not the
    // plane, the volume or the window: the image stays).
    void refresh_outlines();
    bool outlines_waiting() const { return outlining_ || pending_outlines_; }
    // Keeps the plane's framing (centre and pixel size) as it is, through
    // resizes too, as after a pan or zoom (a session restored it); until
    // then, and again with new data, a resize fits the plane's field of
    // view to the view.
    void keep_framing();
    // Scrolls `steps` slices (the wheel, PageUp/PageDown, the slider): the
    // plane moves along its normal and the other views' crosshair follows.
    void scroll(double steps);

    core::SliceOrientation orientation() const { return orientation_; }
    // The view's grid (one image pixel per widget pixel): the plane's, what
    // clicks, outlines and overlays use; valid after refresh with content.
    const core::SliceGrid& grid() const { return grid_; }
    // The grid image() was resliced on: grid() unless a slice is on its way.
    const core::SliceGrid& image_grid() const { return image_grid_; }
    const core::Scene* scene() const;
    const core::SlicePlane* plane() const;
    // Fit: re-centres on the volume and zooms to fit (core::fit_view; key F
    // or a left double-click), keeping the slice and the crosshair.
    void fit();

    // What the view draws over the slice (empty without an image): the
    // letter at each edge (core::SliceEdge order: left, right, top, bottom),
    // the scale bar's length in mm and in pixels, and the hover probe's
    // readout (slice_readout of the pixel under the pointer; empty while the
    // pointer is elsewhere).
    QString edge_letter(core::SliceEdge e) const;
    double scale_bar_mm() const;
    double scale_bar_pixels() const;
    const QString& probe_text() const { return probe_; }
    bool has_image() const { return !image_.isNull(); }
    const QImage& image() const { return image_; }
    std::size_t outline_segments() const;

    // A left click (press and release within a few pixels, no drag) at
    // continuous pixel coordinates.
    std::function<void(SliceView&, QPointF)> on_click;
    // What a left press may grab (a markup point, a crop box edge): `press`
    // returns true when it takes the press; then the moves until the
    // release go to its `move` (no window drag) and the release to its
    // `release` (`dragged`: beyond the click slop; a release without a drag
    // is also a click). Asked in the order added.
    struct Grabber {
        std::function<bool(SliceView&, QPointF)> press;
        std::function<void(SliceView&, QPointF)> move;
        std::function<void(SliceView&, QPointF, bool dragged)> release;
    };
    void add_grabber(Grabber g) { grabbers_.push_back(std::move(g)); }
    // Drawn over the slice after the outlines and the crosshair (the
    // measurements, the crop box), in the order added; the painter's
    // coordinates are the grid's pixels.
    void add_overlay(std::function<void(SliceView&, QPainter&)> paint) { overlays_.push_back(std::move(paint)); }
    // After each refresh (the plane may have moved: a slider follows).
    std::function<void(SliceView&)> on_refresh;

    // A surface's outline on the slice, in its colour.
    struct Outline {
        std::vector<core::SliceSegment> segments;
        QColor color;
    };

protected:
    void paintEvent(QPaintEvent*) override;
    void resizeEvent(QResizeEvent*) override;
    void mousePressEvent(QMouseEvent* e) override;
    void mouseMoveEvent(QMouseEvent* e) override;
    void mouseReleaseEvent(QMouseEvent* e) override;
    void wheelEvent(QWheelEvent* e) override;
    void keyPressEvent(QKeyEvent* e) override;
    void mouseDoubleClickEvent(QMouseEvent* e) override;
    void leaveEvent(QEvent* e) override;

private:
    struct OutlineJob;
    // The visible surfaces' outlines on the current grid: now, or (large
    // surfaces) on a pool thread, one at a time, the newest request next.
    void request_outlines();
    void drop_outlines(); // the outlines shown and asked for go
    void start_outlines();
    std::shared_ptr<OutlineJob> pending_outlines_;
    bool outlining_ = false;
    std::size_t inline_triangles_ = kInlineTriangles;
    std::uint64_t outline_generation_ = 0;
    struct SliceJob;
    // The slice on the current grid: now, or (large volumes) on a pool
    // thread, one at a time per view, the newest request next.
    void request_slice();
    void start_slice();
    void drop_slice();                             // no slice shown or asked for
    void show_values(const core::SliceGrid& grid); // values_ through the window: the image shown
    std::shared_ptr<SliceJob> pending_slice_;
    bool reslicing_ = false;
    std::size_t inline_voxels_ = kInlineVoxels;
    std::uint64_t slice_generation_ = 0;
    // The plane changed by the view's own gesture: into the workspace.
    void set_plane(const core::SlicePlane& p);
    void set_window(const core::WindowLevel& w);
    core::SliceOrientation orientation_;
    core::Workspace* workspace_ = nullptr;
    int observer_ = 0;
    core::WindowLevel window_;
    bool fitted_ = false;
    bool user_framed_ = false; // panned, zoomed or restored: resizes keep the framing
    double fit_pixel_mm_ = 0;  // the pixel size this view's last fit gave
    core::SliceGrid grid_;
    core::SliceGrid image_grid_; // what values_ and image_ were resliced on
    core::SliceImage values_;
    std::vector<std::uint8_t> grey_;
    QImage image_;
    std::vector<Outline> outlines_;
    QImage outline_image_; // outlines_ painted by the pool thread (large surfaces), else null
    double wheel_ = 0;     // accumulated angle delta (touchpads send fractions of a notch)
    // A drag (3D Slicer's slice view): left window/level, middle pan, right
    // zoom (core::pan_pixels, core::zoom_about on the plane's framing).
    PointerDrag drag_;
    std::vector<Grabber> grabbers_;
    std::vector<std::function<void(SliceView&, QPainter&)>> overlays_;
    const Grabber* grabbing_ = nullptr; // the grabber that took the press
    core::WindowLevel window_at_press_;
    std::optional<ValueRange> range_; // the volume's, for the window drag's gain (computed once per content)
    std::optional<QPointF> hover_;    // the pointer over the view, no button held
    QString probe_;                   // the readout at hover_
    bool swallow_release_ = false;    // a left double-click fitted: its release is no click
    void update_probe();
    void paint_annotations(QPainter& p) const;
};

// The readout of a point of a slice view, as a click and the hover probe
// write it: "LPS (x, y, z) mm, READOUT, voxel (i, j, k)" (READOUT:
// core::value_readout in core::value_unit's unit), or "LPS (x, y, z) mm,
// outside the volume"; the point is core::pixel_to_lps of the continuous
// pixel, the value and voxel core::sample_at_pixel's.
QString slice_readout(const Volume& v, const core::SliceGrid& g, QPointF pixel);

// Linear RGB (the scene's surface colours) -> an sRGB QColor, and back,
// through the one sRGB pair (io/color.hpp): a colour picked as #rrggbb is
// saved in a session, and typed on the CLI, as the same #rrggbb.
QColor to_qcolor(const glm::vec3& linear);
glm::vec3 from_qcolor(const QColor& c);

} // namespace iso::gui
