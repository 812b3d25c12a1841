// Structures in the desktop app (docs/gui.md "Structures"): the Isolate tool
// makes the bone component under the cursor a surface of its own, listed in
// the Measurements dock with the volume `measure` gives that component; the
// Distance tool measures skin to bone as the core does and draws it as one
// undoable ruler. Driven through QTest in a real X server (CTest runs it
// under xvfb-run; it skips without a display). Expected values come from
// the core on a scene of the test's own (core::pick with every layer,
// core::measure_surfaces, core::surface_gap), not from the window.
#include <filesystem>

#include <QAction>
#include <QColor>
#include <QScrollBar>
#include <QStatusBar>
#include <QTableWidget>
#include <QTest>
#include <QUndoStack>

#include "app/gui/files.hpp"
#include "app/gui/measurements_panel.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/structure_tools.hpp"
#include "gui_measure_util.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/structures.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/shape.hpp"

using namespace iso;
using namespace iso::test;
using GuiStructures = HeadWindow;

namespace {

// A pixel on the row whose pick lands on the surface named `name`.
std::optional<std::pair<QPoint, core::PickLayer>> find_pixel(HeadOracle& o, QSize size, const std::string& name,
                                                             double row) {
    for (int dx = 0; dx < size.width() / 2; dx += 6)
        for (int side : {1, -1}) {
            const QPoint px(size.width() / 2 + side * dx, int(size.height() * row));
            const auto r = o.pick(px);
            if (r.visible && r.layers[*r.visible].name == name) return std::make_pair(px, r.layers[*r.visible]);
        }
    return std::nullopt;
}

} // namespace

