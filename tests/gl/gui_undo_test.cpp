// No lost work in the desktop app (docs/gui.md "Undo", "Unsaved work"):
// undo and redo of the Surfaces panel's edits on the window's undo stack,
// the Save / Discard / Cancel question before quitting or opening another
// file, and autosave to the recovery file, restored after a kill -9.
// Driven in-process through QTest in a real X server (CTest runs this program
// under xvfb-run; it skips without a display). Expected values come from the
// core API and the session files, not from the panel.
#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QColorDialog>
#include <QDoubleSpinBox>
#include <QMessageBox>
#include <QPushButton>
#include <QSlider>
#include <QTest>
#include <QTimer>
#include <QUndoStack>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "app/gui/files.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/unsaved_work.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/viewer.hpp"
#include "io/color.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/session.hpp"
#include "gui_test_util.hpp"

using namespace iso;

namespace {
using test::wait_until;

using test::add_through_panel;
using test::child;

void open_headsq(gui::MainWindow& w) {
    w.open_path(QString::fromStdString(test::data("headsq.nhdr")));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    ASSERT_TRUE(w.scene().has_volume());
}

// The window on screen with headsq open.
void show_with_headsq(gui::MainWindow& w) {
    w.resize(1400, 1000);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_headsq(w);
}

// A drag of a slider through `values`: pressed, moved, released.
void drag(QSlider* s, std::initializer_list<int> values) {
    s->setSliderDown(true);
    for (int v : values) s->setValue(v);
    s->setSliderDown(false);
}

void settle(gui::MainWindow& w) {
    ASSERT_TRUE(wait_until([&] { return !w.surfaces_panel()->reextracting() && !w.busy(); }, 60000));
}

// The iso surface of headsq at `iso` as the core makes it (no post-processing).
std::size_t triangles_at(const core::Scene& s, double iso) { return s.extract_isosurface(iso).triangles.size(); }

// Answers the next colour dialog (QColorDialog::getColor runs its own loop) with `pick`.
void answer_colour_dialog(QWidget& owner, const QColor& pick) {
    auto* timer = new QTimer(&owner);
    QObject::connect(timer, &QTimer::timeout, timer, [timer, pick] {
        auto* dialog = qobject_cast<QColorDialog*>(QApplication::activeModalWidget());
        if (!dialog || !dialog->isVisible()) return;
        timer->stop();
        timer->deleteLater();
        dialog->setCurrentColor(pick);
        dialog->accept();
    });
    timer->start(20);
}

// Clicks the standard button `which` of the window's box named `name` once it shows.
void answer(gui::MainWindow& w, const char* name, QMessageBox::StandardButton which) {
    QMessageBox* box = nullptr;
    ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>(name)) && box->isVisible(); }, 10000))
        << "no question " << name;
    QTest::mouseClick(box->button(which), Qt::LeftButton);
    ASSERT_TRUE(wait_until([&] { return w.findChild<QMessageBox*>(name) == nullptr; }, 30000));
}

QAction* recent_action(gui::MainWindow& w, const std::string& path) {
    const QString abs = QString::fromStdString(std::filesystem::absolute(path).string());
    for (auto* a : w.findChildren<QAction*>())
        if (a->text() == abs) return a;
    return nullptr;
}

Markup ruler(glm::dvec3 a, glm::dvec3 b) {
    Markup m;
    m.type = MarkupType::Line;
    m.name = "R-1";
    m.points.resize(2);
    m.points[0].position = a;
    m.points[1].position = b;
    return m;
}

void expect_same_surfaces(const core::Session& a, const core::Session& b) {
    ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
    for (std::size_t i = 0; i < a.surfaces.size(); ++i) {
        EXPECT_EQ(a.surfaces[i].value, b.surfaces[i].value) << i;
        EXPECT_EQ(a.surfaces[i].name, b.surfaces[i].name) << i;
        EXPECT_EQ(a.surfaces[i].color, b.surfaces[i].color) << i;
        EXPECT_EQ(a.surfaces[i].opacity, b.surfaces[i].opacity) << i;
        EXPECT_EQ(a.surfaces[i].visible, b.surfaces[i].visible) << i;
        EXPECT_EQ(a.surfaces[i].post.smooth, b.surfaces[i].post.smooth) << i;
    }
}

