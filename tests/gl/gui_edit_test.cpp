// Editing measurements in the desktop app (docs/gui.md "Pick and measure",
// "Editing"): a ruler on both cheeks in the 3D view landing on the front
// skin, dragging its point (3D and on a slice), Edit > Undo / Redo, a
// point list, loading a file twice (the Replace / Add / Cancel question)
// and selecting a row. Driven in-process through QTest in a real X server
// (CTest runs this program under xvfb-run; it skips without a display).
// Expected values come from the core API on a scene of its own (core::pick
// with every layer, core::solid_crossings, core::surface_at,
// iso::sample_volume, core::pixel_to_lps), not from the window's readouts.
#include <QAction>
#include <QMessageBox>
#include <QPushButton>
#include <QStatusBar>
#include <QTest>
#include <QToolButton>
#include <QUndoStack>

#include <cstdio>
#include <filesystem>
#include <thread>

#include "gui_measure_util.hpp"
#include "io/markups.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/surface/analysis.hpp"
#include "tests/support/contrast.hpp"

using namespace iso;
using namespace iso::test;
using GuiEdit = HeadWindow;

namespace {

bool only_skin(const core::PickResult& r) {
    if (r.layers.empty()) return false;
    for (const auto& l : r.layers)
        if (l.name != "iso 500") return false;
    return true;
}

// The pick's visible layer: the first surface whose own opacity reaches 0.5,
// else the nearest.
const core::PickLayer& seen(const core::PickResult& r) {
    for (const auto& l : r.layers)
        if (l.alpha >= 0.5) return l;
    return r.layers.front();
}

double min_y(const core::PickResult& r) {
    double y = 1e300;
    for (const auto& l : r.layers) y = std::min(y, l.lps.y);
    return y;
}

QAction* edit_action(gui::MainWindow& w, const char* name) { return w.findChild<QAction*>(name); }

QString cell(gui::MainWindow& w, int row, int col) { return panel_table(w)->item(row, col)->text(); }

} // namespace

