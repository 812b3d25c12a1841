// The desktop app's opening of multi-series DICOM folders and its views'
// interaction (docs/gui.md), driven in-process through QTest under
// Xvfb (CTest runs this program under xvfb-run; it skips without a
// display). Expected values come from the core API
// (core::list_series, core::pixel_to_lps, core::sample_at_pixel,
// iso::sample_volume, core::drag_window, Scene::camera) and from the
// analytic field the volume was sampled from, not from the widgets' state.
#include <QAction>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QDropEvent>
#include <QMimeData>
#include <QMouseEvent>
#include <QPushButton>
#include <QStatusBar>
#include <QTableWidget>
#include <QTest>
#include <QWheelEvent>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include <glm/geometric.hpp>

#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/series_dialog.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/view_toolbar.hpp"
#include "app/gui/viewer.hpp"
#include "tests/support/dicom_fixtures.hpp"
#include "gui_test_util.hpp"
#include "io/volume_io.hpp"
#include "tests/support/measure_phantoms.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/surface/analysis.hpp"

using namespace iso;
using test::button_drag;
using test::wait_until;

namespace {

// Drops a local file or folder on the window (straight to its handler:
// QApplication routes drag events only during a drag the platform started).
void drop(gui::MainWindow& w, const std::string& path) {
    QMimeData mime;
    mime.setUrls({QUrl::fromLocalFile(QString::fromStdString(path))});
    QDragEnterEvent enter(QPoint(200, 200), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
    static_cast<QObject&>(w).event(&enter);
    ASSERT_TRUE(enter.isAccepted());
    QDropEvent ev(QPointF(200, 200), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
    static_cast<QObject&>(w).event(&ev);
}

gui::SeriesDialog* visible_chooser(gui::MainWindow& w) {
    for (auto* d : w.findChildren<gui::SeriesDialog*>("series_chooser"))
        if (d->isVisible()) return d;
    return nullptr;
}

// ---- the oblique volume: a field linear in LPS on a rotated, anisotropic grid
const glm::dvec3 kCentre(12.3, -45.6, 78.9);
double field(const glm::dvec3& p) {
    return 100.0 + 3.0 * (p.x - kCentre.x) - 2.0 * (p.y - kCentre.y) + 1.5 * (p.z - kCentre.z);
}

struct Readout {
    glm::dvec3 lps{0.0};
    double value = 0;
    long i = -1, j = -1, k = -1;
};
std::optional<Readout> parse_status(const gui::MainWindow& w) {
    const std::string msg = w.statusBar()->currentMessage().toStdString();
    Readout r;
    if (std::sscanf(msg.c_str(), "LPS (%lf, %lf, %lf) mm, value %lf, voxel (%ld, %ld, %ld)", &r.lps.x, &r.lps.y,
                    &r.lps.z, &r.value, &r.i, &r.j, &r.k) != 7)
        return std::nullopt;
    return r;
}

// A left click in a slice view: the status bar says what the core gives for
// that pixel of the view's grid, and the value is the analytic field there.
void check_click(gui::MainWindow& w, gui::SliceView* view, QPoint at, const char* when) {
    const Volume& v = w.scene().volume();
    const core::SliceGrid g = view->grid(); // the grid drawn before the click
    const glm::dvec2 px{double(at.x()), double(at.y())};
    QTest::mouseClick(view, Qt::LeftButton, {}, at);
    const auto got = parse_status(w);
    const std::string what = std::string(core::slice_orientation_name(view->orientation())) + ", " + when;
    ASSERT_TRUE(got) << what << ": " << w.statusBar()->currentMessage().toStdString();
    const glm::dvec3 lps = core::pixel_to_lps(g, px);
    const auto s = core::sample_at_pixel(v, g, px);
    ASSERT_TRUE(s) << what << ": the click missed the volume";
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(got->lps[a], lps[a], 0.0051) << what;
    EXPECT_NEAR(got->value, s->value, 0.0051) << what;
    EXPECT_EQ(got->i, s->voxel[0]) << what;
    EXPECT_EQ(got->j, s->voxel[1]) << what;
    EXPECT_EQ(got->k, s->voxel[2]) << what;
    // The value is the volume's at that LPS point and the analytic field's
    // (trilinear is exact on a linear field; float32 samples: 1e-3).
    const auto direct = sample_volume(v, lps);
    ASSERT_TRUE(direct);
    EXPECT_NEAR(s->value, direct->value, 1e-9) << what;
    EXPECT_NEAR(got->value, field(lps), 0.006) << what;
}

// What the view shows is the grid's: each checked pixel's grey is the window
// applied to the volume sampled at that pixel's centre of view->grid().
void check_drawn(const gui::MainWindow& w, const gui::SliceView* view, const char* when) {
    const Volume& v = w.scene().volume();
    const QImage img = view->image().convertToFormat(QImage::Format_Grayscale8);
    const core::SliceGrid& g = view->grid();
    ASSERT_EQ(img.width(), g.width);
    int checked = 0, inside = 0;
    for (int r = 3; r < g.height; r += 17)
        for (int c = 5; c < g.width; c += 19) {
            const auto s = sample_volume(v, core::pixel_to_lps(g, {c + 0.5, r + 0.5}));
            const int want = s ? core::window_grey(s->value, w.workspace().window()) : 0;
            // 1 grey level: the image is resliced in float32.
            ASSERT_NEAR(int(img.constScanLine(r)[c]), want, 1) << core::slice_orientation_name(view->orientation())
                                                               << ", " << when << ": pixel (" << c << ", " << r << ")";
            ++checked;
            inside += s.has_value();
        }
    EXPECT_GT(inside, checked / 10) << "the view shows little of the volume: " << when;
}

} // namespace

TEST(GuiViews, TwoSeriesFolderShowsTheChooser) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_views_test", dir / "config");

    // Two series in one folder (vtkDICOMWriter, tests/support/dicom_fixtures.hpp);
    // the second has a slice missing (a warning the chooser shows).
    const std::string folder = dir / "two";
    test::SeriesSpec a;
    a.description = "first: head";
    a.series_number = 3;
    a.pattern = "%s/A-%04d.dcm";
    test::SeriesSpec b;
    b.description = "second: smaller";
    b.series_number = 7;
    b.nx = 20;
    b.ny = 10;
    b.nz = 6;
    b.origin = {0, 0, 0};
    b.pattern = "%s/B-%04d.dcm";
    test::write_series(folder, a);
    test::write_series(folder, b);
    std::vector<std::string> bfiles;
    for (const auto& e : std::filesystem::directory_iterator(folder))
        if (e.path().filename().string().starts_with("B-")) bfiles.push_back(e.path().string());
    std::sort(bfiles.begin(), bfiles.end());
    ASSERT_EQ(bfiles.size(), 6u);
    std::filesystem::remove(bfiles[2]);
    const auto expected = core::list_series(folder);
    ASSERT_EQ(expected.size(), 2u);
    ASSERT_EQ(expected[1].description, "second: smaller");
    ASSERT_FALSE(expected[1].warnings.empty());

    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));

    // ---- dropped: the series are listed, the chooser shows them
    drop(w, folder);
    gui::SeriesDialog* chooser = nullptr;
    ASSERT_TRUE(wait_until([&] { return (chooser = visible_chooser(w)) != nullptr; }, 30000))
        << "no chooser: " << w.statusBar()->currentMessage().toStdString();
    EXPECT_FALSE(w.scene().has_volume()) << "something was opened before a series was chosen";
    QTableWidget* table = chooser->table();
    ASSERT_EQ(table->rowCount(), 2);
    using C = gui::SeriesDialog;
    for (int r = 0; r < 2; ++r) {
        const SeriesInfo& s = expected[std::size_t(r)];
        EXPECT_EQ(table->item(r, C::Modality)->text().toStdString(), "CT");
        EXPECT_EQ(table->item(r, C::Description)->text().toStdString(), s.description);
        EXPECT_EQ(table->item(r, C::Number)->text().toInt(), s.number);
        EXPECT_EQ(table->item(r, C::Dimensions)->text(),
                  QString("%1 x %2 x %3").arg(s.dims[0]).arg(s.dims[1]).arg(s.dims[2]));
        EXPECT_EQ(table->item(r, C::Slices)->text().toULongLong(), s.files);
        for (const auto& warn : s.warnings)
            EXPECT_TRUE(table->item(r, C::Warnings)->text().contains(QString::fromStdString(warn)));
    }
    EXPECT_EQ(table->item(0, C::Warnings)->text(), "none");
    EXPECT_TRUE(table->item(1, C::Warnings)->text().contains("missing slice"))
        << table->item(1, C::Warnings)->text().toStdString();
    EXPECT_EQ(table->item(1, C::Dimensions)->text(), "20 x 10 x 6"); // the missing slice is filled in
    EXPECT_EQ(table->item(1, C::Slices)->text(), "5");
    QTest::qWait(100);
    const auto out = test::output_dir("gui_views");
    EXPECT_TRUE(chooser->grab().save(QString::fromStdString((out / "series_chooser.png").string())));

    // ---- choosing the second (select its row, Open) loads that series
    const core::Scene* before = &w.scene();
    table->selectRow(1);
    auto* buttons = chooser->findChild<QDialogButtonBox*>("series_buttons");
    ASSERT_NE(buttons, nullptr);
    buttons->button(QDialogButtonBox::Open)->click();
    ASSERT_TRUE(wait_until([&] { return &w.scene() != before && !w.busy(); }, 30000))
        << "nothing loaded: " << w.statusBar()->currentMessage().toStdString();
    ASSERT_TRUE(w.scene().has_volume());
    const Volume& v = w.scene().volume();
    EXPECT_EQ(v.dims[0], expected[1].dims[0]);
    EXPECT_EQ(v.dims[1], expected[1].dims[1]);
    EXPECT_EQ(v.dims[2], expected[1].dims[2]);
    EXPECT_EQ(v.meta.series_description, "second: smaller");
    EXPECT_EQ(w.workspace().series(), expected[1].uid);
    EXPECT_EQ(v.meta.warnings, expected[1].warnings);
    EXPECT_TRUE(w.slice_view(core::SliceOrientation::Axial)->has_image());

    // ---- Cancel opens nothing
    const core::Scene* shown = &w.scene();
    drop(w, folder);
    ASSERT_TRUE(wait_until([&] { return (chooser = visible_chooser(w)) != nullptr; }, 30000));
    auto* cancel_buttons = chooser->findChild<QDialogButtonBox*>("series_buttons");
    cancel_buttons->button(QDialogButtonBox::Cancel)->click();
    QTest::qWait(300);
    EXPECT_EQ(visible_chooser(w), nullptr);
    EXPECT_FALSE(w.busy());
    EXPECT_EQ(&w.scene(), shown);
    EXPECT_EQ(w.workspace().series(), expected[1].uid);

    // ---- a folder with one series opens directly, as before
    const std::string single = dir / "one";
    test::write_series(single, a);
    w.open_path(QString::fromStdString(single));
    ASSERT_TRUE(wait_until([&] { return &w.scene() != shown && !w.busy(); }, 30000))
        << w.statusBar()->currentMessage().toStdString();
    EXPECT_EQ(visible_chooser(w), nullptr);
    ASSERT_TRUE(w.scene().has_volume());
    EXPECT_EQ(w.scene().volume().dims[2], 8);
    EXPECT_TRUE(w.workspace().series().empty());

    // ---- a slice click on this CT reads out its value in HU (core::value_readout, as the 3D readout does)
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const QPoint at(axial->width() / 2, axial->height() / 2);
    const core::SliceGrid g = axial->grid();
    QTest::mouseClick(axial, Qt::LeftButton, {}, at);
    const auto s = core::sample_at_pixel(w.scene().volume(), g, {double(at.x()), double(at.y())});
    ASSERT_TRUE(s) << "the click missed the volume";
    const std::string msg = w.statusBar()->currentMessage().toStdString();
    EXPECT_NE(msg.find(", " + core::value_readout(s->value, "HU") + ", voxel ("), std::string::npos) << msg;
}

