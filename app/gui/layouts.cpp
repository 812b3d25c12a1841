// View > Layout (3D Slicer's Four-Up, Conventional and One-Up layouts) and
// View > Slice planes in 3D (Slicer's slice intersections in the 3D view).
// Part of MainWindow (main_window.hpp, docs/gui.md "Layouts"). A layout
// moves the four views between the cells of the central grid and shows or
// hides them: nothing is made again, so the 3D view keeps its GL context
// (re-parenting a QOpenGLWidget would make a new one), its camera and its
// accumulated AO, and each slice view its plane.
#include <QAction>
#include <QActionGroup>
#include <QGridLayout>
#include <QMenu>
#include <QStackedWidget>

#include <array>
#include <vector>

#include "app/gui/main_window.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/slices.hpp"

namespace iso::gui {

namespace {

struct LayoutEntry {
    core::ViewLayout layout;
    const char* text;
    const char* tip;
    Qt::Key key; // with Ctrl
};

// Slicer's names for them (its layout menu: "Four-Up", "Conventional",
// "3D only", "Red slice only", ...), the slice views named by orientation.
const LayoutEntry kLayouts[] = {
    {core::ViewLayout::FourUp, "&Four-Up (2 x 2)", "The 3D view and the three slice views in a 2 x 2 grid", Qt::Key_1},
    {core::ViewLayout::Conventional, "&Conventional",
     "The 3D view large above, the axial, coronal and sagittal views in a row below", Qt::Key_2},
    {core::ViewLayout::ThreeD, "&3D only", "The 3D view alone", Qt::Key_3},
    {core::ViewLayout::Axial, "&Axial only", "The axial slice view alone", Qt::Key_4},
    {core::ViewLayout::Coronal, "C&oronal only", "The coronal slice view alone", Qt::Key_5},
    {core::ViewLayout::Sagittal, "&Sagittal only", "The sagittal slice view alone", Qt::Key_6},
};

// Where a layout puts the views (0: the 3D view, 1 to 3: axial, coronal,
// sagittal) in the central grid, and the stretch of its rows and columns.
struct Cell {
    int view, row, column, rows, columns;
};
struct Arrangement {
    std::vector<Cell> cells;
    std::array<int, 3> row_stretch, column_stretch;
};

Arrangement arrangement(core::ViewLayout l) {
    switch (l) {
    case core::ViewLayout::FourUp: // 3D top left, axial top right, coronal and sagittal below
        return {{{0, 0, 0, 1, 1}, {1, 0, 1, 1, 1}, {2, 1, 0, 1, 1}, {3, 1, 1, 1, 1}}, {1, 1, 0}, {1, 1, 0}};
    case core::ViewLayout::Conventional: // Slicer's: the 3D view across the top, twice as tall as the slices' row
        return {{{0, 0, 0, 1, 3}, {1, 1, 0, 1, 1}, {2, 1, 1, 1, 1}, {3, 1, 2, 1, 1}}, {2, 1, 0}, {1, 1, 1}};
    case core::ViewLayout::ThreeD: return {{{0, 0, 0, 1, 1}}, {1, 0, 0}, {1, 0, 0}};
    case core::ViewLayout::Axial: return {{{1, 0, 0, 1, 1}}, {1, 0, 0}, {1, 0, 0}};
    case core::ViewLayout::Coronal: return {{{2, 0, 0, 1, 1}}, {1, 0, 0}, {1, 0, 0}};
    case core::ViewLayout::Sagittal: return {{{3, 0, 0, 1, 1}}, {1, 0, 0}, {1, 0, 0}};
    }
    return arrangement(core::ViewLayout::FourUp);
}

} // namespace

core::ViewLayout MainWindow::layout() const { return core::ViewLayout(layout_); }

QAction* MainWindow::layout_action(core::ViewLayout l) const { return layout_actions_[std::size_t(l)]; }

bool MainWindow::slice_planes_in_3d() const { return slice_planes_3d_ && slice_planes_3d_->isChecked(); }

void MainWindow::set_slice_planes_in_3d(bool on) { slice_planes_3d_->setChecked(on); }

void MainWindow::add_layout_actions(QMenu* view) {
    layout_menu_ = new QMenu("&Layout", this);
    layout_menu_->setObjectName("layout_menu");
    layout_menu_->setToolTipsVisible(true);
    view->setToolTipsVisible(true);
    auto* group = new QActionGroup(this);
    for (const auto& e : kLayouts) {
        auto* a = new QAction(e.text, this);
        a->setObjectName(QString("layout_") + core::view_layout_name(e.layout));
        a->setToolTip(e.tip);
        a->setStatusTip(e.tip);
        a->setCheckable(true);
        a->setShortcut(QKeySequence(Qt::CTRL | e.key));
        a->setActionGroup(group);
        connect(a, &QAction::triggered, this, [this, l = e.layout] { set_layout(l); });
        addAction(a); // its shortcut works before the menu was ever opened
        layout_menu_->addAction(a);
        layout_actions_[std::size_t(e.layout)] = a;
    }
    layout_actions_[std::size_t(core::ViewLayout::FourUp)]->setChecked(true);

    slice_planes_3d_ = new QAction("Slice &planes in 3D", this);
    slice_planes_3d_->setObjectName("slice_planes_3d");
    const char* tip = "Draw each slice view's plane in the 3D view (its outline in the volume, in the view's "
                      "colour: axial red, coronal green, sagittal yellow) and the crosshair";
    slice_planes_3d_->setToolTip(tip);
    slice_planes_3d_->setStatusTip(tip);
    slice_planes_3d_->setCheckable(true);
    slice_planes_3d_->setShortcut(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_P));
    connect(slice_planes_3d_, &QAction::toggled, this, [this] { update_slice_planes_3d(); });
    addAction(slice_planes_3d_);
}