// The case: skin at 0.3 over the bone, a ruler clicked on both
// cheeks beside the bone lands on the front of the face (not on the skin at
// the back of the head), then one point dragged, undone, redone, and the
// ruler deleted and brought back.
TEST_F(GuiEdit, CheekRulerOnTheFrontSkinDragUndoRedo) {
    const std::filesystem::path out = output_dir("gui_edit");
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    HeadOracle oracle(size, viewer->camera());
    ASSERT_TRUE(oracle.error().empty()) << oracle.error();

    // The cheeks: from the middle of the face outwards, the first pixels
    // whose every layer is skin (beside the bone).
    const int row = int(size.height() * 0.55);
    std::optional<QPoint> cheek[2];
    core::PickResult ref[2];
    for (int side = 0; side < 2; ++side)
        for (int dx = 40; dx < size.width() / 2 && !cheek[side]; dx += 6) {
            const QPoint px(size.width() / 2 + (side ? dx : -dx), row);
            const core::PickResult r = oracle.pick(px);
            ASSERT_TRUE(oracle.error().empty()) << oracle.error();
            if (only_skin(r) && r.layers.size() >= 2) {
                cheek[side] = px;
                ref[side] = r;
            }
        }
    ASSERT_TRUE(cheek[0] && cheek[1]) << "no pixel beside the bone with skin only on row " << row;
    std::printf("cheeks at (%d, %d) and (%d, %d): %zu and %zu skin layers\n", cheek[0]->x(), cheek[0]->y(),
                cheek[1]->x(), cheek[1]->y(), ref[0].layers.size(), ref[1].layers.size());

    const int surface_steps = w.undo_stack()->count(); // adding the surfaces and their opacity are steps too
    w.measure_tools()->ruler_action()->trigger();
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, *cheek[0]));
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, *cheek[1]));
    ASSERT_EQ(w.workspace().markups().size(), 1u) << w.statusBar()->currentMessage().toStdString();
    w.measure_tools()->set_tool(gui::MeasureTools::Tool::None);
    const Markup ruler = w.workspace().markups()[0];
    for (int k = 0; k < 2; ++k) {
        const glm::dvec3 p = ruler.points[std::size_t(k)].position;
        // The front skin: the layer nearest the eye, the face's front (smallest y,
        // anterior).
        EXPECT_NEAR(p.y, min_y(ref[k]), 2.0) << "point " << k << " is not on the front of the face";
        EXPECT_NEAR(glm::length(p - ref[k].layers.front().lps), 0.0, 1e-6) << "point " << k;
    }
    const double width = iso::distance_mm(ref[0].layers.front().lps, ref[1].layers.front().lps);
    const QString value = cell(w, 0, gui::MeasurementsPanel::Value);
    std::printf("cheek to cheek: %s (core: %.3f mm)\n", value.toStdString().c_str(), width);
    EXPECT_NEAR(parse_value(value), width, kPrinted);
    // Both points on the skin; what the line passes through, as the core says.
    EXPECT_EQ(cell(w, 0, gui::MeasurementsPanel::Surface), "iso 500 / iso 500");
    QString notes;
    for (const auto& c : core::solid_crossings(oracle.scene(), ruler.points[0].position, ruler.points[1].position))
        notes += QString(notes.isEmpty() ? "passes through " : ", ") +
                 QString("%1 at %2 mm").arg(QString::fromStdString(c.name)).arg(c.along_mm, 0, 'f', 1);
    EXPECT_EQ(cell(w, 0, gui::MeasurementsPanel::Notes), notes);
    std::printf("notes: %s\n", notes.toStdString().c_str());

    // ---- the ruler's label, as the window shows it: WCAG AA contrast (4.5:1)
    // between its text and the halo around it, read from the window's own
    // framebuffer (the label's masks say which pixel is which).
    {
        QTest::qWait(50);
        const QImage shot = viewer->grab().toImage().convertToFormat(QImage::Format_RGB888);
        Image img;
        img.width = shot.width();
        img.height = shot.height();
        img.channels = 3;
        for (int y = 0; y < shot.height(); ++y)
            img.bytes.insert(img.bytes.end(), shot.constScanLine(y), shot.constScanLine(y) + 3 * shot.width());
        int checked = 0;
        for (const LabelBox& l : viewer->drawn_labels()) {
            const test::Measured m = test::measure_label(img, l);
            if (m.text == 0) continue; // off screen
            EXPECT_GE(m.ratio, 4.5) << "label '" << l.text << "' in the window";
            std::printf("window label '%s': contrast %.2f:1\n", l.text.c_str(), m.ratio);
            checked += l.text.find("mm") != std::string::npos;
        }
        EXPECT_GE(checked, 1) << "the ruler's length is among the window's labels";
    }

    // ---- drag the first point down the cheek: it lands on core::pick of the
    // release pixel
    const auto from = viewer->image_pixel(ruler.points[0].position);
    ASSERT_TRUE(from);
    // Down the cheek: 30 pixels, or less where the face ends sooner (the
    // view's size follows the window's tool bars).
    const QPoint press = from->toPoint();
    QPoint release = press + QPoint(-4, 30);
    for (int down = 30; down >= 10 && oracle.pick(release).layers.empty(); down -= 4)
        release = press + QPoint(-4, down);
    const Camera camera = viewer->camera();
    const QString clicked = w.measure_tools()->click_readout();
    drag_widget(viewer, press, release);
    EXPECT_EQ(w.measure_tools()->click_readout(), clicked) << "a drag's release read as a click";
    EXPECT_EQ(viewer->camera().eye, camera.eye) << "the camera turned while a point was dragged";
    EXPECT_EQ(viewer->camera().target, camera.target);
    const core::PickResult at_release = oracle.pick(release);
    ASSERT_FALSE(at_release.layers.empty());
    const glm::dvec3 moved = w.workspace().markups()[0].points[0].position;
    EXPECT_NEAR(glm::length(moved - seen(at_release).lps), 0.0, 1e-6) << "not the release pixel's point";
    const QString moved_value = cell(w, 0, gui::MeasurementsPanel::Value);
    EXPECT_NE(moved_value, value);
    EXPECT_NEAR(parse_value(moved_value), iso::distance_mm(moved, ruler.points[1].position), kPrinted);
    EXPECT_EQ(w.undo_stack()->count(), surface_steps + 2) << "adding and moving: one step each";
    EXPECT_EQ(edit_action(w, "undo")->text(), "&Undo Move point");

    QTest::qWait(200);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((out / "cheek_ruler.png").string())));

    // ---- undo, redo: exactly the old and the new point
    edit_action(w, "undo")->trigger();
    EXPECT_EQ(w.statusBar()->currentMessage(), "Undone: Move point");
    EXPECT_EQ(w.workspace().markups()[0].points[0].position, ruler.points[0].position);
    EXPECT_EQ(cell(w, 0, gui::MeasurementsPanel::Value), value);
    edit_action(w, "redo")->trigger();
    EXPECT_EQ(w.workspace().markups()[0].points[0].position, moved);
    EXPECT_EQ(cell(w, 0, gui::MeasurementsPanel::Value), moved_value);

    // ---- delete and undo
    auto* del = qobject_cast<QToolButton*>(panel_table(w)->cellWidget(0, gui::MeasurementsPanel::Delete));
    ASSERT_NE(del, nullptr);
    del->click();
    ASSERT_TRUE(wait_until([&] { return w.workspace().markups().empty(); }, 5000)) << "the delete button did nothing";
    EXPECT_EQ(edit_action(w, "undo")->text(), "&Undo Delete Line 1");
    edit_action(w, "undo")->trigger();
    ASSERT_EQ(w.workspace().markups().size(), 1u);
    EXPECT_EQ(w.workspace().markups()[0].points[0].position, moved);
    EXPECT_EQ(w.workspace().markups()[0].points[1].position, ruler.points[1].position);
}