TEST_F(GuiStructures, IsolateListsTheComponentMeasureGivesAndDistanceIsTheCores) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    HeadOracle o(size, viewer->camera());
    ASSERT_TRUE(o.error().empty()) << o.error();
    const std::vector<core::SurfaceId> ids = o.scene().surfaces(); // skin, bone
    const auto bone = find_pixel(o, size, "iso 1150", 0.45);
    ASSERT_TRUE(bone) << "no pixel sees the bone";

    // ---- Isolate: the bone component under the cursor
    gui::StructureTools* tools = w.structure_tools();
    tools->isolate_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::StructureTools::Tool::Isolate);
    const std::size_t before = w.scene().surfaces().size();
    QTest::mouseClick(viewer, Qt::LeftButton, {}, bone->first);
    ASSERT_TRUE(QTest::qWaitFor([&] { return w.scene().surfaces().size() == before + 1 && !w.busy(); }, 600000))
        << w.statusBar()->currentMessage().toStdString();
    const core::SurfaceId made = w.scene().surfaces().back();
    // The core's answer: the bone's components, the one nearest the picked point.
    const Mesh& bone_mesh = o.scene().mesh(ids[1]);
    const auto comps = triangle_components(bone_mesh);
    const std::uint32_t k = comps[nearest_point(TriangleBvh(bone_mesh), bone->second.lps).triangle];
    const auto listed = core::measure_surfaces(o.scene(), {ids[1]}).front().measures.components.at(k);
    EXPECT_EQ(w.scene().info(made).name, "iso 1150 component " + std::to_string(k + 1));
    EXPECT_EQ(w.scene().mesh(made).triangles.size(), listed.triangles);
    const auto measured = core::measure_surfaces(w.scene(), {made}).front().measures;
    EXPECT_NEAR(measured.volume_ml, listed.volume_ml, 1e-9 * std::abs(listed.volume_ml) + 1e-12);
    // The structure alone on screen: its parent hidden.
    EXPECT_TRUE(w.scene().info(made).visible);
    EXPECT_FALSE(w.scene().info(ids[1]).visible);
    // The dock's row: name, volume to 3 decimals with its uncertainty.
    QTableWidget* table = tools->table();
    ASSERT_TRUE(QTest::qWaitFor([&] { return table->rowCount() == 1 && !w.busy(); }, 600000));
    EXPECT_EQ(table->item(0, gui::StructureTools::Name)->text().toStdString(), w.scene().info(made).name);
    const QString volume = table->item(0, gui::StructureTools::Volume)->text();
    EXPECT_TRUE(volume.contains(QString::number(std::abs(listed.volume_ml), 'f', 3))) << volume.toStdString();
    EXPECT_EQ(volume.startsWith("encloses a cavity of "), encloses_cavity(listed.volume_ml)) << volume.toStdString();
    EXPECT_FALSE(volume.contains("-")) << "never a negative volume";
    EXPECT_TRUE(volume.contains(QString::fromUtf8("\u00b1"))) << "an isosurface component has an uncertainty";
    EXPECT_EQ(table->item(0, gui::StructureTools::Closed)->text(), listed.closed ? "closed" : "open");
    EXPECT_EQ(table->horizontalScrollBar()->maximum(), 0) << "no column cut off behind a scroll bar";
    EXPECT_GE(table->viewport()->height(), 3 * table->rowHeight(0)) << "more than one row shows";

    // ---- Isolate is one undo step: undone, the component goes and its
    // parent shows again; redone, back under its id. Isolating it again (a
    // click on it) adds nothing.
    EXPECT_EQ(w.undo_stack()->undoText().toStdString(), "Isolate " + w.scene().info(made).name);
    w.undo_stack()->undo();
    EXPECT_FALSE(w.scene().has_surface(made));
    EXPECT_TRUE(w.scene().info(ids[1]).visible);
    w.undo_stack()->redo();
    ASSERT_TRUE(w.scene().has_surface(made));
    EXPECT_EQ(w.scene().mesh(made).triangles.size(), listed.triangles);
    QTest::qWait(100); // a frame with the component drawn
    const auto again = find_pixel(o, size, "iso 1150", 0.45);
    QTest::mouseClick(viewer, Qt::LeftButton, {}, again->first);
    ASSERT_TRUE(QTest::qWaitFor([&] { return tools->isolations() == 2 && !w.busy(); }, 600000));
    EXPECT_EQ(w.scene().surfaces().size(), before + 1) << "the same component is not added twice";
    EXPECT_TRUE(w.statusBar()->currentMessage().contains("one structure already"))
        << w.statusBar()->currentMessage().toStdString();

    // ---- Distance: skin (a cheek, skin only) to that bone component
    {
        core::SurfaceInfo info = w.scene().info(made);
        info.visible = false;
        w.workspace().set_surface_info(made, info);
        info = w.scene().info(ids[1]);
        info.visible = true;
        w.workspace().set_surface_info(ids[1], info);
    } // the view as before: the isolated copy off, the bone on
    const auto skin = find_pixel(o, size, "iso 500", 0.55);
    ASSERT_TRUE(skin) << "no pixel sees only skin";
    tools->distance_action()->trigger();
    const std::size_t markups = w.workspace().markups().size();
    QTest::mouseClick(viewer, Qt::LeftButton, {}, skin->first);
    QTest::mouseClick(viewer, Qt::LeftButton, {}, bone->first);
    ASSERT_TRUE(QTest::qWaitFor([&] { return tools->distances() == 1; }, 600000))
        << w.statusBar()->currentMessage().toStdString();
    ASSERT_EQ(w.workspace().markups().size(), markups + 1);
    const Markup& line = w.workspace().markups().back();
    const core::SurfaceGap gap = core::surface_gap(o.scene(), ids[0], ids[1], skin->second.lps, bone->second.lps);
    EXPECT_EQ(line.name, gap.name_a + " to " + gap.name_b);
    ASSERT_EQ(line.points.size(), 2u);
    EXPECT_NEAR(glm::length(line.points[0].position - gap.distance.pair.a), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(line.points[1].position - gap.distance.pair.b), 0.0, 1e-9);
    EXPECT_NEAR(line_length_mm(line.points[0].position, line.points[1].position), gap.distance.pair.distance_mm, 1e-9);
    EXPECT_EQ(w.measurements_panel()->table()->horizontalScrollBar()->maximum(), 0)
        << "the Measurements table's columns fit the dock";
    std::printf("isolated %s: %s; %s: %.4f mm\n", w.scene().info(made).name.c_str(), volume.toStdString().c_str(),
                line.name.c_str(), gap.distance.pair.distance_mm);
    // One undo step.
    w.undo_stack()->undo();
    EXPECT_EQ(w.workspace().markups().size(), markups);

    // ---- Two clicks on one connected structure: refused, no 0 mm ruler.
    QTest::mouseClick(viewer, Qt::LeftButton, {}, bone->first);
    QTest::mouseClick(viewer, Qt::LeftButton, {}, bone->first + QPoint(3, 0));
    ASSERT_TRUE(QTest::qWaitFor([&] { return tools->distances() == 2 && !w.busy(); }, 600000));
    EXPECT_EQ(w.workspace().markups().size(), markups);
    EXPECT_TRUE(w.statusBar()->currentMessage().contains("one connected structure"))
        << w.statusBar()->currentMessage().toStdString();
    EXPECT_TRUE(core::surface_gap(o.scene(), ids[1], ids[1], bone->second.lps, bone->second.lps).same_structure);
}

