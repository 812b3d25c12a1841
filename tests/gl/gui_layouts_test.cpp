// The desktop app's layouts, the slice views in sessions and the slice
// planes in the 3D view (docs/gui.md "Layouts"), driven in-process through
// QTest under Xvfb (CTest runs this program under xvfb-run; it skips
// without a display). Expected values: the planes and crosshair from the
// core (core::default_planes, core::crosshair_point, core::slice_outline_3d,
// core::slice_color), the outlines' pixels from the camera's projection
// (Viewer::image_pixel), not from the window's own text.
#include <QAction>
#include <QGridLayout>
#include <QMouseEvent>
#include <QStatusBar>

#include <filesystem>

#include "gui_measure_util.hpp"
#include "renderer/core/session.hpp"

using namespace iso;
using namespace iso::test;
using GuiLayouts = HeadWindow;
namespace fs = std::filesystem;

namespace {

using core::SliceOrientation;

// A drag with `button` from `from` by `by`, in steps, as events sent at once.
void drag_by(QWidget* w, Qt::MouseButton button, QPoint from, QPoint by) {
    const auto send = [&](QEvent::Type t, QPoint at, Qt::MouseButtons held) {
        QMouseEvent e(t, QPointF(at), w->mapToGlobal(QPointF(at)), button, held, Qt::NoModifier);
        QCoreApplication::sendEvent(w, &e);
    };
    send(QEvent::MouseButtonPress, from, button);
    for (int i = 1; i <= 10; ++i) send(QEvent::MouseMove, from + by * i / 10, button);
    send(QEvent::MouseButtonRelease, from + by, Qt::NoButton);
}

// How many of the points a quarter and three quarters along each edge of
// plane `i`'s outline (projected with the view's camera) have a pixel of
// the plane's colour within 2 pixels, out of how many were in the image.
std::pair<int, int> outline_pixels_in_colour(gui::MainWindow& w, const QImage& img, std::size_t i) {
    const auto& plane = w.workspace().planes()[i];
    const auto outline = core::slice_outline_3d(w.scene().volume(), plane);
    const glm::vec3 c = core::slice_color(plane.orientation) * 255.0f;
    int hit = 0, tried = 0;
    for (std::size_t k = 0; k < outline.size(); ++k)
        for (const double t : {0.25, 0.75}) {
            const glm::dvec3 p = outline[k] + t * (outline[(k + 1) % outline.size()] - outline[k]);
            const auto px = w.viewer()->image_pixel(p);
            if (!px || px->x() < 3 || px->y() < 3 || px->x() > img.width() - 4 || px->y() > img.height() - 4) continue;
            ++tried;
            bool found = false;
            for (int dy = -2; dy <= 2 && !found; ++dy)
                for (int dx = -2; dx <= 2 && !found; ++dx) {
                    const QColor q = img.pixelColor(int(px->x()) + dx, int(px->y()) + dy);
                    found =
                        std::abs(q.red() - c.r) < 40 && std::abs(q.green() - c.g) < 40 && std::abs(q.blue() - c.b) < 40;
                }
            hit += found;
        }
    return {hit, tried};
}

// A frame drawn after now, once the view has converged (its still frames
// may come from their own thread), read back.
QImage next_frame(gui::Viewer* v) {
    const int frames = v->frames();
    v->update();
    EXPECT_TRUE(wait_until([&] { return v->frames() > frames; }, 30000));
    EXPECT_TRUE(wait_until([&] { return v->converged() || !v->error().empty(); }, 180000));
    EXPECT_EQ(v->error(), "");
    return v->grab().toImage();
}

} // namespace