// A point dragged on the axial view moves in its plane; the window does not
// change.
TEST_F(GuiEdit, SliceDragMovesThePointInThePlane) {
    gui::MainWindow& w = window();
    // The 3D view redraws with every step; without AO its frames do not hold up the slice's events (llvmpipe).
    gui::ViewerOptions o = w.viewer()->options();
    o.look.ao = AoMethod::Off;
    w.viewer()->set_options(o);
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const std::vector<QPoint> a = ruler_pixels(w);
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Ruler, a));
    w.measure_tools()->set_tool(gui::MeasureTools::Tool::None);
    ASSERT_EQ(w.workspace().markups().size(), 1u);
    const Markup before = w.workspace().markups()[0];
    const core::WindowLevel wl = w.workspace().window();
    const QPoint to = a[1] + QPoint(-20, 35);
    drag_widget(axial, a[1] + QPoint(3, -2), to); // within the grab radius of the point
    const glm::dvec3 expected = core::pixel_to_lps(axial->grid(), {double(to.x()), double(to.y())});
    EXPECT_NEAR(glm::length(w.workspace().markups()[0].points[1].position - expected), 0.0, 1e-9);
    EXPECT_EQ(w.workspace().markups()[0].points[0].position, before.points[0].position);
    EXPECT_EQ(w.workspace().window().center, wl.center) << "a point drag changed the window";
    EXPECT_EQ(w.workspace().window().width, wl.width);
    EXPECT_NEAR(parse_value(cell(w, 0, gui::MeasurementsPanel::Value)),
                iso::distance_mm(before.points[0].position, expected), kPrinted);
    w.undo_stack()->undo();
    EXPECT_EQ(w.workspace().markups()[0].points[1].position, before.points[1].position);
    // A press away from every point is the window drag it always was.
    drag_widget(axial, axial_pixel(w, 100, 100), axial_pixel(w, 140, 80));
    EXPECT_NE(w.workspace().window().width, wl.width);
    EXPECT_EQ(w.workspace().markups()[0].points[1].position, before.points[1].position);
}