void expect_same_markups(const std::vector<Markup>& a, const std::vector<Markup>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].type, b[i].type);
        ASSERT_EQ(a[i].points.size(), b[i].points.size());
        for (std::size_t k = 0; k < a[i].points.size(); ++k)
            EXPECT_EQ(a[i].points[k].position, b[i].points[k].position) << i << " " << k;
    }
}
} // namespace

TEST(GuiUndo, SurfaceEditsUndoAndRedo) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_undo_test", dir / "config");
    gui::MainWindow w;
    show_with_headsq(w);
    QUndoStack* undo = w.undo_stack();
    auto* undo_action = w.findChild<QAction*>("undo");
    ASSERT_NE(undo_action, nullptr);
    EXPECT_FALSE(w.workspace().modified());
    EXPECT_FALSE(w.isWindowModified());

    // Add: one step; undo removes the surface, redo puts it back with its mesh.
    add_through_panel(w, 500);
    ASSERT_EQ(w.scene().surfaces().size(), 1u);
    const auto id = w.scene().surfaces()[0];
    const std::size_t at500 = triangles_at(w.scene(), 500);
    EXPECT_EQ(w.scene().mesh(id).triangles.size(), at500);
    EXPECT_EQ(undo->undoText(), "Add iso 500");
    EXPECT_TRUE(w.workspace().modified());
    EXPECT_TRUE(w.isWindowModified());
    undo->undo();
    EXPECT_TRUE(w.scene().surfaces().empty());
    EXPECT_EQ(w.surfaces_panel()->row(id), nullptr);
    EXPECT_FALSE(w.workspace().modified()) << "back at the state opened";
    undo->redo();
    ASSERT_TRUE(w.scene().has_surface(id)) << "redone under its id";
    EXPECT_EQ(w.scene().mesh(id).triangles.size(), at500);
    QWidget* row = w.surfaces_panel()->row(id);
    ASSERT_NE(row, nullptr);

    // Opacity: one drag, one step, named after what it undoes.
    const int steps = undo->count();
    drag(child<QSlider>(row, "opacity"), {90, 70, 55, 40});
    EXPECT_EQ(undo->count(), steps + 1) << "the drag's steps merge";
    EXPECT_FLOAT_EQ(w.scene().info(id).opacity, 0.40f);
    EXPECT_EQ(undo_action->text(), "&Undo Change opacity of iso 500");
    undo->undo();
    EXPECT_FLOAT_EQ(w.scene().info(id).opacity, 1.0f);
    EXPECT_EQ(child<QSlider>(row, "opacity")->value(), 100) << "the row shows the undone value";
    undo->redo();
    EXPECT_FLOAT_EQ(w.scene().info(id).opacity, 0.40f);
    drag(child<QSlider>(row, "opacity"), {45, 50});
    EXPECT_EQ(undo->count(), steps + 2) << "another drag, another step";
    undo->undo();
    EXPECT_FLOAT_EQ(w.scene().info(id).opacity, 0.40f);

    // Visibility.
    child<QCheckBox>(row, "visible")->setChecked(false);
    EXPECT_FALSE(w.scene().info(id).visible);
    EXPECT_EQ(undo->undoText(), "Hide iso 500");
    undo->undo();
    EXPECT_TRUE(w.scene().info(id).visible);
    EXPECT_TRUE(child<QCheckBox>(row, "visible")->isChecked());
    undo->redo();
    EXPECT_FALSE(w.scene().info(id).visible);
    undo->undo();

    // Colour.
    const glm::vec3 colour = w.scene().info(id).color;
    answer_colour_dialog(w, QColor("#3366cc"));
    QTest::mouseClick(child<QPushButton>(row, "color"), Qt::LeftButton);
    EXPECT_EQ(gui::to_qcolor(w.scene().info(id).color).name(), "#3366cc");
    EXPECT_EQ(undo->undoText(), "Change colour of iso 500");
    undo->undo();
    EXPECT_EQ(w.scene().info(id).color, colour);
    undo->redo();
    EXPECT_EQ(gui::to_qcolor(w.scene().info(id).color).name(), "#3366cc");

    // Iso value: the number, then a slider drag (one step); undo re-extracts.
    child<QDoubleSpinBox>(row, "iso_value")->setValue(700);
    settle(w);
    EXPECT_EQ(w.scene().info(id).value, 700.0);
    EXPECT_EQ(w.scene().mesh(id).triangles.size(), triangles_at(w.scene(), 700));
    EXPECT_EQ(undo->undoText(), "Change iso value of iso 500");
    const int before_drag = undo->count();
    auto* slider = child<QSlider>(row, "iso_slider");
    drag(slider, {slider->value() + 50, slider->value() + 100, slider->value() + 150});
    settle(w); // the step is the mesh swapped in: when its extraction is done
    EXPECT_EQ(undo->count(), before_drag + 1) << "the drag's re-extractions make one step";
    const double dragged = w.scene().info(id).value;
    EXPECT_NE(dragged, 700.0);
    undo->undo();
    settle(w);
    EXPECT_EQ(w.scene().info(id).value, 700.0);
    undo->undo();
    settle(w);
    EXPECT_EQ(w.scene().info(id).value, 500.0);
    EXPECT_EQ(w.scene().mesh(id).triangles.size(), at500);
    EXPECT_EQ(child<QDoubleSpinBox>(row, "iso_value")->value(), 500.0);
    undo->redo();
    undo->redo();
    settle(w);
    EXPECT_EQ(w.scene().info(id).value, dragged);

    // Smoothing and keep-largest.
    child<QDoubleSpinBox>(row, "smoothing")->setValue(0.5);
    settle(w);
    EXPECT_DOUBLE_EQ(w.scene().info(id).post.smooth, 0.5);
    EXPECT_EQ(undo->undoText(), QString("Change smoothing of ") + QString::fromStdString(w.scene().info(id).name));
    child<QCheckBox>(row, "keep_largest")->setChecked(true);
    settle(w);
    EXPECT_TRUE(w.scene().info(id).post.keep_largest);
    undo->undo();
    settle(w);
    EXPECT_FALSE(w.scene().info(id).post.keep_largest);
    undo->undo();
    settle(w);
    EXPECT_DOUBLE_EQ(w.scene().info(id).post.smooth, 0.0);
    EXPECT_EQ(w.scene().mesh(id).triangles.size(), triangles_at(w.scene(), dragged));
    undo->redo();
    settle(w);
    EXPECT_DOUBLE_EQ(w.scene().info(id).post.smooth, 0.5);

    // Remove: undo restores the surface with its settings and mesh.
    add_through_panel(w, 1150);
    ASSERT_EQ(w.scene().surfaces().size(), 2u);
    const core::SurfaceInfo kept = w.scene().info(id);
    const std::size_t kept_triangles = w.scene().mesh(id).triangles.size();
    QTest::mouseClick(child<QPushButton>(w.surfaces_panel()->row(id), "remove"), Qt::LeftButton);
    EXPECT_FALSE(w.scene().has_surface(id));
    EXPECT_EQ(undo->undoText(), QString::fromStdString("Remove " + kept.name));
    undo->undo();
    ASSERT_TRUE(w.scene().has_surface(id));
    EXPECT_EQ(w.scene().surfaces().front(), id) << "back in its place";
    EXPECT_EQ(w.scene().info(id).value, kept.value);
    EXPECT_EQ(w.scene().info(id).color, kept.color);
    EXPECT_EQ(w.scene().info(id).opacity, kept.opacity);
    EXPECT_EQ(w.scene().info(id).post.smooth, kept.post.smooth);
    EXPECT_EQ(w.scene().mesh(id).triangles.size(), kept_triangles);
    ASSERT_NE(w.surfaces_panel()->row(id), nullptr);
    EXPECT_FLOAT_EQ(float(child<QSlider>(w.surfaces_panel()->row(id), "opacity")->value()) / 100.0f, kept.opacity);
    // The 3D view draws the restored surface (uploaded again into its object id).
    ASSERT_NE(w.viewer(), nullptr);
    const int frames = w.viewer()->frames();
    w.viewer()->update();
    ASSERT_TRUE(wait_until([&] { return w.viewer()->frames() > frames || !w.viewer()->error().empty(); }, 60000));
    EXPECT_TRUE(w.viewer()->error().empty()) << w.viewer()->error();
    undo->redo();
    EXPECT_FALSE(w.scene().has_surface(id));
    undo->undo();
    EXPECT_TRUE(w.scene().has_surface(id));

    // Undo everything: back to the file as opened, unmodified.
    while (undo->canUndo()) {
        undo->undo();
        settle(w);
    }
    EXPECT_TRUE(w.scene().surfaces().empty());
    EXPECT_FALSE(w.workspace().modified());
}