// With the crop box on, Isolate keeps the part of the component within it,
// cut and capped: the part the core makes with that box (its triangles and
// volume), named "... within box", closed; the crop box kept with it. (The
// click's pick is the test above's; here Isolate is given the point, a
// vertex of the bone, and the expected part comes from the core.)
TEST_F(GuiStructures, IsolateWithTheCropBoxOnKeepsThePartWithinIt) {
    gui::MainWindow& w = window();
    const core::SurfaceId bone = w.scene().surfaces()[1];
    ASSERT_EQ(w.scene().info(bone).name, "iso 1150");
    const Mesh& m = w.scene().mesh(bone);
    const glm::dvec3 p(m.positions[m.triangles[m.triangles.size() / 2][0]]);
    const LpsBox box{p - glm::dvec3(25, 15, 20), p + glm::dvec3(25, 40, 20)};
    const auto plan = core::plan_component(w.scene(), bone, p, box);
    FrameLook look = w.workspace().look();
    look.clip.box = std::make_pair(box.lo, box.hi);
    w.workspace().set_look(look);
    const std::size_t before = w.scene().surfaces().size();
    w.structure_tools()->isolate(bone, p);
    ASSERT_TRUE(QTest::qWaitFor([&] { return w.scene().surfaces().size() == before + 1 && !w.busy(); }, 600000))
        << w.statusBar()->currentMessage().toStdString();
    const core::SurfaceId made = w.scene().surfaces().back();
    EXPECT_EQ(w.scene().info(made).name, plan.info.name);
    EXPECT_NE(plan.info.name.find("within box"), std::string::npos) << plan.info.name;
    EXPECT_EQ(w.scene().mesh(made).triangles.size(), plan.mesh.triangles.size());
    const auto measured = core::measure_surfaces(w.scene(), {made}).front().measures;
    EXPECT_NEAR(measured.volume_ml, plan.measures.volume_ml, 1e-9 * std::abs(plan.measures.volume_ml));
    EXPECT_TRUE(measured.closed) << "the box's caps close the cut";
    ASSERT_TRUE(w.scene().info(made).post.keep_within.has_value());
    EXPECT_EQ(*w.scene().info(made).post.keep_within, box);
    for (const auto& q : w.scene().mesh(made).positions)
        for (int a = 0; a < 3; ++a) {
            EXPECT_GE(double(q[a]), box.lo[a] - 1e-3);
            EXPECT_LE(double(q[a]), box.hi[a] + 1e-3);
        }
    // Without the crop box, the whole component again (a new surface: another part).
    look.clip.box.reset();
    w.workspace().set_look(look);
    w.structure_tools()->isolate(bone, p);
    ASSERT_TRUE(QTest::qWaitFor([&] { return w.scene().surfaces().size() == before + 2 && !w.busy(); }, 600000));
    EXPECT_FALSE(w.scene().info(w.scene().surfaces().back()).post.keep_within.has_value());
    EXPECT_GT(w.scene().mesh(w.scene().surfaces().back()).triangles.size(), plan.mesh.triangles.size());
}