// Each layout shows its views where Slicer puts them and hides the others;
// the views are the same widgets throughout (the 3D view keeps its frame
// thread and camera, each slice view its plane); Ctrl+digit picks a layout.
TEST_F(GuiLayouts, LayoutsMoveTheViewsWithoutMakingThemAgain) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const Camera camera = viewer->camera();
    const auto planes = w.workspace().planes();
    // The grid's cells: the 3D view's stack (the viewer or its hint), each slice view's panel.
    const auto cell = [&w](QWidget* v) {
        while (v->parentWidget() != w.centralWidget()) v = v->parentWidget();
        return v;
    };
    QWidget* view3d = cell(viewer);
    QWidget* axial = cell(w.slice_view(SliceOrientation::Axial));
    QWidget* coronal = cell(w.slice_view(SliceOrientation::Coronal));
    QWidget* sagittal = cell(w.slice_view(SliceOrientation::Sagittal));
    const QRect area = w.centralWidget()->contentsRect();
    const auto settle = [] { QTest::qWait(50); };

    EXPECT_EQ(w.workspace().layout(), core::ViewLayout::FourUp);
    EXPECT_TRUE(w.layouts()->layout_action(core::ViewLayout::FourUp)->isChecked());
    EXPECT_LT(view3d->x(), axial->x());
    EXPECT_EQ(view3d->y(), axial->y());
    EXPECT_EQ(coronal->x(), view3d->x());
    EXPECT_GT(coronal->y(), view3d->y());
    EXPECT_EQ(sagittal->y(), coronal->y());

    w.layouts()->layout_action(core::ViewLayout::Conventional)->trigger();
    settle();
    EXPECT_EQ(w.workspace().layout(), core::ViewLayout::Conventional);
    for (QWidget* v :
         {view3d, static_cast<QWidget*>(axial), static_cast<QWidget*>(coronal), static_cast<QWidget*>(sagittal)})
        EXPECT_TRUE(v->isVisible());
    EXPECT_GT(view3d->width(), area.width() * 9 / 10);
    EXPECT_NEAR(double(view3d->height()) / double(axial->height()), 2.0, 0.1);
    EXPECT_EQ(axial->y(), coronal->y());
    EXPECT_EQ(coronal->y(), sagittal->y());
    EXPECT_LT(axial->x(), coronal->x());
    EXPECT_LT(coronal->x(), sagittal->x());

    const std::pair<core::ViewLayout, QWidget*> alone[] = {{core::ViewLayout::ThreeD, view3d},
                                                           {core::ViewLayout::Axial, axial},
                                                           {core::ViewLayout::Coronal, coronal},
                                                           {core::ViewLayout::Sagittal, sagittal}};
    for (const auto& [layout, shown] : alone) {
        w.layouts()->layout_action(layout)->trigger();
        settle();
        EXPECT_EQ(w.workspace().layout(), layout);
        for (QWidget* v :
             {view3d, static_cast<QWidget*>(axial), static_cast<QWidget*>(coronal), static_cast<QWidget*>(sagittal)})
            EXPECT_EQ(v->isVisible(), v == shown) << core::view_layout_name(layout);
        EXPECT_GT(shown->width(), area.width() * 9 / 10) << core::view_layout_name(layout);
        EXPECT_GT(shown->height(), area.height() * 9 / 10) << core::view_layout_name(layout);
    }
    // The slice view alone shows its slice, larger.
    auto* sagittal_view = w.slice_view(SliceOrientation::Sagittal);
    EXPECT_TRUE(sagittal_view->has_image());
    EXPECT_EQ(sagittal_view->image().width(), sagittal_view->width());
    EXPECT_GT(sagittal_view->height(), area.height() * 8 / 10);

    // Keyboard: Ctrl+4 the axial view alone, Ctrl+1 back to Four-Up (shortcuts need the active window).
    w.activateWindow();
    ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
    QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);
    settle();
    EXPECT_EQ(w.workspace().layout(), core::ViewLayout::Axial);
    EXPECT_TRUE(axial->isVisible());
    EXPECT_FALSE(view3d->isVisible());
    QTest::keyClick(&w, Qt::Key_1, Qt::ControlModifier);
    settle();
    EXPECT_EQ(w.workspace().layout(), core::ViewLayout::FourUp);

    // Nothing was made again: the same viewer (its frame thread) and camera; it still draws.
    EXPECT_EQ(w.viewer(), viewer);
    EXPECT_EQ(viewer->camera().eye, camera.eye);
    EXPECT_EQ(viewer->camera().target, camera.target);
    const int frames = viewer->frames();
    viewer->update();
    EXPECT_TRUE(wait_until([&] { return viewer->frames() > frames; }, 30000));
    EXPECT_TRUE(viewer->error().empty()) << viewer->error();
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(w.workspace().planes()[i].origin, planes[i].origin);
        EXPECT_EQ(w.workspace().planes()[i].offset_mm(), planes[i].offset_mm());
    }
}