TEST(GuiUndo, AskBeforeQuittingOrOpening) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto app = test::make_app("gui_undo_test", dir / "config");
    gui::MainWindow w;
    show_with_headsq(w);
    const std::string headsq = test::data("headsq.nhdr");

    // Nothing changed: quitting asks nothing.
    EXPECT_TRUE(w.close());
    EXPECT_FALSE(w.isVisible());
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));

    add_through_panel(w, 500);
    ASSERT_TRUE(w.workspace().modified());
    // Quit, Cancel: the window and its surface stay.
    EXPECT_FALSE(w.close());
    answer(w, "unsaved", QMessageBox::Cancel);
    EXPECT_TRUE(w.isVisible());
    EXPECT_EQ(w.scene().surfaces().size(), 1u);
    EXPECT_TRUE(w.workspace().modified());

    // File > Recent files (another file), Cancel: nothing opens.
    QAction* recent = recent_action(w, headsq);
    ASSERT_NE(recent, nullptr);
    recent->trigger();
    answer(w, "unsaved", QMessageBox::Cancel);
    QTest::qWait(200);
    EXPECT_FALSE(w.busy());
    EXPECT_EQ(w.scene().surfaces().size(), 1u);

    // Open, Save: the session is saved (to the current session file), then the file opens.
    const std::string session = dir / "work.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    EXPECT_FALSE(w.workspace().modified()) << "saved";
    drag(child<QSlider>(w.surfaces_panel()->row(w.scene().surfaces()[0]), "opacity"), {60, 30});
    ASSERT_TRUE(w.workspace().modified());
    recent_action(w, headsq)->trigger();
    answer(w, "unsaved", QMessageBox::Save);
    ASSERT_TRUE(wait_until([&] { return !w.busy() && w.scene().surfaces().empty(); }, 60000))
        << "the file did not open after the save";
    const core::Session saved = core::read_session(session);
    ASSERT_EQ(saved.surfaces.size(), 1u);
    EXPECT_EQ(saved.surfaces[0].value, 500.0);
    EXPECT_FLOAT_EQ(saved.surfaces[0].opacity, 0.30f) << "the session holds the last edit";
    EXPECT_FALSE(w.workspace().modified());

    // Open, Discard: the file opens, the surfaces go.
    add_through_panel(w, 1150);
    recent_action(w, headsq)->trigger();
    answer(w, "unsaved", QMessageBox::Discard);
    ASSERT_TRUE(wait_until([&] { return !w.busy() && w.scene().surfaces().empty(); }, 60000));
    EXPECT_FALSE(w.workspace().modified());

    // Quit, Save: saved to the session file, then the window closes; Discard closes.
    add_through_panel(w, 900);
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    child<QCheckBox>(w.surfaces_panel()->row(w.scene().surfaces()[0]), "visible")->setChecked(false);
    w.close();
    answer(w, "unsaved", QMessageBox::Save);
    ASSERT_TRUE(wait_until([&] { return !w.isVisible(); }, 60000)) << "the window did not close after the save";
    const core::Session quit_saved = core::read_session(session);
    ASSERT_EQ(quit_saved.surfaces.size(), 1u);
    EXPECT_FALSE(quit_saved.surfaces[0].visible);
    w.show();
    child<QCheckBox>(w.surfaces_panel()->row(w.scene().surfaces()[0]), "visible")->setChecked(true);
    w.close();
    answer(w, "unsaved", QMessageBox::Discard);
    ASSERT_TRUE(wait_until([&] { return !w.isVisible(); }, 10000));
    EXPECT_FALSE(core::read_session(session).surfaces[0].visible) << "Discard wrote nothing";
}