// Grow (3D Slicer's Grow from seeds, a threshold flood fill): a click on
// the bone in the axial view with the range 1150 to the volume's largest
// value makes "grown 1", the region core::plan_grown grows from that point
// on a scene of the test's own, listed in the Measurements dock by its
// voxels (with the partial-volume uncertainty), diameter and centroid; one
// undo step. A click in the 3D view on the same bone seeds inside it (the
// pick lies on the isosurface) and grows the same region.
TEST_F(GuiStructures, GrowFromAClickIsTheCoresRegionListedByItsVoxels) {
    gui::MainWindow& w = window();
    gui::StructureTools* tools = w.structure_tools();
    tools->grow_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::StructureTools::Tool::Grow);
    const double hi = w.scene().value_range().max;
    tools->set_grow_range(1150, hi);
    // An axial pixel on bone, well inside it (its 3x3 neighbours too).
    gui::SliceView* axial = w.slice_view(core::SliceOrientation::Axial);
    const Volume& v = w.scene().volume();
    const auto value = [&](QPoint p) {
        const auto s = core::sample_at_pixel(v, axial->grid(), {double(p.x()), double(p.y())});
        return s ? s->voxel_value : -1e9;
    };
    std::optional<QPoint> seed_px;
    for (int y = 10; y < axial->height() - 10 && !seed_px; y += 3)
        for (int x = 10; x < axial->width() - 10 && !seed_px; x += 3) {
            bool all = true;
            for (int d = -2; d <= 2 && all; d += 2)
                for (int e = -2; e <= 2 && all; e += 2) all = value(QPoint(x + d, y + e)) >= 1300;
            if (all) seed_px = QPoint(x, y);
        }
    ASSERT_TRUE(seed_px) << "no bone in the axial view";
    const glm::dvec3 seed = core::pixel_to_lps(axial->grid(), {double(seed_px->x()), double(seed_px->y())});
    const std::size_t before = w.scene().surfaces().size();
    QTest::mouseClick(axial, Qt::LeftButton, {}, *seed_px);
    ASSERT_TRUE(QTest::qWaitFor([&] { return tools->grown() == 1 && !w.busy(); }, 600000))
        << w.statusBar()->currentMessage().toStdString();
    ASSERT_EQ(w.scene().surfaces().size(), before + 1) << w.statusBar()->currentMessage().toStdString();
    const core::SurfaceId made = w.scene().surfaces().back();
    EXPECT_EQ(w.scene().info(made).name, "grown 1");

    // The core's answer on a scene of the test's own.
    core::Scene own;
    own.open(headsq());
    GrowOptions o;
    o.lo = 1150;
    o.hi = hi;
    const core::GrownPlan expected = core::plan_grown(own, seed, o);
    EXPECT_EQ(w.scene().mesh(made).triangles.size(), expected.mesh.triangles.size());
    const GrownRegion& r = expected.grown.region;
    std::printf("grown from (%.1f, %.1f, %.1f): %zu voxels, %.3f +- %.3f mL\n", seed.x, seed.y, seed.z, r.voxels,
                r.volume_ml, r.partial_volume_ml);
    QTableWidget* table = tools->table();
    ASSERT_TRUE(QTest::qWaitFor([&] { return table->rowCount() == 1 && !w.busy(); }, 600000));
    EXPECT_EQ(table->item(0, gui::StructureTools::Name)->text(), "grown 1");
    const QString vol = table->item(0, gui::StructureTools::Volume)->text();
    EXPECT_TRUE(vol.contains(QString::number(r.volume_ml, 'f', 3))) << vol.toStdString();
    EXPECT_TRUE(vol.contains(QString::number(r.partial_volume_ml, 'f', 3))) << vol.toStdString();
    EXPECT_TRUE(vol.contains(QString("%1 voxels").arg(r.voxels))) << vol.toStdString();
    const ShapeMeasures shape = measure_shape(expected.mesh, true);
    EXPECT_EQ(table->item(0, gui::StructureTools::Diameter)->text(), QString::number(shape.feret_mm, 'f', 2) + " mm");
    EXPECT_TRUE(
        table->item(0, gui::StructureTools::Centroid)->text().contains(QString::number(shape.centroid.x, 'f', 1)));

    // File > Export label map: the visible surfaces as labels 1..3 (skin,
    // bone, then the grown region, whose label wins where they overlap): the
    // grown region's label holds exactly its voxels, read back from the file.
    const std::string labels = dir() / "labels.nii.gz";
    w.files()->export_label_map(QString::fromStdString(labels));
    ASSERT_TRUE(QTest::qWaitFor([&] { return !w.busy(); }, 600000));
    ASSERT_TRUE(std::filesystem::exists(labels)) << w.statusBar()->currentMessage().toStdString();
    EXPECT_TRUE(std::filesystem::exists(std::string(dir() / "labels.ctbl")));
    const Volume back = load_volume(labels);
    ASSERT_EQ(back.dims, v.dims);
    std::size_t grown_voxels = 0;
    for (std::int64_t k = 0; k < back.dims[2]; ++k)
        for (std::int64_t j = 0; j < back.dims[1]; ++j)
            for (std::int64_t i = 0; i < back.dims[0]; ++i) grown_voxels += back.value(i, j, k) == 3.0;
    EXPECT_EQ(grown_voxels, r.voxels);
    EXPECT_TRUE(w.statusBar()->currentMessage().contains("Exported 3 structures"))
        << w.statusBar()->currentMessage().toStdString();

    // One undo step.
    EXPECT_EQ(w.undo_stack()->undoText(), "Grow grown 1");
    w.undo_stack()->undo();
    EXPECT_FALSE(w.scene().has_surface(made));
    ASSERT_TRUE(QTest::qWaitFor([&] { return table->rowCount() == 0; }, 10000));

    // The 3D view: a click on the bone grows from inside it, the same region.
    gui::Viewer* viewer = w.viewer();
    HeadOracle oracle(viewer->image_size(), viewer->camera());
    ASSERT_TRUE(oracle.error().empty()) << oracle.error();
    const auto bone = find_pixel(oracle, viewer->image_size(), "iso 1150", 0.45);
    ASSERT_TRUE(bone);
    QTest::mouseClick(viewer, Qt::LeftButton, {}, bone->first);
    ASSERT_TRUE(QTest::qWaitFor([&] { return tools->grown() == 2 && !w.busy(); }, 600000));
    ASSERT_EQ(w.scene().surfaces().size(), before + 1) << w.statusBar()->currentMessage().toStdString();
    std::printf("3D click: %s\n", w.statusBar()->currentMessage().toStdString().c_str());
    EXPECT_TRUE(w.statusBar()->currentMessage().contains("grown 1:")) << w.statusBar()->currentMessage().toStdString();
}

