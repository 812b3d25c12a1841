// The desktop app's View and Help menus (docs/gui.md "Menus"), driven
// in-process through QTest under Xvfb (CTest runs this program under
// xvfb-run; it skips without a display). Expected values: the versions from
// the core (core::component_versions) and Qt, the GL renderer from a
// render in another process (`isoscope render --stats`), the docks and tool
// bars from the window's widgets.
#include <QAbstractButton>
#include <QAbstractSlider>
#include <QAbstractSpinBox>
#include <QAction>
#include <QApplication>
#include <QComboBox>
#include <QDialog>
#include <QDockWidget>
#include <QMenu>
#include <QMessageBox>
#include <QScrollBar>
#include <QTextBrowser>
#include <QToolBar>

#include <cstdio>

#include "app/gui/viewer.hpp"
#include "gui_measure_util.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/versions.hpp"

using namespace iso;
using namespace iso::test;
using GuiMenus = HeadWindow;

namespace {

QMenu* menu(gui::MainWindow& w, const char* name) {
    auto* m = w.findChild<QMenu*>(name);
    if (m) emit m->aboutToShow(); // as opening it does
    return m;
}

QAction* action_named(QMenu* m, const QString& text) {
    for (auto* a : m->actions())
        if (a->text().remove('&') == text) return a;
    return nullptr;
}

template <class T> T* top_level(const char* name) {
    for (auto* w : QApplication::topLevelWidgets())
        if (auto* t = qobject_cast<T*>(w); t && t->objectName() == name && t->isVisible()) return t;
    return nullptr;
}

} // namespace

// Every dock and tool bar has an entry; a closed dock comes back from it.
TEST_F(GuiMenus, ViewMenuShowsAndHidesEachDockAndToolBar) {
    gui::MainWindow& w = window();
    QMenu* view = menu(w, "view_menu");
    ASSERT_NE(view, nullptr);
    const auto docks = w.findChildren<QDockWidget*>();
    const auto bars = w.findChildren<QToolBar*>();
    ASSERT_GE(docks.size(), 2);
    for (auto* dock : docks) {
        QAction* a = action_named(view, dock->windowTitle());
        ASSERT_NE(a, nullptr) << "no View entry for the dock " << dock->windowTitle().toStdString();
        ASSERT_TRUE(dock->isVisible());
        dock->close(); // as its close button does
        EXPECT_FALSE(dock->isVisible());
        EXPECT_FALSE(a->isChecked());
        a->trigger();
        EXPECT_TRUE(dock->isVisible()) << dock->windowTitle().toStdString() << " did not come back";
    }
    for (auto* bar : bars) {
        QAction* a = action_named(view, bar->windowTitle());
        ASSERT_NE(a, nullptr) << "no View entry for the tool bar " << bar->windowTitle().toStdString();
        a->trigger();
        EXPECT_FALSE(bar->isVisible());
        a->trigger();
        EXPECT_TRUE(bar->isVisible());
    }
}