// The process the autosave test kills: edits, waits for the recovery file,
// writes what it made (MADE) and waits to be killed. Runs only when started
// by GuiUndo.AutosaveKillAndRestore (ISO_UNDO_CHILD=DIR).
TEST(GuiUndoChild, EditAndWaitForTheKill) {
    const char* dir_env = std::getenv("ISO_UNDO_CHILD");
    if (!dir_env) GTEST_SKIP() << "started by GuiUndo.AutosaveKillAndRestore";
    ISO_SKIP_WITHOUT_DISPLAY();
    const std::filesystem::path dir = dir_env;
    const auto app = test::make_app("gui_undo_test", dir / "config");
    gui::MainWindow w;
    w.unsaved_work()->set_autosave_interval(200);
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    open_headsq(w);
    add_through_panel(w, 500);
    add_through_panel(w, 1150);
    const auto ids = w.scene().surfaces();
    ASSERT_EQ(ids.size(), 2u);
    drag(child<QSlider>(w.surfaces_panel()->row(ids[1]), "opacity"), {70, 45});
    child<QDoubleSpinBox>(w.surfaces_panel()->row(ids[0]), "iso_value")->setValue(650);
    settle(w);
    gui::MarkupsState s = w.workspace().markups_state();
    s.markups.push_back(ruler({10, 20, 30}, {40, 50, 60}));
    w.context().edit("Add ruler", core::Parts(core::Part::Markups), [&] { w.workspace().set_markups(s); });
    // An autosave that started before the last edit holds less: wait for one with the ruler.
    const std::string recovery = gui::UnsavedWork::recovery_path().toStdString();
    ASSERT_TRUE(wait_until(
        [&] {
            try {
                return w.unsaved_work()->autosaves() > 0 && core::read_session(recovery).markups.size() == 1;
            } catch (const std::exception&) {
                return false;
            }
        },
        30000))
        << "no autosave";
    core::save_session(w.workspace().session(), dir / "made.json");
    std::ofstream(dir / "ready") << "ready\n";
    wait_until([] { return false; }, 120000); // killed meanwhile
    FAIL() << "not killed";
}

