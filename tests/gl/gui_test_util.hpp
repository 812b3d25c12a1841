// Shared by the desktop app's tests (tests/gl/main_window_test.cpp,
// tests/gl/gui_*_test.cpp): they drive the widgets in-process with QTest
// (make_app) in a real X server. CTest runs each of these programs under
// xvfb-run (tests/CMakeLists.txt); started without a display they skip
// (ISO_SKIP_WITHOUT_DISPLAY). Expected values come from the core API, not from
// the window's own state.
#pragma once

#include <QApplication>
#include <QDoubleSpinBox>
#include <QElapsedTimer>
#include <QImage>
#include <QMouseEvent>
#include <QPushButton>
#include <QSurfaceFormat>
#include <QTest>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "app/gui/app_context.hpp"
#include "app/gui/files.hpp"
#include "app/gui/layouts.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/unsaved_work.hpp"
#include "app/gui/viewer.hpp"
#include "tests/support/test_util.hpp"

namespace iso::test {

inline bool wait_until(const std::function<bool()>& ready, int timeout_ms) {
    QElapsedTimer t;
    t.start();
    while (!ready()) {
        if (t.elapsed() > timeout_ms) return false;
        QTest::qWait(20);
    }
    return true;
}

// A left click in the 3D view, and its pick answered: the view picks on
// its frame thread (Viewer::pick_later), and the click's readout, point or
// crosshair follow when the answer arrives.
inline void click_3d(gui::Viewer* v, QPoint at) {
    QTest::mouseClick(v, Qt::LeftButton, {}, at);
    ASSERT_TRUE(wait_until([&] { return v->picks_waiting() == 0; }, 60000)) << "the click's pick was not answered";
}

// Adds the isosurface at `iso` as the user does: the Surfaces panel's iso
// number, then Add surface; waits for the extraction to end.
inline void add_through_panel(gui::MainWindow& w, double iso) {
    auto* panel = w.surfaces_panel();
    auto* value = panel->findChild<QDoubleSpinBox*>("add_iso_value");
    auto* add = panel->findChild<QPushButton*>("add_surface");
    ASSERT_NE(value, nullptr);
    ASSERT_NE(add, nullptr);
    value->setValue(iso);
    QTest::mouseClick(add, Qt::LeftButton);
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the extraction did not finish";
}

// A drag with one button, as events sent to `target` at once: pressed at
// `from`, `steps` moves to `to`, released there.
inline void button_drag(QWidget* target, Qt::MouseButton button, QPointF from, QPointF to, int steps = 6) {
    const auto send = [&](QEvent::Type type, QPointF at, Qt::MouseButton b, Qt::MouseButtons held) {
        QMouseEvent e(type, at, target->mapToGlobal(at), b, held, Qt::NoModifier);
        QCoreApplication::sendEvent(target, &e);
    };
    send(QEvent::MouseButtonPress, from, button, button);
    for (int i = 1; i <= steps; ++i)
        send(QEvent::MouseMove, from + (to - from) * (double(i) / steps), Qt::NoButton, button);
    send(QEvent::MouseButtonRelease, to, button, Qt::NoButton);
}

// A widget's child of type T named `name` (none without the widget).
template <class T> T* child(QWidget* w, const char* name) { return w ? w->findChild<T*>(name) : nullptr; }

// A left drag delivered straight to the widget (QTest::mouseMove moves the X
// pointer, whose events arrive later), the event loop running between steps.
inline void drag_widget(QWidget* w, QPoint from, QPoint to, int steps = 5, int pause_ms = 30) {
    const auto send = [&](QEvent::Type type, QPoint at, Qt::MouseButtons held) {
        const Qt::MouseButton button = type == QEvent::MouseMove ? Qt::NoButton : Qt::LeftButton;
        QMouseEvent e(type, QPointF(at), w->mapToGlobal(QPointF(at)), button, held, Qt::NoModifier);
        QCoreApplication::sendEvent(w, &e);
    };
    send(QEvent::MouseButtonPress, from, Qt::LeftButton);
    for (int k = 1; k <= steps; ++k) {
        send(QEvent::MouseMove, from + (to - from) * k / steps, Qt::LeftButton);
        QTest::qWait(pause_ms);
    }
    send(QEvent::MouseButtonRelease, to, Qt::NoButton);
}

// Pixels brighter than black: the picture shows something, not an empty frame.
inline double lit_fraction(const QImage& img) {
    if (img.isNull()) return 0;
    const QImage g = img.convertToFormat(QImage::Format_Grayscale8);
    std::size_t lit = 0;
    for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x) lit += g.constScanLine(y)[x] > 20;
    return double(lit) / double(g.width() * g.height());
}

// Why a test skips: no X display to open windows on (CTest starts these
// programs under xvfb-run when it is installed; ./setup.sh installs it).
inline const char* missing_display() {
    const char* d = std::getenv("DISPLAY");
    return d && *d ? nullptr
                   : "no X display (DISPLAY unset): run under xvfb-run, as CTest does (./setup.sh installs it)";
}

// First in every test that opens windows: skips, saying why, without a display.
#define ISO_SKIP_WITHOUT_DISPLAY()                                                                                     \
    if (const char* why = ::iso::test::missing_display()) GTEST_SKIP() << why

// The tests' application: GL 4.5 core surfaces, settings (recent
// files) in `config_dir`, not the user's. Keep it while the test runs and
// let it go before the test ends (one per process: Qt allows one at a time;
// a static one would outlive Qt's own statics).
inline std::unique_ptr<QApplication> make_app(const std::string& name, const std::filesystem::path& config_dir) {
    ::setenv("XDG_CONFIG_HOME", config_dir.c_str(), 1);
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
    static int argc = 1;
    static std::string arg0;
    arg0 = name;
    static char* argv[2] = {nullptr, nullptr};
    argv[0] = arg0.data();
    auto app = std::make_unique<QApplication>(argc, argv);
    QApplication::setOrganizationName("isoscope-test");
    QApplication::setApplicationName(QString::fromStdString(name));
    return app;
}

// Fewer still frames in the 3D view than the app's 16 (cone AO and
// anti-aliasing accumulate over them; ViewerOptions::interactive_look).
// On llvmpipe a still frame of the head with a translucent skin takes about
// 0.8 s (1 s under the sanitizers; its translucent AO alone 0.55 s,
// `isoscope render --stats`), and the tests that wait for a converged view
// waited for 16 of them each time: what they check (threads, picks,
// pictures against the core's of the same look) holds at any count.
// Through the workspace's look, as a user's change of the look goes.
inline void fewer_still_frames(gui::MainWindow& w, int frames = 4) {
    FrameLook look = w.workspace().look();
    look.ao_frames = frames;
    look.aa.view_frames = frames;
    w.workspace().set_look(look);
}

// The test's output folder for screenshots: build/test_output/<name>.
inline std::filesystem::path output_dir(const std::string& name) {
    const auto out = std::filesystem::path(ISOSCOPE_BINARY_DIR) / "test_output" / name;
    std::filesystem::create_directories(out);
    return out;
}

} // namespace iso::test