// The Point tool: one point list (F) whose points F-1, F-2 are where the
// clicks were, with the volume's value there in their rows, saved in .mrk.json.
TEST_F(GuiEdit, PointListInThePanelAndTheFile) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    const QPoint face = face_pixel(size);
    nlohmann::json layer;
    ASSERT_NO_FATAL_FAILURE(cli_pick(size, face, layer));
    const glm::dvec3 picked = json_lps(layer);

    w.measure_tools()->point_action()->trigger();
    ASSERT_EQ(w.measure_tools()->tool(), gui::MeasureTools::Tool::Point);
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, face));
    // Placing a point moves the crosshair there: each plane through it.
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal}) {
        const core::SliceGrid& g = w.slice_view(o)->grid();
        EXPECT_NEAR(glm::dot(picked, g.normal), g.offset_mm, 1e-6) << core::slice_orientation_name(o);
    }
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const QPoint on_slice = axial_pixel(w, 20, -30);
    const glm::dvec3 clicked = lps_of(axial->grid(), on_slice);
    QTest::mouseClick(axial, Qt::LeftButton, {}, on_slice);
    ASSERT_EQ(w.workspace().markups().size(), 1u);
    const Markup& list = w.workspace().markups()[0];
    EXPECT_EQ(list.type, MarkupType::Fiducial);
    EXPECT_EQ(list.name, "F");
    ASSERT_EQ(list.points.size(), 2u);
    EXPECT_EQ(list.points[0].label, "F-1");
    EXPECT_EQ(list.points[1].label, "F-2");
    EXPECT_NEAR(glm::length(list.points[0].position - picked), 0.0, 1e-6);
    EXPECT_NEAR(glm::length(list.points[1].position - clicked), 0.0, 1e-9);
    EXPECT_EQ(w.undo_stack()->undoText(), "Add point F-2");

    // The panel: the list's row, then a row per point with the volume's value
    // there.
    auto* panel = w.measurements_panel();
    EXPECT_EQ(cell(w, panel->row_of(0), gui::MeasurementsPanel::Value), "2 points");
    for (int k = 0; k < 2; ++k) {
        const int r = panel->row_of(0, k);
        ASSERT_GE(r, 0);
        EXPECT_EQ(cell(w, r, gui::MeasurementsPanel::Name).toStdString(), list.points[std::size_t(k)].label);
        const auto s = iso::sample_volume(w.scene().volume(), list.points[std::size_t(k)].position);
        ASSERT_TRUE(s);
        const QString v = cell(w, r, gui::MeasurementsPanel::Value);
        EXPECT_TRUE(v.startsWith("value ")) << v.toStdString();
        EXPECT_NEAR(parse_value(v.mid(6)), s->value, kPrinted) << "point " << k;
    }
    // F-1 was picked on the surface the pick saw; F-2, in the slice's plane, is
    // as far from one as the core says.
    EXPECT_EQ(cell(w, panel->row_of(0, 0), gui::MeasurementsPanel::Surface).toStdString(),
              layer["surface"].get<std::string>());
    const core::SurfacePoint near2 = core::surface_at(w.scene(), clicked);
    EXPECT_EQ(cell(w, panel->row_of(0, 1), gui::MeasurementsPanel::Surface).toStdString(),
              near2.distance_mm <= 0.5 ? w.scene().info(near2.surface).name : "off surface");

    // The window with the list's row selected (highlighted, the views centred on F-1).
    w.measure_tools()->set_tool(gui::MeasureTools::Tool::None);
    panel_table(w)->selectRow(panel->row_of(0));
    QTest::qWait(300);
    EXPECT_TRUE(w.grab().toImage().save(QString::fromStdString((output_dir("gui_edit") / "point_list.png").string())));

    // Saved like the other markups.
    const std::string saved = dir() / "points.mrk.json";
    ASSERT_TRUE(w.measurements_panel()->save(QString::fromStdString(saved)));
    const MarkupsFile f = load_markups(saved);
    ASSERT_EQ(f.markups.size(), 1u);
    EXPECT_EQ(f.markups[0].type, MarkupType::Fiducial);
    ASSERT_EQ(f.markups[0].points.size(), 2u);
    EXPECT_EQ(f.markups[0].points[1].label, "F-2");
    EXPECT_NEAR(glm::length(f.markups[0].points[1].position - clicked), 0.0, 1e-9);
}