// View > Layout lists the six layouts (one checked at a time, each with a
// tooltip and its Ctrl+digit), and View has the slice planes toggle;
// choosing an entry sets the window's layout.
TEST_F(GuiMenus, ViewMenuHasTheLayoutsAndTheSlicePlanesToggle) {
    gui::MainWindow& w = window();
    QMenu* view = menu(w, "view_menu");
    ASSERT_NE(view, nullptr);
    QAction* entry = action_named(view, "Layout");
    ASSERT_NE(entry, nullptr);
    ASSERT_NE(entry->menu(), nullptr);
    const auto layouts = entry->menu()->actions();
    ASSERT_EQ(layouts.size(), 6);
    for (int i = 0; i < 6; ++i) {
        QAction* a = layouts[i];
        EXPECT_TRUE(a->isCheckable());
        EXPECT_FALSE(a->toolTip().isEmpty());
        EXPECT_NE(a->toolTip(), a->text().remove('&')) << "a tooltip that says more than the entry";
        EXPECT_EQ(a->shortcut(), QKeySequence(Qt::CTRL | Qt::Key(Qt::Key_1 + i)));
        EXPECT_EQ(a, w.layouts()->layout_action(core::ViewLayout(i)));
    }
    layouts[3]->trigger();
    EXPECT_EQ(w.workspace().layout(), core::ViewLayout::Axial);
    int checked = 0;
    for (QAction* a : layouts) checked += a->isChecked();
    EXPECT_EQ(checked, 1);
    EXPECT_TRUE(layouts[3]->isChecked());
    layouts[0]->trigger();
    EXPECT_EQ(w.workspace().layout(), core::ViewLayout::FourUp);
    QAction* planes = action_named(view, "Slice planes in 3D");
    ASSERT_NE(planes, nullptr);
    EXPECT_EQ(planes, w.layouts()->slice_planes_action());
    EXPECT_TRUE(planes->isCheckable());
    EXPECT_FALSE(planes->toolTip().isEmpty());
    EXPECT_FALSE(w.workspace().slice_planes_in_3d());
    planes->trigger();
    EXPECT_TRUE(w.workspace().slice_planes_in_3d());
}

// About names isoscope's and its libraries' versions, Qt's and the GL
// renderer the 3D view draws with (the one a headless render reports).
TEST_F(GuiMenus, AboutNamesTheVersionsAndTheRenderer) {
    gui::MainWindow& w = window();
    ASSERT_TRUE(wait_until([&] { return w.viewer() && w.viewer()->frames() > 0; }, 60000));
    const QString about = w.about_text();
    for (const auto& [name, version] : core::component_versions()) {
        EXPECT_TRUE(about.contains(QString::fromStdString(name))) << name;
        EXPECT_TRUE(about.contains(QString::fromStdString(version))) << name << " " << version;
    }
    EXPECT_TRUE(about.contains(qVersion()));
    const auto r = run_command(cli() + " render " + headsq() + " --iso 500 --size 64x48 --no-aa --stats -o " +
                               (std::filesystem::path(dir().path()) / "r.png").string());
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto open = r.out.find("rendered 64x48 ("), close = r.out.find(") -> ", open);
    ASSERT_NE(open, std::string::npos) << r.out;
    const std::string renderer = r.out.substr(open + 16, close - open - 16);
    EXPECT_TRUE(about.contains(QString::fromStdString(renderer).toHtmlEscaped())) << renderer;
    // The menu entry opens it, not modal.
    QMenu* help = w.findChild<QMenu*>("help_menu");
    ASSERT_NE(help, nullptr);
    w.findChild<QAction*>("help_about")->trigger();
    QMessageBox* box = nullptr;
    ASSERT_TRUE(wait_until([&] { return (box = top_level<QMessageBox>("about_box")) != nullptr; }, 30000));
    EXPECT_EQ(box->text(), about);
    box->close();
}

// Help > Mouse and keyboard lists the 3D view's keys and the slice views' bindings.
TEST_F(GuiMenus, BindingsListTheViewsKeys) {
    gui::MainWindow& w = window();
    w.findChild<QAction*>("help_bindings")->trigger();
    QDialog* d = nullptr;
    ASSERT_TRUE(wait_until([&] { return (d = top_level<QDialog>("bindings_dialog")) != nullptr; }, 30000));
    const QString text = d->findChild<QTextBrowser*>()->toPlainText();
    for (const char* s :
         {"A P L R S I", "O", "Page Up", "Left drag", "Middle drag", "Right drag", "Escape", "Ctrl+Z",
          "F, double-click, Fit", "Pointer over a view", "Slider under a view", "Ctrl+1", "Ctrl+Shift+P"})
        EXPECT_TRUE(text.contains(s)) << s;
    EXPECT_FALSE(d->isModal());
    d->close();
}

