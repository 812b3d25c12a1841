// Measuring in the desktop app (docs/gui.md "Pick and measure"): rulers and
// angles placed by clicks on the axial view and in the 3D view, listed in the
// Measurements panel and drawn. Driven in-process through QTest in a real X
// server (CTest runs this program under xvfb-run; it skips without a
// display). Expected values come from the core API and the CLI
// (core::pixel_to_lps, iso::distance_mm / angle_deg, `isoscope pick`), not
// from the window's own state. Saving and loading: gui_markups_file_test.cpp.
#include <QStatusBar>
#include <QTest>

#include <cstdio>
#include <filesystem>

#include "gui_measure_util.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/frame/annotations.hpp"
#include "gui_test_util.hpp"

using namespace iso;
using namespace iso::test;
using GuiMeasure = HeadWindow;

// Ruler (two clicks), then Angle with a stray click dropped by Escape (three
// clicks): the markups' points, the axial slice kept and the other views
// moved to the point, the panel's values, and the ruler drawn on the axial view.
TEST_F(GuiMeasure, RulerAndAngleOnTheAxialView) {
    const std::filesystem::path out = output_dir("gui_measure");
    gui::MainWindow& w = window();
    auto* tools = w.measure_tools();
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const double axial_offset = axial->grid().offset_mm;
    const core::SliceGrid grid = axial->grid();
    const auto lps = [&](QPoint p) { return lps_of(grid, p); };

    const std::vector<QPoint> a = ruler_pixels(w);
    tools->ruler_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::MeasureTools::Tool::Ruler);
    QTest::mouseClick(axial, Qt::LeftButton, {}, a[0]);
    EXPECT_EQ(tools->pending().size(), 1u);
    EXPECT_TRUE(w.workspace().markups().empty());
    QTest::mouseClick(axial, Qt::LeftButton, {}, a[1]);
    ASSERT_EQ(w.workspace().markups().size(), 1u);
    {
        const Markup& m = w.workspace().markups()[0];
        EXPECT_EQ(m.type, MarkupType::Line);
        ASSERT_EQ(m.points.size(), 2u);
        EXPECT_NEAR(glm::length(m.points[0].position - lps(a[0])), 0.0, 1e-9);
        EXPECT_NEAR(glm::length(m.points[1].position - lps(a[1])), 0.0, 1e-9);
    }
    EXPECT_EQ(axial->grid().offset_mm, axial_offset) << "a point placed on the axial view keeps its slice";
    // The other views moved to the last point placed (the crosshair shows how deep it lies).
    for (auto o : {core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal}) {
        const core::SliceGrid& g = w.slice_view(o)->grid();
        EXPECT_NEAR(glm::dot(lps(a[1]), g.normal), g.offset_mm, 1e-9) << core::slice_orientation_name(o);
    }
    const double distance = iso::distance_mm(lps(a[0]), lps(a[1]));

    const std::vector<QPoint> b = angle_pixels(w);
    tools->angle_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::MeasureTools::Tool::Angle);
    EXPECT_FALSE(tools->ruler_action()->isChecked());
    // Escape drops a point placed by mistake (the tool stays on).
    w.activateWindow();
    ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
    QTest::mouseClick(axial, Qt::LeftButton, {}, axial_pixel(w, 90, 90));
    EXPECT_EQ(tools->pending().size(), 1u);
    QTest::keyClick(axial, Qt::Key_Escape);
    EXPECT_TRUE(tools->pending().empty()) << "Escape did not drop the point";
    EXPECT_EQ(tools->tool(), gui::MeasureTools::Tool::Angle);
    for (const QPoint& p : b) QTest::mouseClick(axial, Qt::LeftButton, {}, p);
    ASSERT_EQ(w.workspace().markups().size(), 2u);
    EXPECT_EQ(w.workspace().markups()[1].type, MarkupType::Angle);
    const double angle = iso::angle_deg(lps(b[0]), lps(b[1]), lps(b[2]));

    // The panel lists both, with the core's values (to the printed decimals).
    QTableWidget* table = panel_table(w);
    ASSERT_EQ(table->rowCount(), 2);
    EXPECT_EQ(table->item(0, gui::MeasurementsPanel::Kind)->text(), "Line");
    EXPECT_EQ(table->item(1, gui::MeasurementsPanel::Kind)->text(), "Angle");
    const QString dist_text = table->item(0, gui::MeasurementsPanel::Value)->text();
    const QString angle_text = table->item(1, gui::MeasurementsPanel::Value)->text();
    std::printf("panel: %s %s, %s %s (core: %.4f mm, %.4f deg)\n", table->item(0, 0)->text().toStdString().c_str(),
                dist_text.toStdString().c_str(), table->item(1, 0)->text().toStdString().c_str(),
                angle_text.toStdString().c_str(), distance, angle);
    EXPECT_TRUE(dist_text.endsWith(" mm")) << dist_text.toStdString();
    EXPECT_NEAR(parse_value(dist_text), distance, kPrinted);
    EXPECT_TRUE(angle_text.endsWith(QChar(0x00B0))) << angle_text.toStdString();
    EXPECT_NEAR(parse_value(angle_text), angle, kPrinted);

    // The axial view draws them: the ruler's segment in the line colour at its middle.
    QTest::qWait(50);
    const QImage img = axial->grab().toImage();
    const QColor c = img.pixelColor((a[0].x() + a[1].x()) / 2, a[0].y());
    const glm::vec3 want = markup_color(w.workspace().markups()[0]) * 255.0f;
    EXPECT_NEAR(c.red(), want.r, 40) << "no ruler drawn on the axial view";
    EXPECT_NEAR(c.green(), want.g, 40);
    EXPECT_NEAR(c.blue(), want.b, 40);
    EXPECT_TRUE(img.save(QString::fromStdString((out / "axial.png").string())));
}