// Loading a file that markups came from asks: Cancel changes nothing, Add
// keeps both, Replace gives the file's in place of what came from it.
TEST_F(GuiEdit, LoadingAFileAgainAsksReplaceAddOrCancel) {
    gui::MainWindow& w = window();
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Ruler, ruler_pixels(w)));
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Angle, angle_pixels(w)));
    w.measure_tools()->set_tool(gui::MeasureTools::Tool::None);
    const std::string path = dir() / "two.mrk.json";
    {
        MarkupsFile f;
        f.markups = w.workspace().markups();
        save_markups(f, path); // written by io, not by the window: the markups are
                               // from no file yet
    }
    auto* panel = w.measurements_panel();
    const QString qpath = QString::fromStdString(path);
    ASSERT_TRUE(panel->load(qpath));
    EXPECT_EQ(w.findChild<QMessageBox*>("reload"), nullptr) << "a file not loaded before needs no question";
    ASSERT_EQ(w.workspace().markups().size(), 4u);

    const auto answer = [&](const char* button) {
        ASSERT_TRUE(panel->load(qpath));
        QMessageBox* box = nullptr;
        ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>("reload")) != nullptr; }, 5000));
        ASSERT_TRUE(box->text().contains(" measurement(s) came from two.mrk.json")) << box->text().toStdString();
        auto* b = box->findChild<QPushButton*>(button);
        ASSERT_NE(b, nullptr) << button;
        b->click();
        ASSERT_TRUE(wait_until([&] { return w.findChild<QMessageBox*>("reload") == nullptr; }, 5000));
    };
    ASSERT_NO_FATAL_FAILURE(answer("cancel"));
    EXPECT_EQ(w.workspace().markups().size(), 4u);
    ASSERT_NO_FATAL_FAILURE(answer("add"));
    ASSERT_EQ(w.workspace().markups().size(), 6u);
    // Move one of the loaded ones: Replace still drops it (it came from the
    // file).
    gui::MarkupsState s = w.workspace().markups_state();
    s.markups[2].points[0].position += glm::dvec3(5, 0, 0);
    w.context().edit("Move point", core::Parts(core::Part::Markups), [&] { w.workspace().set_markups(s); });
    ASSERT_NO_FATAL_FAILURE(answer("replace"));
    ASSERT_EQ(w.workspace().markups().size(), 4u);
    const MarkupsFile file = load_markups(path);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(w.workspace().markups()[2 + i].name, file.markups[i].name);
        for (std::size_t k = 0; k < file.markups[i].points.size(); ++k)
            EXPECT_EQ(w.workspace().markups()[2 + i].points[k].position, file.markups[i].points[k].position);
    }
    EXPECT_EQ(w.undo_stack()->undoText(), "Replace markups from two.mrk.json");
    w.undo_stack()->undo();
    EXPECT_EQ(w.workspace().markups().size(), 6u);
}

