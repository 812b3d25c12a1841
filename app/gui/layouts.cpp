// View > Layout (3D Slicer's Four-Up, Conventional and One-Up layouts) and
// View > Slice planes in 3D (Slicer's slice intersections in the 3D view).
#include <QAction>
#include <QMainWindow>
#include <QSignalBlocker>
#include <QActionGroup>
#include <QGridLayout>
#include <QMenu>
#include <QStackedWidget>

#include <array>
#include <vector>

#include "app/gui/app_context.hpp"
#include "app/gui/layouts.hpp"
#include "renderer/core/session.hpp"

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

Layouts::Layouts(AppContext& context, QGridLayout* grid, std::array<QWidget*, 4> cells)
    : QObject(&context.window), context_(context), grid_(grid), cells_(cells) {
    QMainWindow& window = context.window;
    menu_ = new QMenu("&Layout", &window);
    menu_->setObjectName("layout_menu");
    menu_->setToolTipsVisible(true);
    auto* group = new QActionGroup(this);
    for (const auto& e : kLayouts) {
        auto* a = new QAction(e.text, &window);
        a->setObjectName(QString("layout_") + core::view_layout_name(e.layout));
        a->setToolTip(e.tip);
        a->setStatusTip(e.tip);
        a->setCheckable(true);
        a->setShortcut(QKeySequence(Qt::CTRL | e.key));
        a->setActionGroup(group);
        connect(a, &QAction::triggered, this, [this, l = e.layout] { context_.workspace.set_layout(l); });
        window.addAction(a); // its shortcut works before the menu was ever opened
        menu_->addAction(a);
        actions_[std::size_t(e.layout)] = a;
    }
    slice_planes_ = new QAction("Slice &planes in 3D", &window);
    slice_planes_->setObjectName("slice_planes_3d");
    const char* tip = "Draw each slice view's plane in the 3D view (its outline in the volume, in the view's "
                      "colour: axial red, coronal green, sagittal yellow) and the crosshair";
    slice_planes_->setToolTip(tip);
    slice_planes_->setStatusTip(tip);
    slice_planes_->setCheckable(true);
    slice_planes_->setShortcut(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_P));
    connect(slice_planes_, &QAction::toggled, this, [this](bool on) { context_.workspace.set_slice_planes_in_3d(on); });
    window.addAction(slice_planes_);
    observer_ = context_.workspace.observe([this](core::Parts p) {
        if (p & core::Parts(core::Part::Layout)) arrange();
    });
    arrange();
}

Layouts::~Layouts() { context_.workspace.unobserve(observer_); }

// The workspace's layout: the views moved into their cells and shown or
// hidden, the menu's entries checked.
void Layouts::arrange() {
    const core::ViewLayout l = context_.workspace.layout();
    {
        const QSignalBlocker block(slice_planes_);
        slice_planes_->setChecked(context_.workspace.slice_planes_in_3d());
    }
    if (shown_ && *shown_ == l) return;
    shown_ = l;
    for (QWidget* w : cells_) grid_->removeWidget(w);
    const Arrangement a = arrangement(l);
    for (int i = 0; i < 3; ++i) {
        grid_->setRowStretch(i, a.row_stretch[std::size_t(i)]);
        grid_->setColumnStretch(i, a.column_stretch[std::size_t(i)]);
    }
    std::array<bool, 4> shown{};
    for (const Cell& c : a.cells) {
        grid_->addWidget(cells_[std::size_t(c.view)], c.row, c.column, c.rows, c.columns);
        shown[std::size_t(c.view)] = true;
    }
    for (std::size_t i = 0; i < 4; ++i) cells_[i]->setVisible(shown[i]);
    actions_[std::size_t(l)]->setChecked(true);
}

} // namespace iso::gui
