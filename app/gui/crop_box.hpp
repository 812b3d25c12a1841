// The crop box on the slice views (docs/gui.md "Volume panel"): while
// cropping, each view draws the box's section with its plane in orange (the
// colour of the box's edges in the 3D view), and a side of that section can
// be dragged: the box's face it lies on follows the pointer (never past the
// opposite face), the Volume panel's numbers follow, and the release is one
// undo step ("Move crop box L min"). The geometry is the core's
// (core::plane_box_section, core::lps_to_pixel, core::pixel_to_lps); the box
// is the workspace's look.
#pragma once

#include <optional>

#include <QObject>
#include <QPointF>

#include "renderer/frame/frame.hpp"

namespace iso::gui {

class AppContext;
class SliceView;

class CropBoxOnSlices : public QObject {
public:
    explicit CropBoxOnSlices(AppContext& context);
    ~CropBoxOnSlices() override;
    // Draws the box on `view` and takes presses near its sides (after the
    // tools added before it).
    void attach(SliceView& view);
    // How near (pixels) a press must be to a side to grab it.
    static constexpr double kGrabRadiusPx = 6;
    // The face being dragged: axis 0..2 (L, P, S) and its end (min or max).
    struct Face {
        int axis = 0;
        bool max = false;
    };
    std::optional<Face> dragging() const;

private:
    bool press(SliceView& view, QPointF pixel);
    void move(SliceView& view, QPointF pixel);
    void release(SliceView& view, QPointF pixel, bool dragged);
    AppContext& context_;
    struct Grab {
        Face face;
        FrameLook before; // the look at the press: what Undo restores
    };
    std::optional<Grab> grab_;
    int observer_ = 0;
};

} // namespace iso::gui