// Selecting a row highlights the markup and takes the slice views to its
// first point; the 3D view's camera stays (a selection is no change of the
// figure: the next export is framed as the user left it).
TEST_F(GuiEdit, SelectingARowHighlightsAndCentres) {
    gui::MainWindow& w = window();
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Ruler, ruler_pixels(w)));
    ASSERT_NO_FATAL_FAILURE(click_on_axial(w, gui::MeasureTools::Tool::Angle, angle_pixels(w)));
    w.measure_tools()->set_tool(gui::MeasureTools::Tool::None);
    gui::Viewer* viewer = w.viewer();
    const Camera before = viewer->camera();
    const double distance = glm::length(before.eye - before.target);
    panel_table(w)->selectRow(1);
    ASSERT_EQ(w.workspace().selected(), std::optional<std::size_t>(1));
    const glm::dvec3 first = w.workspace().markups()[1].points[0].position;
    for (auto o : {core::SliceOrientation::Axial, core::SliceOrientation::Coronal, core::SliceOrientation::Sagittal}) {
        const core::SliceGrid& g = w.slice_view(o)->grid();
        EXPECT_NEAR(glm::dot(first, g.normal), g.offset_mm, 1e-9) << core::slice_orientation_name(o);
    }
    EXPECT_EQ(viewer->camera().target, before.target);
    EXPECT_EQ(viewer->camera().eye, before.eye);
    EXPECT_NEAR(glm::length(viewer->camera().eye - viewer->camera().target), distance, 1e-9);
    ASSERT_TRUE(w.workspace().camera());
    EXPECT_EQ(w.workspace().camera()->target, before.target) << "the session's camera stays too";
    // Drawn in the highlight colour: the views' markups, and the axial view's
    // pixels at the vertex.
    const auto drawn = w.measure_tools()->drawn_markups();
    EXPECT_EQ(glm::vec3(markup_color(drawn[1])), glm::vec3(gui::MeasureTools::highlight_color()));
    EXPECT_NE(glm::vec3(markup_color(drawn[0])), glm::vec3(gui::MeasureTools::highlight_color()));
    QTest::qWait(50);
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const QImage img = axial->grab().toImage();
    // Magenta (the highlight) is nowhere else: not in the grey slice, the orange
    // crosshair, cyan lines or green angles.
    const auto magenta = [](QColor c) { return c.red() > 150 && c.blue() > 150 && c.green() < 120; };
    const auto magenta_near = [&](const glm::dvec3& lps) {
        const core::SlicePoint at = core::lps_to_pixel(axial->grid(), lps);
        bool found = false;
        for (int dy = -6; dy <= 6; ++dy)
            for (int dx = -6; dx <= 6; ++dx)
                found |= magenta(img.pixelColor(int(at.pixel.x) + dx, int(at.pixel.y) + dy));
        return found;
    };
    const bool found = magenta_near(w.workspace().markups()[1].points[1].position);
    EXPECT_FALSE(magenta_near(w.workspace().markups()[0].points[0].position)) << "the ruler is not selected";
    EXPECT_TRUE(found) << "the selected angle is not drawn in the highlight colour";
    panel_table(w)->clearSelection();
    EXPECT_FALSE(w.workspace().selected());
}

// A point's label near a slice view's right edge goes to the left of the
// point rather than off the view (labels were cut off at the edge); where the
// point is comes from the core (core::pixel_to_lps / lps_to_pixel).
TEST_F(GuiEdit, SliceLabelsStayInsideTheView) {
    gui::MainWindow& w = window();
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    const core::SliceGrid& g = axial->grid();
    const glm::dvec2 px(g.width - 6.5, 0.5 * g.height);
    Markup m;
    m.type = MarkupType::Fiducial;
    m.name = "AVM nidus";
    m.points.resize(1);
    m.points[0].position = core::pixel_to_lps(g, px);
    w.workspace().set_markups({{m}, {}});
    QTest::qWait(50);
    const QImage img = axial->grab().toImage();
    const glm::dvec3 c = markup_color(m, 0);
    const QColor colour = QColor::fromRgbF(float(c.r), float(c.g), float(c.b));
    const auto near = [&](QColor p) {
        return std::abs(p.red() - colour.red()) + std::abs(p.green() - colour.green()) +
                   std::abs(p.blue() - colour.blue()) <
               60;
    };
    const glm::dvec2 at = core::lps_to_pixel(g, m.points[0].position).pixel;
    int left = 0;
    for (int y = int(at.y) - 12; y <= int(at.y) + 12; ++y)
        for (int x = int(at.x) - 140; x < int(at.x) - 9; ++x) left += near(img.pixelColor(x, y));
    EXPECT_GT(left, 20) << "the label is not drawn to the left of a point at the right edge";
}