// A session keeps the layout, each slice view's slice, pan and zoom, the
// crosshair and the slice planes toggle: a fresh window of another size
// opening it shows the same (values from the core's planes).
TEST_F(GuiLayouts, SessionRestoresTheLayoutSliceViewsAndCrosshair) {
    gui::MainWindow& w = window();
    w.layouts()->layout_action(core::ViewLayout::Conventional)->trigger();
    w.layouts()->slice_planes_action()->trigger();
    ASSERT_TRUE(w.workspace().slice_planes_in_3d());
    QTest::qWait(50);
    // The crosshair to a point, then the axial view two slices up: the crosshair follows its slice.
    const auto defaults = core::default_planes(w.scene().volume());
    const glm::dvec3 pick = defaults[0].origin + glm::dvec3(12.25, -20.5, -8.0);
    w.workspace().set_crosshair(pick);
    auto* axial = w.slice_view(SliceOrientation::Axial);
    axial->setFocus();
    QTest::keyClick(axial, Qt::Key_PageUp);
    QTest::keyClick(axial, Qt::Key_PageUp);
    const glm::dvec3 crosshair = pick + glm::dvec3(0, 0, 2.0 * defaults[0].step_mm);
    EXPECT_LT(glm::length(core::crosshair_point(w.workspace().planes()) - crosshair), 1e-9);
    EXPECT_NEAR(w.workspace().planes()[0].offset_mm(), crosshair.z, 1e-9);
    // The coronal view zoomed (a right drag up), the sagittal one panned (a middle drag).
    auto* coronal = w.slice_view(SliceOrientation::Coronal);
    auto* sagittal = w.slice_view(SliceOrientation::Sagittal);
    const double coronal_pixel = w.workspace().planes()[1].pixel_mm;
    const glm::dvec3 sagittal_centre = w.workspace().planes()[2].center;
    drag_by(coronal, Qt::RightButton, {coronal->width() / 2, coronal->height() / 2}, {0, -40});
    drag_by(sagittal, Qt::MiddleButton, {sagittal->width() / 2, sagittal->height() / 2}, {30, 20});
    EXPECT_LT(w.workspace().planes()[1].pixel_mm, coronal_pixel * 0.9);
    EXPECT_GT(glm::length(w.workspace().planes()[2].center - sagittal_centre), 1.0);
    const auto saved = w.workspace().planes();

    const std::string session = dir() / "layout.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    ASSERT_TRUE(fs::exists(session)) << w.statusBar()->currentMessage().toStdString();
    const core::Session file = core::read_session(session);
    ASSERT_TRUE(file.layout && file.slice_views);
    EXPECT_EQ(*file.layout, core::ViewLayout::Conventional);
    EXPECT_TRUE(file.slice_planes_in_3d);

    gui::MainWindow w2;
    w2.resize(1200, 900);
    w2.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w2));
    w2.open_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w2.busy(); }, 120000));
    ASSERT_EQ(w2.scene().surfaces().size(), 2u) << w2.statusBar()->currentMessage().toStdString();
    QTest::qWait(100); // the layout settles: resizes keep the restored framing
    EXPECT_EQ(w2.workspace().layout(), core::ViewLayout::Conventional);
    EXPECT_TRUE(w2.layouts()->layout_action(core::ViewLayout::Conventional)->isChecked());
    EXPECT_TRUE(w2.workspace().slice_planes_in_3d());
    EXPECT_TRUE(w2.layouts()->slice_planes_action()->isChecked());
    EXPECT_LT(glm::length(core::crosshair_point(w2.workspace().planes()) - crosshair), 1e-9);
    for (std::size_t i = 0; i < 3; ++i) {
        const auto& a = saved[i];
        const auto& b = w2.workspace().planes()[i];
        EXPECT_EQ(b.origin, a.origin) << i;
        EXPECT_NEAR(b.offset_mm(), a.offset_mm(), 1e-12) << i;
        EXPECT_LT(glm::length(b.center - a.center), 1e-9) << i;
        EXPECT_EQ(b.pixel_mm, a.pixel_mm) << i;
    }
    // The views draw what the planes say: the crosshair at the restored point.
    auto* axial2 = w2.slice_view(SliceOrientation::Axial);
    ASSERT_TRUE(axial2->has_image());
    EXPECT_NEAR(axial2->grid().offset_mm, crosshair.z, 1e-9);
    EXPECT_EQ(axial2->grid().pixel_mm, saved[0].pixel_mm);
}

