// The desktop app's Measurements panel with files (docs/gui.md "Pick and
// measure"): renaming and deleting rows, saving as .mrk.json (read back
// through io/markups), a file that cannot be written, and loading into a
// fresh window (a broken file first). Driven in-process through QTest in a
// real X server (CTest runs this program under xvfb-run; it skips without a
// display). Expected values come from io/markups and the core's
// core::pixel_to_lps, iso::distance_mm / angle_deg, not from the window's
// own state.
#include <QMessageBox>
#include <QTest>
#include <QToolButton>

#include <filesystem>

#include "gui_measure_util.hpp"
#include "io/markups.hpp"
#include "renderer/surface/analysis.hpp"

using namespace iso;
using namespace iso::test;
using GuiMarkupsFile = HeadWindow;

TEST_F(GuiMarkupsFile, RenameDeleteSaveAndLoadInAFreshWindow) {
    const std::filesystem::path out = output_dir("gui_measure");
    gui::MainWindow& w = window();
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const double axial_offset = axial->grid().offset_mm;
    const core::SliceGrid grid = axial->grid();
    const auto lps = [&](QPoint p) { return lps_of(grid, p); };
    // A ruler and an angle to keep, and a third markup (a ruler) to delete.
    const std::vector<QPoint> a = ruler_pixels(w), b = angle_pixels(w);
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Ruler, a));
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Angle, b));
    ASSERT_NO_FATAL_FAILURE(
        click_on_axial(w, gui::MeasureTools::Tool::Ruler, {axial_pixel(w, -30, 40), axial_pixel(w, 30, 60)}));
    w.measure_tools()->set_tool(gui::MeasureTools::Tool::None);
    ASSERT_EQ(w.workspace().markups().size(), 3u);
    const double distance = iso::distance_mm(lps(a[0]), lps(a[1]));
    const double angle = iso::angle_deg(lps(b[0]), lps(b[1]), lps(b[2]));

    // ---- rename one (what the table's editor commits), delete one
    QTableWidget* table = panel_table(w);
    table->item(0, gui::MeasurementsPanel::Name)->setText("head width");
    EXPECT_EQ(w.workspace().markups()[0].name, "head width");
    auto* del = qobject_cast<QToolButton*>(table->cellWidget(2, gui::MeasurementsPanel::Delete));
    ASSERT_NE(del, nullptr);
    del->click();
    ASSERT_TRUE(wait_until([&] { return w.workspace().markups().size() == 2; }, 5000))
        << "the delete button did nothing";
    EXPECT_EQ(table->rowCount(), 2);
    EXPECT_EQ(table->item(0, gui::MeasurementsPanel::Name)->text(), "head width");
    const std::string angle_name = w.workspace().markups()[1].name;

    // ---- save as .mrk.json, read back through io/markups
    const std::string saved = dir() / "measurements.mrk.json";
    ASSERT_TRUE(w.measurements_panel()->save(QString::fromStdString(saved)));
    const MarkupsFile f = load_markups(saved);
    ASSERT_EQ(f.markups.size(), 2u);
    EXPECT_EQ(f.markups[0].name, "head width");
    EXPECT_EQ(f.markups[1].name, angle_name);
    EXPECT_EQ(f.markups[0].type, MarkupType::Line);
    EXPECT_EQ(f.markups[1].type, MarkupType::Angle);
    for (std::size_t i = 0; i < 2; ++i) {
        ASSERT_EQ(f.markups[i].points.size(), w.workspace().markups()[i].points.size());
        for (std::size_t k = 0; k < f.markups[i].points.size(); ++k)
            EXPECT_NEAR(glm::length(f.markups[i].points[k].position - w.workspace().markups()[i].points[k].position),
                        0.0, 1e-9);
    }
    EXPECT_NEAR(glm::length(f.markups[1].points[2].position - lps(b[2])), 0.0, 1e-9);

    // A file that cannot be written: a dialog names it, nothing changes.
    {
        const QString bad = QString::fromStdString((dir().path() / "no such folder" / "m.mrk.json").string());
        EXPECT_FALSE(w.measurements_panel()->save(bad));
        QMessageBox* box = nullptr;
        ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>("error")) && box->isVisible(); }, 5000));
        EXPECT_TRUE(box->text().contains("m.mrk.json")) << box->text().toStdString();
        box->close();
        QTest::qWait(50);
        EXPECT_EQ(w.workspace().markups().size(), 2u);
    }

    // ---- a fresh window loads them: the panel lists them with the same values
    gui::MainWindow w2;
    w2.resize(1200, 900);
    w2.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w2));
    w2.open_path(QString::fromStdString(headsq()));
    ASSERT_TRUE(wait_until([&] { return !w2.busy(); }, 60000));
    // A broken file first: a dialog names it, nothing is loaded.
    const std::string broken = dir() / "broken.mrk.json";
    write_file(broken, "{\"@schema\": \"not markups\"");
    EXPECT_FALSE(w2.measurements_panel()->load(QString::fromStdString(broken)));
    QMessageBox* box = nullptr;
    ASSERT_TRUE(wait_until([&] { return (box = w2.findChild<QMessageBox*>("error")) && box->isVisible(); }, 5000));
    EXPECT_TRUE(box->text().contains("broken.mrk.json")) << box->text().toStdString();
    box->close();
    EXPECT_TRUE(w2.workspace().markups().empty());

    ASSERT_TRUE(w2.measurements_panel()->load(QString::fromStdString(saved)));
    QTableWidget* t2 = panel_table(w2);
    ASSERT_EQ(t2->rowCount(), 2);
    EXPECT_EQ(t2->item(0, gui::MeasurementsPanel::Name)->text(), "head width");
    EXPECT_EQ(t2->item(1, gui::MeasurementsPanel::Name)->text().toStdString(), angle_name);
    EXPECT_NEAR(parse_value(t2->item(0, gui::MeasurementsPanel::Value)->text()), distance, kPrinted);
    EXPECT_NEAR(parse_value(t2->item(1, gui::MeasurementsPanel::Value)->text()), angle, kPrinted);
    // On the axial slice they were measured on, the ruler is drawn again.
    w2.workspace().set_crosshair(lps(a[0]));
    QTest::qWait(50);
    auto* axial2 = w2.slice_view(core::SliceOrientation::Axial);
    EXPECT_NEAR(axial2->grid().offset_mm, axial_offset, 1e-6);
    EXPECT_TRUE(axial2->grab().toImage().save(QString::fromStdString((out / "axial_loaded.png").string())));
}