// A ruler in the 3D view: its points are the pick's visible layer.
TEST_F(GuiMeasure, RulerInThe3DViewIsOnThePickedPoints) {
    const std::filesystem::path out = output_dir("gui_measure");
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    const QPoint c0 = face_pixel(size), c1(c0.x() - 40, c0.y() + 60);
    nlohmann::json layer;
    ASSERT_NO_FATAL_FAILURE(cli_pick(size, c0, layer));
    const glm::dvec3 expected = json_lps(layer);
    // The window as in docs/gui.md's screenshot: a ruler and an angle on the axial slice too.
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Ruler, ruler_pixels(w)));
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Angle, angle_pixels(w)));
    ASSERT_EQ(w.workspace().markups().size(), 2u);

    auto* tools = w.measure_tools();
    tools->ruler_action()->trigger();
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, c0));
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, c1));
    ASSERT_EQ(w.workspace().markups().size(), 3u) << w.statusBar()->currentMessage().toStdString();
    const Markup& m = w.workspace().markups()[2];
    ASSERT_EQ(m.points.size(), 2u);
    EXPECT_NEAR(glm::length(m.points[0].position - expected), 0.0, 1e-6) << "the 3D point is not core::pick's";
    const auto p1 = viewer->pick_at(QPointF(c1) + QPointF(0.5, 0.5));
    ASSERT_TRUE(p1.visible);
    EXPECT_NEAR(glm::length(m.points[1].position - p1.layers[*p1.visible].lps), 0.0, 1e-9);
    EXPECT_NEAR(parse_value(panel_table(w)->item(2, gui::MeasurementsPanel::Value)->text()),
                iso::distance_mm(m.points[0].position, m.points[1].position), kPrinted);
    tools->set_tool(gui::MeasureTools::Tool::None);
    QTest::qWait(200);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "gui_measure.png").string())));
    std::printf("screenshots: %s\n", out.c_str());
}