// View > Slice planes in 3D: each plane's outline in the volume is drawn
// in its colour where the camera projects it, follows the slice as it
// scrolls, and is gone when the toggle is off.
TEST_F(GuiLayouts, SlicePlanesAreDrawnInTheirColoursIn3d) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    // The outlines are the overlay's, drawn in every frame: one frame a view
    // (no AO, no anti-aliasing still frames to wait for; under the
    // sanitizers the 4 x 32 still frames took 108 s).
    FrameLook look = w.workspace().look();
    look.ao = AoMethod::Off;
    look.aa.samples = 1;
    look.aa.view_frames = 1;
    w.workspace().set_look(look);
    // Surfaces in a neutral blue, so no surface pixel passes for a plane's colour.
    for (auto id : w.scene().surfaces()) {
        core::SurfaceInfo info = w.scene().info(id);
        info.color = {0.05f, 0.08f, 0.3f};
        w.workspace().set_surface_info(id, info);
    }
    // An oblique camera: every plane's outline is a polygon on screen, not an edge-on line.
    Camera c = viewer->camera();
    const glm::dvec3 centre = core::crosshair_point(w.workspace().planes());
    c.target = centre;
    c.eye = centre + glm::dvec3(-260.0, -420.0, 300.0);
    c.up = {0, 0, 1};
    viewer->set_camera(c);

    QImage off = next_frame(viewer);
    for (std::size_t i = 0; i < 3; ++i) {
        const auto [hit, tried] = outline_pixels_in_colour(w, off, i);
        EXPECT_GE(tried, 6) << i;
        EXPECT_EQ(hit, 0) << "plane " << i << " drawn with the toggle off";
    }
    w.layouts()->slice_planes_action()->trigger();
    ASSERT_TRUE(w.workspace().slice_planes_in_3d());
    QImage on = next_frame(viewer);
    for (std::size_t i = 0; i < 3; ++i) {
        const auto [hit, tried] = outline_pixels_in_colour(w, on, i);
        EXPECT_GE(tried, 6) << i;
        EXPECT_GE(hit, tried * 3 / 4) << "plane " << i << ": " << hit << " of " << tried;
    }
    // The axial view ten slices up: its outline is drawn at its new height.
    auto* axial = w.slice_view(SliceOrientation::Axial);
    const double before = w.workspace().planes()[0].offset_mm();
    axial->setFocus();
    for (int k = 0; k < 10; ++k) QTest::keyClick(axial, Qt::Key_PageUp);
    ASSERT_GT(w.workspace().planes()[0].offset_mm(), before + 5.0);
    on = next_frame(viewer);
    const auto [hit, tried] = outline_pixels_in_colour(w, on, 0);
    EXPECT_GE(tried, 6);
    EXPECT_GE(hit, tried * 3 / 4) << hit << " of " << tried;
    w.layouts()->slice_planes_action()->trigger();
    EXPECT_FALSE(w.workspace().slice_planes_in_3d());
    off = next_frame(viewer);
    EXPECT_EQ(outline_pixels_in_colour(w, off, 0).first, 0);
}