// Every control of the window says what it does when the pointer rests on
// it (buttons, sliders, number boxes, lists), a surface's row included;
// scroll bars and Qt's own title-bar and overflow buttons aside.
TEST_F(GuiMenus, EveryControlHasATooltip) {
    gui::MainWindow& w = window();
    std::vector<std::string> missing;
    int checked = 0;
    for (QWidget* c : w.findChildren<QWidget*>()) {
        const bool control = qobject_cast<QAbstractButton*>(c) || qobject_cast<QAbstractSlider*>(c) ||
                             qobject_cast<QAbstractSpinBox*>(c) || qobject_cast<QComboBox*>(c);
        const QString cls = c->metaObject()->className();
        if (!control || !c->isVisible() || qobject_cast<QScrollBar*>(c) || cls == "QDockWidgetTitleButton" ||
            cls == "QTableCornerButton" || c->objectName() == "qt_toolbar_ext_button")
            continue;
        ++checked;
        if (c->toolTip().trimmed().isEmpty())
            missing.push_back(cls.toStdString() + " '" + c->objectName().toStdString() + "'");
    }
    std::printf("%d controls checked\n", checked);
    EXPECT_GT(checked, 20);
    for (const auto& m : missing) ADD_FAILURE() << "no tooltip: " << m;
}

// At the window's default size (1280 x 900) no tool is hidden in a tool
// bar's overflow (the Distance tool was); Edit > Delete all measurements is
// enabled only with a measurement; the title names the session once there
// is one, else the data, with "*" while there is unsaved work.
TEST(GuiMenusDefault, ToolsShowDeleteAllFollowsTheMeasurementsTitleNamesTheSession) {
    ISO_SKIP_WITHOUT_DISPLAY();
    TempDir dir;
    const auto app = make_app("gui_menus_default", dir / "config");
    gui::MainWindow w;
    fewer_still_frames(w); // gui_test_util.hpp
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    ASSERT_EQ(w.size(), QSize(1280, 900));
    for (QToolBar* bar : w.findChildren<QToolBar*>())
        for (QAction* a : bar->actions()) {
            if (a->isSeparator() || !a->isVisible()) continue;
            QWidget* button = bar->widgetForAction(a);
            ASSERT_NE(button, nullptr) << a->text().toStdString();
            EXPECT_TRUE(button->isVisible()) << bar->objectName().toStdString() << ": " << a->text().toStdString()
                                             << " is in the tool bar's overflow";
        }
    auto* clear = w.findChild<QAction*>("clear_measurements");
    ASSERT_NE(clear, nullptr);
    EXPECT_FALSE(clear->isEnabled()) << "nothing open";
    EXPECT_EQ(w.windowTitle(), "isoscope[*]");
    w.open_path(QString::fromStdString(headsq()));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    EXPECT_FALSE(clear->isEnabled()) << "a volume, no measurement";
    EXPECT_TRUE(clear->toolTip().contains("No measurement")) << clear->toolTip().toStdString();
    EXPECT_EQ(w.windowTitle(), "isoscope - headsq.nhdr[*]");
    Markup m;
    m.type = MarkupType::Fiducial;
    m.name = "AVM nidus";
    m.points.resize(1);
    w.context().edit("Add AVM nidus", core::Parts(core::Part::Markups), [&] { w.workspace().set_markups({{m}, {}}); });
    EXPECT_TRUE(clear->isEnabled());
    EXPECT_TRUE(w.isWindowModified());
    const std::string session = dir / "day one.isoscope.json";
    w.files()->save_session(QString::fromStdString(session));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000));
    EXPECT_EQ(w.windowTitle(), "isoscope - day one.isoscope.json[*]");
    EXPECT_FALSE(w.isWindowModified());
    clear->trigger();
    EXPECT_TRUE(w.workspace().markups().empty());
    EXPECT_FALSE(clear->isEnabled());
    EXPECT_TRUE(w.isWindowModified());
}
