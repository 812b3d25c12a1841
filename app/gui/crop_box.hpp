// Dragging the crop box (docs/gui.md "Volume panel"), as 3D Slicer's ROI
// widget: while cropping, each slice view draws the box's section with its
// plane in orange (the colour of the box's edges in the 3D view) and a side
// of it can be dragged; the 3D view draws a handle at the centre of each of
// the box's six faces (View3D's guides) and a handle can be dragged along
// its face's axis (the point of that axis nearest the ray under the
// pointer). The face follows the pointer, never past the opposite face, the
// Volume panel's numbers follow, and the release is one undo step ("Move
// crop box L min"). The geometry is the core's (core::plane_box_section,
// core::lps_to_pixel, core::pixel_to_lps, Camera::pixel_ray); the box is the
// workspace's look.
#pragma once

#include <optional>
#include <utility>
#include <vector>

#include <QObject>
#include <QPointF>

#include "renderer/frame/frame.hpp"

namespace iso::gui {

class AppContext;
class SliceView;
class Viewer;

class CropBoxTool : public QObject {
public:
    explicit CropBoxTool(AppContext& context);
    ~CropBoxTool() override;
    // Draws the box on `view` and takes presses near its sides (after the
    // tools added before it).
    void attach(SliceView& view);
    // Takes presses near the face handles of the 3D view (after the hooks
    // set on it before: a markup point is grabbed first).
    void attach(Viewer& viewer);
    // How near (pixels) a press must be to a side, or to a handle in 3D, to grab it.
    static constexpr double kGrabRadiusPx = 6;
    static constexpr double kHandleRadiusPx = 9;
    // The face being dragged: axis 0..2 (L, P, S) and its end (min or max).
    struct Face {
        int axis = 0;
        bool max = false;
    };
    std::optional<Face> dragging() const;
    // The centres of the box's six faces (the 3D view's handles), L min first.
    static std::vector<std::pair<Face, glm::dvec3>> face_centres(const std::pair<glm::dvec3, glm::dvec3>& box);

private:
    bool press(SliceView& view, QPointF pixel);
    void move(SliceView& view, QPointF pixel);
    void release(SliceView& view, QPointF pixel, bool dragged);
    bool press_3d(Viewer& v, QPointF pixel);
    void move_3d(Viewer& v, QPointF pixel);
    // The grabbed face at `value` (clamped to the opposite face), shown at once.
    void move_face(double value);
    void finish();
    AppContext& context_;
    struct Grab {
        Face face;
        FrameLook before; // the look at the press: what Undo restores
    };
    std::optional<Grab> grab_;
    int observer_ = 0;
};

} // namespace iso::gui