// Scissors: an outline dragged over the left half of the 3D view cuts the
// surface it encloses most of: the part is core::plan_scissors' for the same
// outline, camera and view size on a scene of the test's own (the same
// triangles and volume), closed, listed in the Measurements dock, its parent
// hidden; one undo step brings the parent back.
TEST_F(GuiStructures, ScissorsCutTheSurfaceAsTheCoreDoes) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    gui::StructureTools* tools = w.structure_tools();
    tools->scissors_action()->trigger();
    ASSERT_EQ(tools->tool(), gui::StructureTools::Tool::Scissors);
    ASSERT_TRUE(QTest::qWaitFor([&] { return viewer->frames() > 0; }, 60000));
    const QSize size = viewer->size();
    // A pentagon over the left half, its corners joined by 10-pixel steps.
    const std::vector<QPoint> corners{{size.width() / 10, size.height() / 10},
                                      {size.width() / 2, size.height() / 8},
                                      {size.width() / 2 - 20, size.height() / 2},
                                      {size.width() / 2, size.height() * 7 / 8},
                                      {size.width() / 10, size.height() * 9 / 10}};
    std::vector<QPoint> path;
    for (std::size_t i = 0; i < corners.size(); ++i) {
        const QPoint a = corners[i], b = corners[(i + 1) % corners.size()];
        const int steps = std::max(1, int(std::hypot(b.x() - a.x(), b.y() - a.y()) / 10));
        for (int k = 0; k < steps; ++k) path.push_back(a + (b - a) * k / steps);
    }
    const auto send = [&](QEvent::Type type, QPoint at, Qt::MouseButtons held) {
        const Qt::MouseButton button = type == QEvent::MouseMove ? Qt::NoButton : Qt::LeftButton;
        QMouseEvent e(type, QPointF(at), viewer->mapToGlobal(QPointF(at)), button, held, Qt::NoModifier);
        QCoreApplication::sendEvent(viewer, &e);
    };
    const Camera camera = viewer->camera();
    const std::size_t before = w.scene().surfaces().size();
    send(QEvent::MouseButtonPress, path.front(), Qt::LeftButton);
    for (std::size_t k = 1; k < path.size(); ++k) send(QEvent::MouseMove, path[k], Qt::LeftButton);
    send(QEvent::MouseButtonRelease, path.back(), Qt::NoButton);
    ASSERT_TRUE(QTest::qWaitFor([&] { return tools->cuts() == 1 && !w.busy(); }, 600000))
        << w.statusBar()->currentMessage().toStdString();
    ASSERT_EQ(w.scene().surfaces().size(), before + 1) << w.statusBar()->currentMessage().toStdString();
    EXPECT_EQ(viewer->camera(), camera) << "the outline's drag turned the view";
    const core::SurfaceId made = w.scene().surfaces().back();
    const std::string name = w.scene().info(made).name;
    std::printf("scissors: %s; %s\n", name.c_str(), w.statusBar()->currentMessage().toStdString().c_str());
    const core::SurfaceId parent = name.rfind("iso 500", 0) == 0 ? 1 : 2;
    EXPECT_EQ(name, (parent == 1 ? "iso 500" : "iso 1150") + std::string(" scissors 1"));
    EXPECT_FALSE(w.scene().info(parent).visible) << "the parent is hidden";

    // The core on a scene of the test's own, with the same outline (image pixels).
    core::Scene own;
    own.open(headsq());
    own.add_isosurfaces({500, 1150});
    core::ScissorsRequest r;
    const double dpr = viewer->devicePixelRatioF();
    for (const QPoint& p : path) r.outline.push_back({p.x() * dpr, p.y() * dpr});
    r.camera = camera;
    r.width = viewer->image_size().width();
    r.height = viewer->image_size().height();
    const core::ComponentPlan expected = core::plan_scissors(own, parent, r);
    EXPECT_EQ(w.scene().mesh(made).triangles.size(), expected.mesh.triangles.size());
    const auto got = core::measure_surfaces(w.scene(), {made}).front().measures;
    EXPECT_NEAR(got.volume_ml, expected.measures.volume_ml, 1e-9 + 1e-9 * std::abs(expected.measures.volume_ml));
    EXPECT_EQ(got.closed, expected.measures.closed);
    QTableWidget* table = tools->table();
    ASSERT_TRUE(QTest::qWaitFor([&] { return table->rowCount() == 1 && !w.busy(); }, 600000));
    EXPECT_EQ(table->item(0, gui::StructureTools::Name)->text().toStdString(), name);

    // The list as Slicer's segment list: its colour, and a box that hides and shows it (one undo step each).
    QTableWidgetItem* row = table->item(0, gui::StructureTools::Name);
    EXPECT_EQ(row->checkState(), Qt::Checked);
    EXPECT_EQ(row->data(Qt::DecorationRole).value<QColor>(), gui::to_qcolor(w.scene().info(made).color));
    row->setCheckState(Qt::Unchecked);
    EXPECT_FALSE(w.scene().info(made).visible);
    EXPECT_EQ(w.undo_stack()->undoText().toStdString(), "Hide " + name);
    w.undo_stack()->undo();
    EXPECT_TRUE(w.scene().info(made).visible);
    // The list follows (rebuilt when the event loop runs next).
    EXPECT_TRUE(QTest::qWaitFor(
        [&] {
            return table->rowCount() == 1 && table->item(0, gui::StructureTools::Name)->checkState() == Qt::Checked;
        },
        10000));

    // Kept in the session with its outline: a window opened from it cuts the same part again.
    const std::string session = dir() / "cut.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(QTest::qWaitFor([&] { return !w.busy(); }, 60000));
    {
        gui::MainWindow w2;
        w2.resize(900, 700);
        w2.show();
        ASSERT_TRUE(QTest::qWaitForWindowExposed(&w2));
        w2.open_session(QString::fromStdString(session));
        ASSERT_TRUE(QTest::qWaitFor([&] { return !w2.busy(); }, 600000));
        ASSERT_EQ(w2.scene().surfaces().size(), w.scene().surfaces().size())
            << w2.statusBar()->currentMessage().toStdString();
        const core::SurfaceId again = w2.scene().surfaces().back();
        EXPECT_EQ(w2.scene().info(again).name, name);
        EXPECT_EQ(w2.scene().info(again).post, w.scene().info(made).post);
        EXPECT_EQ(w2.scene().mesh(again).triangles.size(), expected.mesh.triangles.size());
        EXPECT_NEAR(measure_surface(w2.scene().mesh(again)).volume_ml, measure_surface(expected.mesh).volume_ml,
                    1e-9 * std::abs(measure_surface(expected.mesh).volume_ml));
        QTableWidget* table2 = w2.structure_tools()->table();
        ASSERT_TRUE(QTest::qWaitFor([&] { return table2->rowCount() == 1 && !w2.busy(); }, 600000));
        EXPECT_EQ(table2->item(0, gui::StructureTools::Name)->text().toStdString(), name);
    }

    EXPECT_EQ(w.undo_stack()->undoText().toStdString(), "Scissors " + name);
    w.undo_stack()->undo();
    EXPECT_FALSE(w.scene().has_surface(made));
    EXPECT_TRUE(w.scene().info(parent).visible);
}
