// What the desktop app's benchmark programs share (gui_frame_bench,
// gui_latency_bench): the event loop run until a condition, times, the GL
// format, the bundled head opened with its skin and bone, the CSV written.
#pragma once

#include <QApplication>
#include <QEventLoop>
#include <QMouseEvent>
#include <QSurfaceFormat>
#include <QTimer>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "renderer/core/scene.hpp"

namespace iso::bench {

inline double now_ms() {
    using namespace std::chrono;
    return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

// Runs the event loop until `ready` or `timeout_ms`.
inline bool wait_until(const std::function<bool()>& ready, int timeout_ms) {
    const double t0 = now_ms();
    while (!ready()) {
        if (now_ms() - t0 > timeout_ms) return false;
        QEventLoop loop;
        QTimer::singleShot(5, &loop, &QEventLoop::quit);
        loop.exec();
    }
    return true;
}

// Nearest rank: the smallest sample with at least q of them at or below it.
inline double quantile(std::vector<double> v, double q) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const std::size_t k = std::size_t(std::ceil(q * double(v.size())));
    return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
}

// The desktop app's GL format (before the QApplication).
inline void set_gl_format() {
    QSurfaceFormat fmt;
    fmt.setVersion(4, 5);
    fmt.setProfile(QSurfaceFormat::CoreProfile);
    fmt.setDepthBufferSize(24);
    QSurfaceFormat::setDefaultFormat(fmt);
}

// Shows `w` (its default size, as a user first sees it), opens `input` and
// adds the skin (500) and the bone (1150); empty when done, else why not.
inline std::string open_head(gui::MainWindow& w, const std::string& input) {
    w.show();
    if (!wait_until([&] { return w.isVisible(); }, 10000)) return "the window did not show";
    w.open_path(QString::fromStdString(input));
    if (!wait_until([&] { return !w.busy(); }, 120000) || !w.scene().has_volume()) return "cannot open " + input;
    for (double iso : {500.0, 1150.0}) {
        w.surfaces_panel()->add_surface(iso);
        if (!wait_until([&] { return !w.busy(); }, 300000)) return "the extraction did not finish";
    }
    if (w.scene().surfaces().size() != 2) return "expected the skin and the bone surfaces";
    return {};
}

// Shows the window and opens a mesh file in it; an error's text, or empty.
inline std::string open_mesh(gui::MainWindow& w, const std::string& path) {
    w.show();
    if (!wait_until([&] { return w.isVisible(); }, 10000)) return "the window did not show";
    w.open_path(QString::fromStdString(path));
    if (!wait_until([&] { return !w.busy(); }, 300000) || w.scene().surfaces().empty()) return "cannot open " + path;
    return {};
}

// Runs the event loop for `ms`.
inline void wait_ms(int ms) {
    const double until = now_ms() + ms;
    wait_until([&] { return now_ms() >= until; }, ms + 1000);
}

// The 10 ms probe: how late each tick came (the GUI thread was busy meanwhile).
struct Probe {
    QTimer timer;
    double last = 0;
    std::vector<double> late;
    // From the start: an event handled before the first tick is counted too.
    Probe() : last(now_ms()) {
        timer.setTimerType(Qt::PreciseTimer);
        timer.setInterval(10);
        QObject::connect(&timer, &QTimer::timeout, [this] {
            const double t = now_ms();
            late.push_back(std::max(0.0, t - last - 10.0));
            last = t;
        });
        timer.start();
    }
    double max() const { return late.empty() ? 0.0 : *std::max_element(late.begin(), late.end()); }
};

// A mouse event posted to `to` (as the window system delivers them: queued).
inline void post_mouse(QWidget* to, QEvent::Type type, QPointF at, Qt::MouseButton b, Qt::MouseButtons held) {
    QCoreApplication::postEvent(to, new QMouseEvent(type, at, to->mapToGlobal(at), b, held, Qt::NoModifier));
}

// Writes `text` to `path` atomically; throws iso::Error.
inline void write_text(const std::string& path, const std::string& text) {
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream f(tmp);
        f << text;
        if (!f.flush()) throw Error(path, "cannot write");
    });
}

// A benchmark's failure: "PROGRAM: why" on stderr; the exit status, 1.
inline int fail(const char* program, const std::string& why) {
    std::fprintf(stderr, "%s: %s\n", program, why.c_str());
    return 1;
}

// Writes the CSV and says where; the exit status (fail's when it cannot).
inline int write_csv(const char* program, const std::string& path, const std::string& text) {
    try {
        write_text(path, text);
    } catch (const std::exception& e) {
        return fail(program, e.what());
    }
    std::printf("\nwrote %s\n", path.c_str());
    return 0;
}

} // namespace iso::bench
