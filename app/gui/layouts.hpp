// View > Layout (3D Slicer's Four-Up, Conventional and One-Up layouts) and
// View > Slice planes in 3D (Slicer's slice intersections in the 3D view),
// docs/gui.md "Layouts". The layout is the workspace's (a session keeps
// it): its menu entries set it, and the views follow it. A layout moves the
// four views between the cells of the central grid and shows or hides them:
// nothing is made again, so the 3D view keeps its frame thread (with its
// GL context and the scene on its GPU), its camera and its accumulated AO,
// and each slice view its plane.
#pragma once

#include <array>
#include <optional>

#include <QObject>

#include "renderer/core/session.hpp"

class QAction;
class QGridLayout;
class QMenu;
class QWidget;

namespace iso::gui {

class AppContext;

class Layouts : public QObject {
public:
    // `cells`: the 3D view's and the axial, coronal and sagittal views' widgets in `grid`.
    Layouts(AppContext& context, QGridLayout* grid, std::array<QWidget*, 4> cells);
    ~Layouts() override;
    QMenu* menu() const { return menu_; }
    QAction* layout_action(core::ViewLayout l) const { return actions_[std::size_t(l)]; }
    QAction* slice_planes_action() const { return slice_planes_; }

private:
    void arrange();
    AppContext& context_;
    QGridLayout* grid_;
    std::array<QWidget*, 4> cells_;
    QMenu* menu_ = nullptr;
    std::array<QAction*, 6> actions_{};
    QAction* slice_planes_ = nullptr;
    std::optional<core::ViewLayout> shown_;
    int observer_ = 0;
};

} // namespace iso::gui