TEST(GuiUndo, AutosaveKillAndRestore) {
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    // The app in a process of its own (this program, the test above), killed with SIGKILL once it autosaved.
    const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
    const auto started =
        test::run_command("ISO_UNDO_CHILD='" + dir.path().string() + "' '" + self +
                          "' --gtest_filter=GuiUndoChild.* > '" + dir / "child.log" + "' 2>&1 & echo $!");
    const int pid = std::atoi(started.out.c_str());
    ASSERT_GT(pid, 0) << started.out;
    const bool ready = wait_until([&] { return std::filesystem::exists(dir / "ready"); }, 120000);
    ::kill(pid, SIGKILL);
    ASSERT_TRUE(ready) << test::read_file(dir / "child.log");
    const auto recovery = dir.path() / "config" / "isoscope-test" / "gui_undo_test" / "recovery.isoscope.json";
    ASSERT_TRUE(std::filesystem::exists(recovery)) << "no recovery file after the kill";
    for (const auto& e : std::filesystem::directory_iterator(recovery.parent_path()))
        EXPECT_EQ(e.path().filename().string().find("isoscope-tmp"), std::string::npos)
            << "a temporary file left behind";
    const core::Session made = core::read_session(dir / "made.json");
    const core::Session autosaved = core::read_session(recovery.string());
    expect_same_surfaces(autosaved, made);
    expect_same_markups(autosaved.markups, made.markups);

    // Started again: the offer; Restore brings the work back, as unsaved work.
    const auto app = test::make_app("gui_undo_test", dir / "config");
    ASSERT_EQ(gui::UnsavedWork::recovery_path().toStdString(), recovery.string());
    gui::MainWindow w;
    test::fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    bool otherwise = false;
    w.offer_recovery([&] { otherwise = true; });
    QMessageBox* box = nullptr;
    ASSERT_TRUE(wait_until([&] { return (box = w.findChild<QMessageBox*>("recovery")) && box->isVisible(); }, 30000));
    QTest::mouseClick(box->findChild<QPushButton*>("restore"), Qt::LeftButton);
    ASSERT_TRUE(wait_until([&] { return !w.busy() && !w.scene().surfaces().empty(); }, 60000));
    EXPECT_FALSE(otherwise);
    const core::Session now = w.workspace().session();
    expect_same_surfaces(now, made);
    expect_same_markups(now.markups, made.markups);
    ASSERT_EQ(now.surfaces.size(), 2u);
    EXPECT_EQ(now.surfaces[0].value, 650.0);
    EXPECT_FLOAT_EQ(now.surfaces[1].opacity, 0.45f);
    EXPECT_EQ(w.scene().mesh(w.scene().surfaces()[0]).triangles.size(), triangles_at(w.scene(), 650));
    EXPECT_TRUE(w.workspace().modified()) << "restored work is unsaved";
    EXPECT_TRUE(w.workspace().session_path().empty()) << "the recovery file is not the session";
    EXPECT_TRUE(std::filesystem::exists(recovery)) << "kept until saved or quit";

    // A clean exit (Discard) removes it; with none, the offer runs `otherwise` at once.
    w.close();
    answer(w, "unsaved", QMessageBox::Discard);
    EXPECT_FALSE(std::filesystem::exists(recovery));
    w.offer_recovery([&] { otherwise = true; });
    EXPECT_TRUE(otherwise);
}