TEST(GuiViews, ObliqueVolumeSliceClicksPanZoomAndWindow) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_views_test", dir / "config");

    // An oblique (rotated 25 degrees), anisotropic (0.7 x 1.0 x 1.3 mm) NRRD
    // of a field linear in LPS.
    const std::array<std::int64_t, 3> dims{60, 48, 40};
    const Volume original = test::sample_field(dims, test::oblique_affine(dims, 1.0, kCentre), field);
    const std::string file = dir / "oblique.nrrd";
    save_volume(original, file);

    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(file));
    ASSERT_TRUE(wait_until([&] { return w.scene().has_volume() && !w.busy(); }, 30000))
        << w.statusBar()->currentMessage().toStdString();
    const Volume& v = w.scene().volume();
    // Really oblique on the way in: the file's space directions are rotated.
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) ASSERT_NEAR(v.index_to_lps[c][r], original.index_to_lps[c][r], 1e-9);
    EXPECT_GT(std::abs(v.index_to_lps[0][1]), 0.1);

    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal}) {
        auto* view = w.slice_view(o);
        ASSERT_TRUE(view->has_image());
        const QPoint mid(view->width() / 2, view->height() / 2);
        check_click(w, view, mid + QPoint(11, -7), "fitted");
        check_drawn(w, view, "fitted");

        // ---- middle drag pans: the content follows the pointer, the slice stays
        const core::SliceGrid g0 = view->grid();
        const QPointF delta(37, 21);
        button_drag(view, Qt::MiddleButton, mid, QPointF(mid) + delta);
        const core::SliceGrid g1 = view->grid();
        EXPECT_NEAR(g1.offset_mm, g0.offset_mm, 1e-9);
        EXPECT_EQ(g1.pixel_mm, g0.pixel_mm);
        for (const glm::dvec2& q : {glm::dvec2(10.5, 20.5), glm::dvec2(mid.x(), mid.y())})
            EXPECT_NEAR(
                glm::length(core::pixel_to_lps(g1, q + glm::dvec2(delta.x(), delta.y())) - core::pixel_to_lps(g0, q)),
                0.0, 1e-9);
        check_drawn(w, view, "panned");
        check_click(w, view, mid + QPoint(-13, 9), "panned");

        // ---- right drag up zooms about the press point
        const core::SliceGrid g2 = view->grid();
        const QPointF press(mid.x() - 20, mid.y() + 10);
        const double up = view->height() / 4.0;
        button_drag(view, Qt::RightButton, press, press - QPointF(0, up));
        const core::SliceGrid g3 = view->grid();
        EXPECT_NEAR(g2.pixel_mm / g3.pixel_mm, core::drag_zoom_factor(up, view->height()), 1e-9);
        EXPECT_NEAR(glm::length(core::pixel_to_lps(g3, {press.x(), press.y()}) -
                                core::pixel_to_lps(g2, {press.x(), press.y()})),
                    0.0, 1e-9);
        EXPECT_NEAR(g3.offset_mm, g2.offset_mm, 1e-9);
        check_drawn(w, view, "zoomed");
        check_click(w, view, mid + QPoint(6, 14), "zoomed");
    }
    const auto out = test::output_dir("gui_views");
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "oblique_panned_zoomed.png").string())));

    // ---- left drag: window (right = wider) and level (up = higher), Slicer's gain; no click
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const QString status = w.statusBar()->currentMessage();
    const core::WindowLevel start = w.workspace().window();
    const QPointF from(axial->width() / 2.0, axial->height() / 2.0);
    button_drag(axial, Qt::LeftButton, from, from + QPointF(60, -25));
    const core::WindowLevel want = core::drag_window(start, {60, 25}, v.value_range());
    EXPECT_NEAR(w.workspace().window().width, want.width, 1e-9);
    EXPECT_NEAR(w.workspace().window().center, want.center, 1e-9);
    EXPECT_NE(want.width, start.width);
    // The tool bar's numbers follow (one decimal shown).
    EXPECT_NEAR(w.findChild<QDoubleSpinBox*>("window_width")->value(), want.width, 0.051);
    EXPECT_NEAR(w.findChild<QDoubleSpinBox*>("window_center")->value(), want.center, 0.051);
    EXPECT_EQ(w.statusBar()->currentMessage(), status) << "a drag is not a click";
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal})
        check_drawn(w, w.slice_view(o), "new window");
}

