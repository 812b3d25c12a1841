// The desktop app's main window (docs/gui.md) driven in-process
// through QTest in a real X server (CTest runs this program under xvfb-run;
// the window tests skip without a display). Expected values come from the core API
// (core::sample_at_pixel, the scene), not from the window's own state.
#include <QApplication>
#include <QElapsedTimer>
#include <QMessageBox>
#include <QMimeData>
#include <QProgressDialog>
#include <QPushButton>
#include <QSettings>
#include <QStatusBar>
#include <QSurfaceFormat>
#include <QTest>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>

#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "gui_test_util.hpp"

using namespace iso;

namespace {
using test::lit_fraction;
using test::wait_until;
} // namespace

TEST(MainWindow, NoArgumentsWithoutADisplayStaysACommandLineTool) {
    // The README's headless commands keep working: no display, no window.
    const auto r = test::run_command("env -u DISPLAY -u WAYLAND_DISPLAY " + test::cli(), true);
    EXPECT_NE(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("subcommand"), std::string::npos) << r.out;
    const auto h = test::run_command(test::cli() + " gui --help", true);
    EXPECT_EQ(h.exit_code, 0) << h.out;
    EXPECT_NE(h.out.find("input"), std::string::npos) << h.out;
}

TEST(MainWindow, OpenSlicesClickSurfaceAndBrokenFile) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    // Recent files go to a throwaway settings folder, not the user's.
    const auto app = test::make_app("main_window_test", dir / "config");

    gui::MainWindow w;
    w.resize(1400, 1000);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));

    // ---- open the bundled CT through File > Open's path, in the background
    const std::string headsq = test::data("headsq.nhdr");
    w.open_path(QString::fromStdString(headsq));
    EXPECT_TRUE(w.busy());
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    ASSERT_TRUE(w.scene().has_volume()) << w.statusBar()->currentMessage().toStdString();
    const Volume& v = w.scene().volume();
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal}) {
        const auto* view = w.slice_view(o);
        ASSERT_TRUE(view->has_image()) << core::slice_orientation_name(o);
        EXPECT_EQ(view->image().width(), view->width());
        // The head fills a good part of each view (measured: a quarter or more).
        EXPECT_GT(lit_fraction(view->image()), 0.1) << core::slice_orientation_name(o);
    }

    // Remembered among the recent files.
    EXPECT_TRUE(QSettings()
                    .value("recent_files")
                    .toStringList()
                    .contains(QString::fromStdString(std::filesystem::absolute(headsq).string())));

    // ---- Cancel on a load: the window stops waiting at once and keeps what it shows
    {
        const core::Scene* shown = &w.scene();
        w.open_path(QString::fromStdString(headsq));
        auto* progress = w.findChild<QProgressDialog*>("progress");
        ASSERT_NE(progress, nullptr);
        // Its Cancel button, before the worker's end can reach the window
        // (QProgressDialog::cancel() would not emit canceled()).
        auto* cancel = progress->findChild<QPushButton*>();
        ASSERT_NE(cancel, nullptr);
        cancel->click();
        EXPECT_FALSE(w.busy());
        QTest::qWait(1500); // the abandoned worker ends; its result is dropped
        EXPECT_EQ(&w.scene(), shown);
        EXPECT_EQ(w.findChild<QMessageBox*>("error"), nullptr);
    }

    // ---- a click in the axial view: the status bar says what the core samples there
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const QPoint at(axial->width() / 2 + 17, axial->height() / 2 - 23);
    QTest::mouseClick(axial, Qt::LeftButton, {}, at);
    const glm::dvec2 px{double(at.x()), double(at.y())};
    const auto expected = core::sample_at_pixel(v, axial->grid(), px);
    ASSERT_TRUE(expected.has_value()) << "the click missed the volume";
    const glm::dvec3 lps = core::pixel_to_lps(axial->grid(), px);
    const std::string msg = w.statusBar()->currentMessage().toStdString();
    double x = 0, y = 0, z = 0, value = 0;
    long i = -1, j = -1, k = -1;
    ASSERT_EQ(std::sscanf(msg.c_str(), "LPS (%lf, %lf, %lf) mm, value %lf, voxel (%ld, %ld, %ld)", &x, &y, &z, &value,
                          &i, &j, &k),
              7)
        << msg;
    EXPECT_NEAR(x, lps.x, 0.005);
    EXPECT_NEAR(y, lps.y, 0.005);
    EXPECT_NEAR(z, lps.z, 0.005);
    EXPECT_NEAR(value, expected->value, 0.005);
    EXPECT_EQ(i, expected->voxel[0]);
    EXPECT_EQ(j, expected->voxel[1]);
    EXPECT_EQ(k, expected->voxel[2]);
    // The crosshair moved the other views through the point.
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Coronal)->grid().offset_mm, lps.y, 1e-6);
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Sagittal)->grid().offset_mm, lps.x, 1e-6);

    // ---- PageUp scrolls the axial view by one slice step
    const double before = axial->grid().offset_mm;
    QTest::keyClick(axial, Qt::Key_PageUp);
    EXPECT_NEAR(axial->grid().offset_mm, before + core::default_plane(v, core::SliceOrientation::Axial).step_mm, 1e-6);

    // ---- window presets set the numbers
    w.workspace().set_window(*core::ct_window_preset("bone"));
    EXPECT_EQ(w.workspace().window().center, core::ct_window_preset("bone")->center);

    // ---- add the skin surface (iso 500 on this CT) in the background
    w.surfaces_panel()->add_surface(500);
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 120000)) << "the extraction did not finish";
    const auto ids = w.scene().surfaces();
    ASSERT_EQ(ids.size(), 1u) << w.statusBar()->currentMessage().toStdString();
    EXPECT_EQ(w.scene().info(ids[0]).value, 500.0);
    EXPECT_GT(w.scene().mesh(ids[0]).triangles.size(), 10000u);
    w.workspace().set_window(core::default_window(v));
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal})
        EXPECT_GT(w.slice_view(o)->outline_segments(), 50u) << core::slice_orientation_name(o) << ": no skin outline";
    // ---- the same outlines worked out and painted on the pool thread (a massive surface's way)
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal}) {
        gui::SliceView* sv = w.slice_view(o);
        const std::size_t segments = sv->outline_segments();
        const QImage here = sv->grab().toImage().convertToFormat(QImage::Format_RGB32);
        sv->set_inline_triangles(0);
        sv->refresh();
        EXPECT_TRUE(sv->outlines_waiting());
        ASSERT_TRUE(wait_until([&] { return !sv->outlines_waiting(); }, 30000));
        EXPECT_EQ(sv->outline_segments(), segments) << core::slice_orientation_name(o);
        const QImage pooled = sv->grab().toImage().convertToFormat(QImage::Format_RGB32);
        ASSERT_EQ(pooled.size(), here.size());
        // Painted into an image and blended, or painted on the view: antialiased edges may differ by rounding.
        std::size_t differ = 0;
        for (int y = 0; y < here.height(); ++y)
            for (int x = 0; x < here.width(); ++x) {
                const QRgb a = here.pixel(x, y), b = pooled.pixel(x, y);
                differ += std::abs(qRed(a) - qRed(b)) > 8 || std::abs(qGreen(a) - qGreen(b)) > 8 ||
                          std::abs(qBlue(a) - qBlue(b)) > 8;
            }
        EXPECT_LT(differ, std::size_t(here.width()) * here.height() / 1000) << core::slice_orientation_name(o);
        sv->set_inline_triangles(gui::SliceView::kInlineTriangles);
    }
    ASSERT_NE(w.viewer(), nullptr);
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > 0 || !w.viewer()->error().empty(); }, 60000));
    EXPECT_TRUE(w.viewer()->error().empty()) << w.viewer()->error();

    // ---- a screenshot of the window into the test's output folder
    const std::filesystem::path out = test::output_dir("main_window");
    QTest::qWait(200);
    const QImage shot = w.grab().toImage();
    EXPECT_TRUE(shot.save(QString::fromStdString((out / "main_window.png").string())));
    std::printf("screenshot: %s\n", (out / "main_window.png").c_str());

    // ---- a broken file: a dialog names it, the window stays as it was
    const std::string broken = dir / "broken.nrrd";
    std::ofstream(broken) << "this is not a NRRD file\n\x01\x02\x03 garbage";
    w.open_path(QString::fromStdString(broken));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    QMessageBox* box = nullptr;
    ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>("error")) && box->isVisible(); }, 10000));
    EXPECT_TRUE(box->text().contains("broken.nrrd")) << box->text().toStdString();
    std::printf("error dialog: %s\n", box->text().toStdString().c_str());
    box->close();
    QTest::qWait(50);
    EXPECT_TRUE(w.isVisible());
    EXPECT_TRUE(w.scene().has_volume());
    EXPECT_EQ(w.scene().surfaces().size(), 1u);
    // Still usable: another click answers.
    QTest::mouseClick(axial, Qt::LeftButton, {}, QPoint(axial->width() / 2, axial->height() / 2));
    EXPECT_EQ(w.statusBar()->currentMessage().left(5), "LPS (");

    // ---- dropping a file opens it: a new scene without surfaces, the 3D view's placeholder back
    {
        QMimeData mime;
        mime.setUrls({QUrl::fromLocalFile(QString::fromStdString(headsq))});
        // Straight to the window's event handler: QApplication routes drag
        // events only during a drag the platform started.
        QObject* target = &w;
        QDragEnterEvent enter(QPoint(200, 200), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
        target->event(&enter);
        EXPECT_TRUE(enter.isAccepted()) << "a local file is refused";
        QDropEvent drop(QPointF(200, 200), Qt::CopyAction, &mime, Qt::LeftButton, Qt::NoModifier);
        const core::Scene* before_drop = &w.scene();
        target->event(&drop);
        // The surface added above is unsaved work: the window asks first (docs/gui.md "Unsaved work").
        QMessageBox* ask = nullptr;
        ASSERT_TRUE(wait_until([&] { return (ask = w.findChild<QMessageBox*>("unsaved")) && ask->isVisible(); }, 5000));
        QTest::mouseClick(ask->button(QMessageBox::Discard), Qt::LeftButton);
        // The load may start and end within one wait step: wait for the new scene.
        ASSERT_TRUE(wait_until([&] { return &w.scene() != before_drop && !w.busy(); }, 60000))
            << "the drop opened nothing: " << w.statusBar()->currentMessage().toStdString();
        EXPECT_TRUE(w.scene().has_volume());
        EXPECT_TRUE(w.scene().surfaces().empty());
        EXPECT_EQ(w.viewer(), nullptr);
        EXPECT_TRUE(w.slice_view(core::SliceOrientation::Sagittal)->has_image());
    }
}