TEST(GuiUndo, RealAppRestoresOrDiscardsTheRecoveryFileAtStart) {
    // `isoscope gui` itself: ISOSCOPE_RECOVERY answers the offer; a restored
    // session is unsaved work, so the app autosaves it again (every 200 ms
    // here) until killed with SIGKILL.
    ISO_SKIP_WITHOUT_DISPLAY();
    test::TempDir dir;
    const auto folder = dir.path() / "config" / "isoscope" / "isoscope"; // the app's AppConfigLocation
    std::filesystem::create_directories(folder);
    const auto recovery = folder / "recovery.isoscope.json";
    core::Session made;
    made.input = std::filesystem::absolute(test::data("headsq.nhdr")).string();
    made.surfaces.resize(1);
    made.surfaces[0].value = 700;
    made.surfaces[0].name = "iso 700";
    made.surfaces[0].color = "#3366cc";
    made.surfaces[0].opacity = 0.5f;
    made.markups.push_back(ruler({1, 2, 3}, {4, 5, 6}));
    const auto write_recovery = [&] {
        core::save_session(made, recovery.string());
        std::filesystem::last_write_time(recovery,
                                         std::filesystem::file_time_type::clock::now() - std::chrono::hours(1));
    };
    const auto run = [&](const std::string& answer, int seconds) {
        return test::run_command("XDG_CONFIG_HOME='" + (dir / "config") + "' ISOSCOPE_RECOVERY=" + answer +
                                     " ISOSCOPE_AUTOSAVE_MS=200 timeout -s KILL " + std::to_string(seconds) + " " +
                                     test::cli() + " gui",
                                 true);
    };

    write_recovery();
    const auto old_time = std::filesystem::last_write_time(recovery);
    const auto restored = run("restore", 12);
    ASSERT_TRUE(std::filesystem::exists(recovery)) << restored.out;
    EXPECT_GT(std::filesystem::last_write_time(recovery), old_time)
        << "not autosaved after the restore: " << restored.out;
    const core::Session again = core::read_session(recovery.string());
    expect_same_surfaces(again, made);
    expect_same_markups(again.markups, made.markups);
    EXPECT_EQ(again.input, made.input);

    write_recovery();
    const auto discarded = run("discard", 6);
    EXPECT_FALSE(std::filesystem::exists(recovery)) << "Discard kept the file: " << discarded.out;
}