void MainWindow::set_layout(core::ViewLayout l) {
    auto* grid = qobject_cast<QGridLayout*>(centralWidget()->layout());
    // What the grid holds for each view: the view or the widget around it (a slice view's panel).
    const auto cell = [this](QWidget* w) {
        while (w->parentWidget() && w->parentWidget() != centralWidget()) w = w->parentWidget();
        return w;
    };
    QWidget* const views[4] = {cell(view3d_), cell(views_[0]), cell(views_[1]), cell(views_[2])};
    for (QWidget* w : views) grid->removeWidget(w);
    const Arrangement a = arrangement(l);
    for (int i = 0; i < 3; ++i) {
        grid->setRowStretch(i, a.row_stretch[std::size_t(i)]);
        grid->setColumnStretch(i, a.column_stretch[std::size_t(i)]);
    }
    std::array<bool, 4> shown{};
    for (const Cell& c : a.cells) {
        grid->addWidget(views[c.view], c.row, c.column, c.rows, c.columns);
        shown[std::size_t(c.view)] = true;
    }
    for (std::size_t i = 0; i < 4; ++i) views[i]->setVisible(shown[i]);
    layout_ = std::uint8_t(l);
    if (auto* action = layout_action(l)) action->setChecked(true);
}

void MainWindow::set_slice_views(const core::SliceViewsState& s) {
    if (!scene_->has_volume()) return;
    core::apply_slice_views(s, planes_);
    for (auto* v : views_) v->keep_framing(); // the stored pan and zoom, not a fit
    refresh_slices();
}

void MainWindow::update_slice_planes_3d() {
    if (!viewer_) return;
    std::vector<Annotations::Line> lines;
    std::vector<glm::dvec3> points;
    if (slice_planes_in_3d() && scene_->has_volume()) {
        for (const auto& plane : planes_) {
            const auto outline = core::slice_outline_3d(scene_->volume(), plane);
            const glm::vec4 colour(core::slice_color(plane.orientation), 1.0f);
            for (std::size_t i = 0; i < outline.size(); ++i)
                lines.push_back({outline[i], outline[(i + 1) % outline.size()], colour});
        }
        points.push_back(core::crosshair_point(planes_));
    }
    for (auto& line : crop_box_lines()) lines.push_back(line); // the Volume panel's crop box
    viewer_->set_guides(std::move(lines), std::move(points));
}

} // namespace iso::gui
