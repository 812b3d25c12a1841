// Pick and measure in the desktop app (docs/gui.md "Pick and
// measure"), driven in-process through QTest in a real X server (CTest runs
// this program under xvfb-run). Expected values come from the core API and the CLI
// (`isoscope pick`: core::pick, render_image's own frame in another process;
// core::pixel_to_lps, iso::distance_mm / angle_deg, io/markups), not from
// the window's own state.
#include <QApplication>
#include <QElapsedTimer>
#include <QMessageBox>
#include <QMouseEvent>
#include <QSlider>
#include <QStatusBar>
#include <QTableWidget>
#include <QTest>
#include <QToolButton>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "app/gui/main_window.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/measurements_panel.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "io/markups.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/iso/measure.hpp"
#include "renderer/render/overlay.hpp"
#include "gui_test_util.hpp"

using namespace iso;

namespace {
using test::wait_until;
// The readout prints 2 decimals: the printed number is within half a unit of the last digit.
constexpr double kPrinted = 0.005 + 1e-9;

struct Readout {
    glm::dvec3 lps{0.0};
    double value = 0;
    std::string surface;
};

// "LPS (x, y, z) mm, value v, surface NAME" (headsq is not CT: "value", not "HU").
std::optional<Readout> parse_readout(const std::string& s) {
    Readout r;
    char name[128] = {};
    if (std::sscanf(s.c_str(), "LPS (%lf, %lf, %lf) mm, value %lf, surface %127[^\n]", &r.lps.x, &r.lps.y, &r.lps.z, &r.value, name) != 5)
        return std::nullopt;
    r.surface = name;
    return r;
}

double parse_value(const QString& text) { return std::stod(text.toStdString()); }

QTableWidget* panel_table(gui::MainWindow& w) { return w.measurements_panel()->table(); }

// The pointer moving over the view with no button held, delivered at once
// (QTest::mouseMove also moves the X server's pointer, whose motion events
// arrive later, spread over time).
void hover(QWidget* w, QPoint at) {
    QMouseEvent e(QEvent::MouseMove, QPointF(at), w->mapToGlobal(QPointF(at)), Qt::NoButton, Qt::NoButton, Qt::NoModifier);
    QCoreApplication::sendEvent(w, &e);
}

} // namespace