TEST(GuiViews, ThreeDViewMouseAndToolBar) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_views_test", dir / "config");
    // A CT-like ball (1000 inside, 0 outside) on the oblique grid: its 500 surface is a sphere.
    const std::array<std::int64_t, 3> dims{48, 40, 34};
    const Volume ball = test::sample_field(dims, test::oblique_affine(dims, 1.0, kCentre), [](const glm::dvec3& p) {
        return test::ct_edge(14.0 - glm::length(p - kCentre), 1.0);
    });
    const std::string file = dir / "ball.nrrd";
    save_volume(ball, file);

    gui::MainWindow w;
    w.resize(1200, 900);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(file));
    ASSERT_TRUE(wait_until([&] { return w.scene().has_volume() && !w.busy(); }, 30000));
    w.surfaces_panel()->add_surface(500);
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    gui::Viewer* viewer = w.viewer();
    ASSERT_NE(viewer, nullptr);
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > 0 || !viewer->error().empty(); }, 60000));
    ASSERT_TRUE(viewer->error().empty()) << viewer->error();
    gui::ViewToolBar* bar = w.view_toolbar();
    ASSERT_NE(bar, nullptr);

    // ---- AO toggle
    EXPECT_NE(viewer->options().look.ao, AoMethod::Off);
    bar->ao_action()->trigger();
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Off);
    // The O key in the view toggles it too, and the button follows.
    viewer->setFocus();
    QTest::keyClick(viewer, Qt::Key_O);
    EXPECT_NE(viewer->options().look.ao, AoMethod::Off);
    EXPECT_TRUE(bar->ao_action()->isChecked());
    QTest::keyClick(viewer, Qt::Key_O);
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Off);
    EXPECT_FALSE(bar->ao_action()->isChecked());
    // The AO button's menu chooses the method and turns AO on; the O key
    // turns it off and back on with that method; cone traced again after.
    bar->ao_raytraced_action()->trigger();
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Raytraced);
    EXPECT_TRUE(bar->ao_action()->isChecked());
    QTest::keyClick(viewer, Qt::Key_O);
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Off);
    QTest::keyClick(viewer, Qt::Key_O);
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Raytraced);
    bar->ao_cone_action()->trigger();
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Cone);
    bar->ao_action()->trigger();
    EXPECT_EQ(viewer->options().look.ao, AoMethod::Off);

    // ---- patient-view buttons and reset: the scene's camera for that view
    const double aspect = double(viewer->width()) / double(viewer->height());
    auto expect_camera = [&](const Camera& want, const char* what) {
        const Camera& c = viewer->camera();
        EXPECT_NEAR(glm::length(c.eye - want.eye), 0.0, 1e-9) << what;
        EXPECT_NEAR(glm::length(c.target - want.target), 0.0, 1e-9) << what;
        EXPECT_NEAR(glm::length(c.up - want.up), 0.0, 1e-9) << what;
    };
    for (auto pv : {PatientView::Anterior, PatientView::Posterior, PatientView::Left, PatientView::Right,
                    PatientView::Superior, PatientView::Inferior}) {
        bar->view_action(pv)->trigger();
        expect_camera(w.scene().camera(pv, aspect), patient_view_name(pv));
    }
    bar->reset_action()->trigger();
    expect_camera(w.scene().camera(PatientView::Anterior, aspect), "reset");

    // ---- a click (press and release, no drag) reaches on_click once; drags do not
    int clicks = 0, hovers = 0;
    viewer->on_click = [&](gui::Viewer&, QPointF) { ++clicks; };
    viewer->on_hover = [&](gui::Viewer&, QPointF) { ++hovers; };
    // Whole pixels: the 3D view reads integer mouse positions.
    const QPointF mid(viewer->width() / 2, viewer->height() / 2);
    ASSERT_NO_FATAL_FAILURE(test::click_3d(viewer, mid.toPoint()));
    EXPECT_EQ(clicks, 1);
    QTest::mouseMove(viewer, (mid + QPointF(5, 5)).toPoint());
    EXPECT_GE(hovers, 1);

    // ---- left drag rotates about the target (distance kept)
    Camera c0 = viewer->camera();
    button_drag(viewer, Qt::LeftButton, mid, mid + QPointF(40, 0));
    Camera c1 = viewer->camera();
    EXPECT_NEAR(glm::length(c1.target - c0.target), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(c1.eye - c1.target), glm::length(c0.eye - c0.target), 1e-6);
    EXPECT_GT(std::acos(std::clamp(glm::dot(c1.forward(), c0.forward()), -1.0, 1.0)), 0.1); // radians
    EXPECT_EQ(clicks, 1);

    // ---- middle drag pans (direction and distance kept, target moved)
    c0 = viewer->camera();
    button_drag(viewer, Qt::MiddleButton, mid, mid + QPointF(30, 20));
    c1 = viewer->camera();
    EXPECT_NEAR(glm::length(c1.forward() - c0.forward()), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(c1.eye - c1.target), glm::length(c0.eye - c0.target), 1e-6);
    EXPECT_GT(glm::length(c1.target - c0.target), 1.0);

    // ---- right drag up zooms in (core::drag_zoom_factor of the drag), down zooms out
    c0 = viewer->camera();
    const double up = double(viewer->height() / 4);
    button_drag(viewer, Qt::RightButton, mid, mid - QPointF(0, up), 4);
    c1 = viewer->camera();
    EXPECT_NEAR(glm::length(c0.eye - c0.target) / glm::length(c1.eye - c1.target),
                core::drag_zoom_factor(up, viewer->height()), 1e-6);
    EXPECT_NEAR(glm::length(c1.target - c0.target), 0.0, 1e-9);
    button_drag(viewer, Qt::RightButton, mid, mid + QPointF(0, up), 4);
    EXPECT_NEAR(glm::length(viewer->camera().eye - viewer->camera().target), glm::length(c0.eye - c0.target), 1e-6);

    // ---- the wheel zooms (one notch forward: closer)
    c0 = viewer->camera();
    QWheelEvent wheel(mid, viewer->mapToGlobal(mid), QPoint(), QPoint(0, 120), Qt::NoButton, Qt::NoModifier,
                      Qt::NoScrollPhase, false);
    QCoreApplication::sendEvent(viewer, &wheel);
    EXPECT_LT(glm::length(viewer->camera().eye - viewer->camera().target), glm::length(c0.eye - c0.target));
    EXPECT_EQ(clicks, 1);

    // ---- AO waits while a drag moves the camera, and comes back when it stops
    bar->ao_action()->trigger();
    ASSERT_NE(viewer->options().look.ao, AoMethod::Off);
    ASSERT_TRUE(wait_until([&] { return viewer->converged(); }, 60000)) << "the AO did not converge";
    {
        auto send = [&](QEvent::Type type, QPointF at, Qt::MouseButton button, Qt::MouseButtons held) {
            QMouseEvent e(type, at, viewer->mapToGlobal(at), button, held, Qt::NoModifier);
            QCoreApplication::sendEvent(viewer, &e);
        };
        send(QEvent::MouseButtonPress, mid, Qt::LeftButton, Qt::LeftButton);
        send(QEvent::MouseMove, mid + QPointF(30, 0), Qt::NoButton, Qt::LeftButton);
        EXPECT_TRUE(viewer->dragging());
        // The picture before the drag may stay up until the frame thread's
        // first drag frame arrives: that one has no AO.
        const int drawn = viewer->frames();
        EXPECT_TRUE(wait_until([&] { return viewer->frames() > drawn && viewer->ao_frames() == 0; }, 30000))
            << "no frame without AO during the drag";
        EXPECT_FALSE(viewer->converged());
        send(QEvent::MouseButtonRelease, mid + QPointF(30, 0), Qt::LeftButton, Qt::NoButton);
        EXPECT_FALSE(viewer->dragging());
        ASSERT_TRUE(wait_until([&] { return viewer->converged(); }, 60000))
            << "the AO did not come back after the drag";
        EXPECT_EQ(viewer->ao_frames(), viewer->options().look.ao_frames);
        EXPECT_EQ(clicks, 1);
    }
    bar->ao_action()->trigger();
    ASSERT_EQ(viewer->options().look.ao, AoMethod::Off);

    // ---- transparency off: the translucent skin is drawn as if opaque
    // (the converged frames compared pixel for pixel: the view shows its
    // last picture until the frame thread's new one arrives, so a grab
    // right after a change may still show the one before)
    const auto settled = [&] {
        EXPECT_TRUE(wait_until([&] { return viewer->converged() || !viewer->error().empty(); }, 120000));
        return viewer->grab().toImage();
    };
    bar->reset_action()->trigger();
    const auto id = w.scene().surfaces().front();
    {
        core::SurfaceInfo info = w.scene().info(id);
        info.opacity = 0.3f;
        w.workspace().set_surface_info(id, info);
    }
    ASSERT_TRUE(bar->transparency_action()->isChecked());
    const QImage translucent = settled();
    bar->transparency_action()->trigger();
    EXPECT_FALSE(viewer->options().look.transparency);
    const QImage forced = settled();
    EXPECT_EQ(w.scene().info(id).opacity, 0.3f) << "the toggle must not edit the surface";
    bar->transparency_action()->trigger();
    {
        core::SurfaceInfo info = w.scene().info(id);
        info.opacity = 1.0f;
        w.workspace().set_surface_info(id, info);
    }
    const QImage opaque = settled();
    ASSERT_EQ(forced.size(), opaque.size());
    long differ_opaque = 0, differ_translucent = 0;
    for (int y = 0; y < forced.height(); ++y)
        for (int x = 0; x < forced.width(); ++x) {
            differ_opaque += forced.pixel(x, y) != opaque.pixel(x, y);
            differ_translucent += forced.pixel(x, y) != translucent.pixel(x, y);
        }
    EXPECT_EQ(differ_opaque, 0);
    EXPECT_GT(differ_translucent, 1000);
    EXPECT_TRUE(viewer->error().empty()) << viewer->error();
    const auto out = test::output_dir("gui_views");
    translucent.save(QString::fromStdString((out / "skin_translucent.png").string()));
    forced.save(QString::fromStdString((out / "skin_transparency_off.png").string()));
}