TEST(GuiMeasure, PickReadoutRulerAngleMarkupsSaveAndLoad) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_measure_test", dir / "config");
    const std::filesystem::path out = test::output_dir("gui_measure");

    gui::MainWindow w;
    w.resize(1400, 1000);
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    const std::string headsq = test::data("headsq.nhdr");
    w.open_path(QString::fromStdString(headsq));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    ASSERT_TRUE(w.scene().has_volume());
    // The skin at opacity 0.3 (through the Surfaces dock's slider) over the bone: the pick is what is seen.
    for (const double iso : {500.0, 1150.0}) {
        w.add_surface(iso);
        ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 120000)) << "the extraction did not finish";
    }
    ASSERT_EQ(w.scene().surfaces().size(), 2u);
    auto* skin_opacity = w.findChild<QWidget*>("surface_1")->findChild<QSlider*>("opacity");
    ASSERT_NE(skin_opacity, nullptr);
    skin_opacity->setValue(30);
    ASSERT_FLOAT_EQ(w.scene().info(1).opacity, 0.3f);
    gui::Viewer* viewer = w.viewer();
    ASSERT_NE(viewer, nullptr);
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > 0 || !viewer->error().empty(); }, 60000));
    ASSERT_TRUE(viewer->error().empty()) << viewer->error();

    // The camera `isoscope pick` uses for this image size: the scene's
    // anterior view at the image's aspect (what the view starts with; set
    // here so that a resize between its first frame and now cannot matter).
    const QSize size = viewer->image_size();
    viewer->set_camera(w.scene().camera(PatientView::Anterior, double(size.width()) / double(size.height())));
    const int frames = viewer->frames();
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > frames; }, 30000));

    // ---- a click in the 3D view: the status bar says what core::pick finds there
    const QPoint at(size.width() / 2 + 11, int(size.height() * 0.42)); // device pixel ratio 1 under Xvfb
    QTest::mouseClick(viewer, Qt::LeftButton, {}, at);
    const std::string msg = w.statusBar()->currentMessage().toStdString();
    std::printf("3D click at %d,%d: %s\n", at.x(), at.y(), msg.c_str());
    const auto shown = parse_readout(msg);
    ASSERT_TRUE(shown) << msg;
    const auto cli = test::run_command(test::cli() + " pick " + headsq + " --iso 500 --iso 1150 --opacity 0.3 --opacity 1 --size " + std::to_string(size.width()) + "x" +
                                       std::to_string(size.height()) + " --at " + std::to_string(at.x()) + "," +
                                       std::to_string(at.y()) + " --json");
    ASSERT_EQ(cli.exit_code, 0) << cli.out;
    const auto j = nlohmann::json::parse(cli.out);
    ASSERT_TRUE(j["visible"].is_number()) << "the pixel should see the head: " << cli.out;
    const auto& layer = j["layers"][j["visible"].get<std::size_t>()];
    EXPECT_EQ(layer["surface"], "iso 1150") << "through the skin at 0.3 the bone is what is seen: " << cli.out;
    const glm::dvec3 expected{layer["lps"][0].get<double>(), layer["lps"][1].get<double>(), layer["lps"][2].get<double>()};
    EXPECT_NEAR(shown->lps.x, expected.x, kPrinted);
    EXPECT_NEAR(shown->lps.y, expected.y, kPrinted);
    EXPECT_NEAR(shown->lps.z, expected.z, kPrinted);
    EXPECT_NEAR(shown->value, layer["hu"].get<double>(), kPrinted);
    EXPECT_EQ(shown->surface, layer["surface"].get<std::string>());
    // ... and the slice views' crosshair moved there (each plane through the point).
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Axial)->grid().offset_mm, expected.z, 1e-6);
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Coronal)->grid().offset_mm, expected.y, 1e-6);
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Sagittal)->grid().offset_mm, expected.x, 1e-6);

    // A background pixel says so.
    QTest::mouseClick(viewer, Qt::LeftButton, {}, QPoint(3, 3));
    EXPECT_EQ(w.statusBar()->currentMessage(), "background");

    // ---- hovering: throttled picks, the latest position wins
    auto* tools = w.measure_tools();
    {
        const int before = tools->hover_picks();
        hover(viewer, QPoint(at.x() - 30, at.y()));
        ASSERT_TRUE(wait_until([&] { return tools->hover_picks() > before; }, 5000)) << "no hover pick";
        const auto hovered = viewer->pick_at(QPointF(at.x() - 30 + 0.5, at.y() + 0.5));
        EXPECT_EQ(w.statusBar()->currentMessage(), tools->readout(hovered));
        // A burst of moves at once: one pick, for the last position.
        const int burst = tools->hover_picks();
        const QPoint last(at.x() + 20, at.y() + 25);
        QTest::qWait(2 * tools->hover_interval_ms()); // an idle pointer
        for (int k = 0; k < 10; ++k) hover(viewer, QPoint(at.x() - 20 + 4 * k, at.y() + 2 * k + 7));
        hover(viewer, last);
        QTest::qWait(3 * tools->hover_interval_ms());
        EXPECT_EQ(tools->hover_picks() - burst, 1) << "hover picks are not throttled";
        EXPECT_EQ(w.statusBar()->currentMessage(), tools->readout(viewer->pick_at(QPointF(last) + QPointF(0.5, 0.5))));
        // A pointer moving for 2 s, a move every 10 ms: at most one pick per
        // interval (80 ms or more), and the readout follows.
        const int moving = tools->hover_picks();
        QElapsedTimer t;
        t.start();
        // At least 2 s; on a loaded machine (picks slow, the interval adapts
        // upwards) on until two picks came, at most 10 s.
        for (int k = 0; t.elapsed() < 2000 || (tools->hover_picks() - moving < 2 && t.elapsed() < 10000); ++k) {
            hover(viewer, QPoint(at.x() - 40 + (k % 80), at.y() + 30));
            QTest::qWait(10);
        }
        const double seconds = t.elapsed() / 1000.0;
        const int picks = tools->hover_picks() - moving;
        std::printf("hover: %d picks in %.2f s of moving, interval now %d ms\n", picks, seconds, tools->hover_interval_ms());
        EXPECT_GE(picks, 2) << "the readout does not follow a moving pointer";
        EXPECT_LE(picks, int(seconds * 1000 / 80) + 1) << "hover picks are not throttled";
    }

    // ---- rotate with the mouse (left drag), then click: the readout is
    // core::pick's with the view's camera (a fresh scene of the same state,
    // on a worker thread: render_image has its own EGL context)
    {
        const Camera before = viewer->camera();
        const QPoint from(size.width() / 2, size.height() / 2), to = from + QPoint(70, -25);
        // Events straight to the view (QTest::mouseMove moves the X pointer, whose events arrive later).
        const auto send = [&](QEvent::Type type, QPoint at, Qt::MouseButtons held) {
            const Qt::MouseButton button = type == QEvent::MouseMove ? Qt::NoButton : Qt::LeftButton;
            QMouseEvent e(type, QPointF(at), viewer->mapToGlobal(QPointF(at)), button, held, Qt::NoModifier);
            QCoreApplication::sendEvent(viewer, &e);
        };
        send(QEvent::MouseButtonPress, from, Qt::LeftButton);
        for (int k = 1; k <= 5; ++k) send(QEvent::MouseMove, from + (to - from) * k / 5, Qt::LeftButton);
        send(QEvent::MouseButtonRelease, to, Qt::NoButton);
        const Camera turned = viewer->camera();
        ASSERT_GT(glm::length(turned.eye - before.eye), 1.0) << "the left drag did not rotate the view";
        const int drawn = viewer->frames();
        ASSERT_TRUE(wait_until([&] { return viewer->frames() > drawn; }, 30000));
        const QPoint px(size.width() / 2 - 14, int(size.height() * 0.47));
        QTest::mouseClick(viewer, Qt::LeftButton, {}, px);
        const std::string turned_msg = w.statusBar()->currentMessage().toStdString();
        std::printf("3D click after rotating, at %d,%d: %s\n", px.x(), px.y(), turned_msg.c_str());
        const auto got = parse_readout(turned_msg);
        ASSERT_TRUE(got) << turned_msg;
        core::PickResult ref;
        std::string error;
        std::thread worker([&] {
            try {
                core::Scene s;
                s.open(headsq);
                const auto ids = s.add_isosurfaces({500, 1150});
                s.info(ids[0]).opacity = 0.3f;
                core::RenderRequest req;
                req.width = size.width();
                req.height = size.height();
                req.camera = turned;
                core::PickRequest at_px;
                at_px.x = px.x();
                at_px.y = px.y();
                ref = core::pick(s, req, at_px);
            } catch (const std::exception& e) {
                error = e.what();
            }
        });
        worker.join();
        ASSERT_TRUE(error.empty()) << error;
        ASSERT_TRUE(ref.visible.has_value()) << "the pixel should see the head after the turn";
        const auto& l = ref.layers[*ref.visible];
        EXPECT_NEAR(got->lps.x, l.lps.x, kPrinted);
        EXPECT_NEAR(got->lps.y, l.lps.y, kPrinted);
        EXPECT_NEAR(got->lps.z, l.lps.z, kPrinted);
        ASSERT_TRUE(l.hu.has_value());
        EXPECT_NEAR(got->value, *l.hu, kPrinted);
        EXPECT_EQ(got->surface, l.name);
        viewer->set_camera(w.scene().camera(PatientView::Anterior, double(size.width()) / double(size.height())));
    }

    // What a pick costs in the view (docs/gui.md): the frame it rides on, presented, and the resolve.
    {
        std::vector<double> ms;
        for (int k = 0; k < 5; ++k) ms.push_back(viewer->pick_at(QPointF(at) + QPointF(0.5, 0.5)).frame_ms);
        std::sort(ms.begin(), ms.end());
        std::printf("3D view pick at %dx%d: median %.1f ms, min %.1f, max %.1f of 5\n", size.width(), size.height(), ms[2], ms[0],
                    ms[4]);
    }
    // Picks leave the view's AO accumulation alone: the next frame adds to it.
    if (viewer->options().ao) {
        ASSERT_TRUE(wait_until([&] { return viewer->converged(); }, 120000)) << "the AO did not converge";
        const int ao_frames = viewer->ao_frames(), drawn = viewer->frames();
        viewer->pick_at(QPointF(at));
        viewer->update();
        ASSERT_TRUE(wait_until([&] { return viewer->frames() > drawn; }, 10000));
        EXPECT_EQ(viewer->ao_frames(), ao_frames + 1) << "a pick restarted the view's AO accumulation";
    }

    // ---- ruler on the axial view: two clicks
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const double axial_offset = axial->grid().offset_mm;
    const QPoint a0(axial->width() / 2 - 60, axial->height() / 2 + 10), a1(axial->width() / 2 + 55, axial->height() / 2 + 10);
    tools->ruler_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::MeasureTools::Tool::Ruler);
    const core::SliceGrid grid = axial->grid();
    QTest::mouseClick(axial, Qt::LeftButton, {}, a0);
    EXPECT_EQ(tools->pending().size(), 1u);
    EXPECT_TRUE(w.markups().empty());
    QTest::mouseClick(axial, Qt::LeftButton, {}, a1);
    const auto lps = [&](QPoint p) { return core::pixel_to_lps(grid, {double(p.x()), double(p.y())}); };
    ASSERT_EQ(w.markups().size(), 1u);
    {
        const Markup& m = w.markups()[0];
        EXPECT_EQ(m.type, MarkupType::Line);
        ASSERT_EQ(m.points.size(), 2u);
        EXPECT_NEAR(glm::length(m.points[0].position - lps(a0)), 0.0, 1e-9);
        EXPECT_NEAR(glm::length(m.points[1].position - lps(a1)), 0.0, 1e-9);
    }
    EXPECT_EQ(axial->grid().offset_mm, axial_offset) << "a tool's click does not move the crosshair";
    const double distance = iso::distance_mm(lps(a0), lps(a1));

    // ---- angle on the axial view: three clicks (arm, vertex, arm)
    const QPoint b0(axial->width() / 2 - 40, axial->height() / 2 - 50), b1(axial->width() / 2, axial->height() / 2 - 10),
        b2(axial->width() / 2 + 45, axial->height() / 2 - 70);
    tools->angle_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::MeasureTools::Tool::Angle);
    EXPECT_FALSE(tools->ruler_action()->isChecked());
    // Escape drops a point placed by mistake (the tool stays on).
    w.activateWindow();
    ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
    QTest::mouseClick(axial, Qt::LeftButton, {}, QPoint(axial->width() / 2 + 90, axial->height() / 2 + 90));
    EXPECT_EQ(tools->pending().size(), 1u);
    QTest::keyClick(axial, Qt::Key_Escape);
    EXPECT_TRUE(tools->pending().empty()) << "Escape did not drop the point";
    EXPECT_EQ(tools->tool(), gui::MeasureTools::Tool::Angle);
    for (const QPoint& p : {b0, b1, b2}) QTest::mouseClick(axial, Qt::LeftButton, {}, p);
    ASSERT_EQ(w.markups().size(), 2u);
    EXPECT_EQ(w.markups()[1].type, MarkupType::Angle);
    const double angle = iso::angle_deg(lps(b0), lps(b1), lps(b2));

    // The panel lists both, with the core's values (to the printed decimals).
    QTableWidget* table = panel_table(w);
    ASSERT_EQ(table->rowCount(), 2);
    EXPECT_EQ(table->item(0, gui::MeasurementsPanel::Kind)->text(), "Line");
    EXPECT_EQ(table->item(1, gui::MeasurementsPanel::Kind)->text(), "Angle");
    const QString dist_text = table->item(0, gui::MeasurementsPanel::Value)->text();
    const QString angle_text = table->item(1, gui::MeasurementsPanel::Value)->text();
    std::printf("panel: %s %s, %s %s (core: %.4f mm, %.4f deg)\n", table->item(0, 0)->text().toStdString().c_str(),
                dist_text.toStdString().c_str(), table->item(1, 0)->text().toStdString().c_str(), angle_text.toStdString().c_str(),
                distance, angle);
    EXPECT_TRUE(dist_text.endsWith(" mm")) << dist_text.toStdString();
    EXPECT_NEAR(parse_value(dist_text), distance, kPrinted);
    EXPECT_TRUE(angle_text.endsWith(QChar(0x00B0))) << angle_text.toStdString();
    EXPECT_NEAR(parse_value(angle_text), angle, kPrinted);

    // The axial view draws them: the ruler's segment in the line colour at its middle.
    {
        QTest::qWait(50);
        const QImage img = axial->grab().toImage();
        const QColor c = img.pixelColor((a0.x() + a1.x()) / 2, a0.y());
        const glm::vec3 want = markup_color(w.markups()[0]) * 255.0f;
        EXPECT_NEAR(c.red(), want.r, 40) << "no ruler drawn on the axial view";
        EXPECT_NEAR(c.green(), want.g, 40);
        EXPECT_NEAR(c.blue(), want.b, 40);
        EXPECT_TRUE(img.save(QString::fromStdString((out / "axial.png").string())));
    }

    // ---- a ruler in the 3D view: its points are the pick's visible layer
    tools->ruler_action()->trigger();
    const QPoint c0 = at, c1(at.x() - 40, at.y() + 60);
    QTest::mouseClick(viewer, Qt::LeftButton, {}, c0);
    QTest::mouseClick(viewer, Qt::LeftButton, {}, c1);
    ASSERT_EQ(w.markups().size(), 3u) << w.statusBar()->currentMessage().toStdString();
    {
        const Markup& m = w.markups()[2];
        ASSERT_EQ(m.points.size(), 2u);
        EXPECT_NEAR(glm::length(m.points[0].position - expected), 0.0, 1e-6) << "the 3D point is not core::pick's";
        const auto p1 = viewer->pick_at(QPointF(c1) + QPointF(0.5, 0.5));
        ASSERT_TRUE(p1.visible);
        EXPECT_NEAR(glm::length(m.points[1].position - p1.layers[*p1.visible].lps), 0.0, 1e-9);
        EXPECT_NEAR(parse_value(table->item(2, gui::MeasurementsPanel::Value)->text()),
                    iso::distance_mm(m.points[0].position, m.points[1].position), kPrinted);
    }
    tools->set_tool(gui::MeasureTools::Tool::None);
    QTest::qWait(200);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "gui_measure.png").string())));
    std::printf("screenshots: %s\n", out.c_str());

    // ---- rename one (what the table's editor commits), delete one
    table->item(0, gui::MeasurementsPanel::Name)->setText("head width");
    EXPECT_EQ(w.markups()[0].name, "head width");
    auto* del = qobject_cast<QToolButton*>(table->cellWidget(2, gui::MeasurementsPanel::Delete));
    ASSERT_NE(del, nullptr);
    del->click();
    ASSERT_TRUE(wait_until([&] { return w.markups().size() == 2; }, 5000)) << "the delete button did nothing";
    EXPECT_EQ(table->rowCount(), 2);
    EXPECT_EQ(table->item(0, gui::MeasurementsPanel::Name)->text(), "head width");
    const std::string angle_name = w.markups()[1].name;

    // ---- save as .mrk.json, read back through io/markups
    const std::string saved = dir / "measurements.mrk.json";
    ASSERT_TRUE(w.measurements_panel()->save(QString::fromStdString(saved)));
    const MarkupsFile f = load_markups(saved);
    ASSERT_EQ(f.markups.size(), 2u);
    EXPECT_EQ(f.markups[0].name, "head width");
    EXPECT_EQ(f.markups[1].name, angle_name);
    EXPECT_EQ(f.markups[0].type, MarkupType::Line);
    EXPECT_EQ(f.markups[1].type, MarkupType::Angle);
    for (std::size_t i = 0; i < 2; ++i) {
        ASSERT_EQ(f.markups[i].points.size(), w.markups()[i].points.size());
        for (std::size_t k = 0; k < f.markups[i].points.size(); ++k)
            EXPECT_NEAR(glm::length(f.markups[i].points[k].position - w.markups()[i].points[k].position), 0.0, 1e-9);
    }
    EXPECT_NEAR(glm::length(f.markups[1].points[2].position - lps(b2)), 0.0, 1e-9);

    // A file that cannot be written: a dialog names it, nothing changes.
    {
        const QString bad = QString::fromStdString((dir.path() / "no such folder" / "m.mrk.json").string());
        EXPECT_FALSE(w.measurements_panel()->save(bad));
        QMessageBox* box = nullptr;
        ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>("error")) && box->isVisible(); }, 5000));
        EXPECT_TRUE(box->text().contains("m.mrk.json")) << box->text().toStdString();
        box->close();
        QTest::qWait(50);
        EXPECT_EQ(w.markups().size(), 2u);
    }

    // ---- a fresh window loads them: the panel lists them with the same values
    {
        gui::MainWindow w2;
        w2.resize(1200, 900);
        w2.show();
        ASSERT_TRUE(QTest::qWaitForWindowExposed(&w2));
        w2.open_path(QString::fromStdString(headsq));
        ASSERT_TRUE(wait_until([&] { return !w2.busy(); }, 60000));
        // A broken file first: a dialog names it, nothing is loaded.
        const std::string broken = dir / "broken.mrk.json";
        std::ofstream(broken) << "{\"@schema\": \"not markups\"";
        EXPECT_FALSE(w2.measurements_panel()->load(QString::fromStdString(broken)));
        QMessageBox* box = nullptr;
        ASSERT_TRUE(wait_until([&] { return (box = w2.findChild<QMessageBox*>("error")) && box->isVisible(); }, 5000));
        EXPECT_TRUE(box->text().contains("broken.mrk.json")) << box->text().toStdString();
        box->close();
        EXPECT_TRUE(w2.markups().empty());

        ASSERT_TRUE(w2.measurements_panel()->load(QString::fromStdString(saved)));
        QTableWidget* t2 = panel_table(w2);
        ASSERT_EQ(t2->rowCount(), 2);
        EXPECT_EQ(t2->item(0, gui::MeasurementsPanel::Name)->text(), "head width");
        EXPECT_EQ(t2->item(1, gui::MeasurementsPanel::Name)->text().toStdString(), angle_name);
        EXPECT_NEAR(parse_value(t2->item(0, gui::MeasurementsPanel::Value)->text()), distance, kPrinted);
        EXPECT_NEAR(parse_value(t2->item(1, gui::MeasurementsPanel::Value)->text()), angle, kPrinted);
        // On the axial slice they were measured on, the ruler is drawn again.
        w2.set_crosshair(lps(a0));
        QTest::qWait(50);
        auto* axial2 = w2.slice_view(core::SliceOrientation::Axial);
        EXPECT_NEAR(axial2->grid().offset_mm, axial_offset, 1e-6);
        EXPECT_TRUE(axial2->grab().toImage().save(QString::fromStdString((out / "axial_loaded.png").string())));
    }
}
