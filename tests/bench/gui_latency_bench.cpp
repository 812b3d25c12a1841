// Input latency of the desktop app while its 3D view accumulates still
// frames (docs/gui.md, "Still frames off the GUI thread"): the main window
// opens datasets/headsq.nhdr, adds the skin (iso 500, opacity 0.3: the
// translucent case, the slowest still frames) and the bone (1150), with
// the 3D view's default look (cone AO over 16 still frames, anti-aliased).
// Each trial drags the 3D view (a left-button rotation of 10 moves), lets
// go, and measures
//   - the time from the release to the first still frame with AO on screen,
//     and to the converged picture;
//   - while the still frames accumulate: a slice step (a wheel notch posted
//     to the axial view, timed to the end of that view's repaint) and a
//     button press (posted press and release, timed to its clicked signal),
//     three of each, 200-400 ms apart, as a user would go on working;
//   - how long the GUI thread was away from its event loop: the lateness of
//     a 10 ms timer from the release to the converged picture (the "~30 ms
//     at a time" rule).
// Two ways, taking turns trial by trial so a shared machine's load reaches
// both alike: still frames drawn on the GUI thread (ViewerOptions::still_thread
// off, as before) and on their own thread (the default).
//
//   xvfb-run -a -s '-screen 0 1600x1200x24' build/tests/bench/gui_latency_bench [--trials 4] [--csv docs/gui_latency.csv]
//
// Prints a markdown table; writes the CSV (one row per way).
#include <QApplication>
#include <QEventLoop>
#include <QMouseEvent>
#include <QPushButton>
#include <QStatusBar>
#include <QSurfaceFormat>
#include <QTimer>
#include <QWheelEvent>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "app/gui/main_window.hpp"
#include "gui_bench_util.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "renderer/core/scene.hpp"

using namespace iso;
using bench::now_ms;
using bench::quantile;
using bench::wait_until;

namespace {

void wait_ms(int ms) {
    const double until = now_ms() + ms;
    wait_until([&] { return now_ms() >= until; }, ms + 1000);
}

int fail(const std::string& why) {
    std::fprintf(stderr, "gui_latency_bench: %s\n", why.c_str());
    return 1;
}

struct Way {
    const char* name;
    bool thread;
    std::vector<double> first_still, converged, slice_step, button, stall;
    int inputs_during_accumulation = 0, inputs = 0;
};

// The 10 ms probe: how late each tick came (the GUI thread was busy meanwhile).
struct Probe {
    QTimer timer;
    double last = 0;
    std::vector<double> late;
    Probe() {
        timer.setTimerType(Qt::PreciseTimer);
        timer.setInterval(10);
        QObject::connect(&timer, &QTimer::timeout, [this] {
            const double t = now_ms();
            if (last > 0) late.push_back(std::max(0.0, t - last - 10.0));
            last = t;
        });
        timer.start();
    }
};

void post_mouse(QWidget* to, QEvent::Type type, QPointF at, Qt::MouseButton b, Qt::MouseButtons held) {
    QCoreApplication::postEvent(to, new QMouseEvent(type, at, to->mapToGlobal(at), b, held, Qt::NoModifier));
}

// A left drag of the 3D view: press, 10 moves of 8 pixels (each waits for
// its frame), release; returns the time of the release.
double drag(gui::Viewer& v) {
    const QPointF mid(v.width() / 2.0, v.height() / 2.0);
    post_mouse(&v, QEvent::MouseButtonPress, mid, Qt::LeftButton, Qt::LeftButton);
    for (int k = 1; k <= 10; ++k) {
        const int drawn = v.frames();
        post_mouse(&v, QEvent::MouseMove, mid + QPointF(8 * k, 0), Qt::NoButton, Qt::LeftButton);
        wait_until([&] { return v.frames() > drawn; }, 30000);
    }
    const double t = now_ms();
    post_mouse(&v, QEvent::MouseButtonRelease, mid + QPointF(80, 0), Qt::LeftButton, Qt::NoButton);
    return t;
}

// One trial of `way`; false: something did not arrive in time.
bool trial(gui::MainWindow& w, Way& way, QPushButton& button, std::mt19937& rng) {
    gui::Viewer& v = *w.viewer();
    gui::SliceView& axial = *w.slice_view(core::SliceOrientation::Axial);
    gui::ViewerOptions o = v.options();
    o.still_thread = way.thread;
    v.set_options(o);
    if (!wait_until([&] { return v.converged(); }, 300000)) return false;
    const double released = drag(v);
    Probe probe; // from the release on: the drag's own frames are the interaction
    if (!wait_until([&] { return !v.dragging() && v.ao_frames() > 0; }, 120000)) return false;
    way.first_still.push_back(now_ms() - released);
    // The user goes on working while the still frames accumulate.
    // The time the axial view last painted (an overlay of the bench's own,
    // after the window's; it outlives this run, so it keeps a shared cell).
    auto painted_at = std::make_shared<double>(0.0);
    axial.add_overlay([painted_at](gui::SliceView&, QPainter&) { *painted_at = now_ms(); });
    double& painted = *painted_at;
    double clicked = 0;
    const auto c = QObject::connect(&button, &QPushButton::clicked, [&] { clicked = now_ms(); });
    std::uniform_int_distribution<int> gap(200, 400);
    for (int k = 0; k < 6; ++k) {
        wait_ms(gap(rng));
        const bool accumulating = !v.converged();
        const double t0 = now_ms();
        if (k % 2 == 0) {
            painted = 0;
            const QPointF at(axial.width() / 2.0, axial.height() / 2.0);
            QCoreApplication::postEvent(&axial, new QWheelEvent(at, axial.mapToGlobal(at), QPoint(),
                                                                QPoint(0, k % 4 ? 120 : -120), Qt::NoButton,
                                                                Qt::NoModifier, Qt::NoScrollPhase, false));
            if (!wait_until([&] { return painted > 0; }, 30000)) return false;
            way.slice_step.push_back(painted - t0);
        } else {
            clicked = 0;
            const QPointF at(button.width() / 2.0, button.height() / 2.0);
            post_mouse(&button, QEvent::MouseButtonPress, at, Qt::LeftButton, Qt::LeftButton);
            post_mouse(&button, QEvent::MouseButtonRelease, at, Qt::LeftButton, Qt::NoButton);
            if (!wait_until([&] { return clicked > 0; }, 30000)) return false;
            way.button.push_back(clicked - t0);
        }
        ++way.inputs;
        way.inputs_during_accumulation += accumulating ? 1 : 0;
    }
    QObject::disconnect(c);
    if (!wait_until([&] { return v.converged(); }, 300000)) return false;
    way.converged.push_back(now_ms() - released);
    way.stall.insert(way.stall.end(), probe.late.begin(), probe.late.end());
    return v.error().empty();
}

} // namespace

int main(int argc, char** argv) {
    int trials = 4;
    std::string csv = std::string(ISOSCOPE_SOURCE_DIR) + "/docs/gui_latency.csv";
    std::string input = std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--trials" && i + 1 < argc)
            trials = std::max(1, std::atoi(argv[++i]));
        else if (a == "--csv" && i + 1 < argc)
            csv = argv[++i];
        else if (a == "--input" && i + 1 < argc)
            input = argv[++i];
        else {
            std::printf("usage: gui_latency_bench [--trials N] [--csv FILE] [--input VOLUME]  (under xvfb-run)\n");
            return a == "--help" ? 0 : 2;
        }
    }
    bench::set_gl_format();
    int qargc = 1;
    char* qargv[] = {argv[0], nullptr};
    QApplication app(qargc, qargv);
    QApplication::setOrganizationName("isoscope-bench");
    QApplication::setApplicationName("gui_latency_bench");

    gui::MainWindow w; // its default size, as a user first sees it
    QPushButton button("probe");
    w.statusBar()->addPermanentWidget(&button);
    if (const std::string why = bench::open_head(w, input); !why.empty()) return fail(why);
    const auto ids = w.scene().surfaces();
    core::SurfaceInfo skin = w.scene().info(ids[0]);
    skin.opacity = 0.3f;
    w.workspace().set_surface_info(ids[0], skin);
    gui::Viewer* v = w.viewer();
    if (!v || !wait_until([&] { return v->frames() > 0 || !v->error().empty(); }, 60000)) return fail("no 3D frame");
    if (!v->error().empty()) return fail(v->error());
    const QSize size = v->image_size();
    std::printf("gui_latency_bench: %s, skin 500 at 0.3 + bone 1150, 3D view %d x %d, cone AO %d still frames, "
                "%d trials per way\n\n",
                input.c_str(), size.width(), size.height(), v->options().look.ao_frames, trials);

    std::vector<Way> ways = {{"GUI thread (before)", false, {}, {}, {}, {}, {}, 0, 0},
                             {"own thread", true, {}, {}, {}, {}, {}, 0, 0}};
    std::mt19937 rng(7);
    for (int t = 0; t < trials; ++t)
        for (auto& way : ways)
            if (!trial(w, way, button, rng)) return fail(std::string("a trial timed out (") + way.name + ")");

    std::printf("| still frames drawn on | first AO frame after release, median ms | converged, median s | slice step "
                "median / max ms | button median / max ms | GUI thread away p99 / max ms | inputs while "
                "accumulating |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
    std::string out = "way,width,height,trials,first_still_median_ms,converged_median_ms,slice_step_median_ms,"
                      "slice_step_max_ms,button_median_ms,button_max_ms,stall_p99_ms,stall_max_ms,inputs_accumulating,"
                      "inputs\n";
    for (const auto& way : ways) {
        const double step_max = *std::max_element(way.slice_step.begin(), way.slice_step.end());
        const double button_max = *std::max_element(way.button.begin(), way.button.end());
        const double stall_max = way.stall.empty() ? 0 : *std::max_element(way.stall.begin(), way.stall.end());
        std::printf("| %s | %.0f | %.1f | %.0f / %.0f | %.0f / %.0f | %.0f / %.0f | %d of %d |\n", way.name,
                    quantile(way.first_still, 0.5), quantile(way.converged, 0.5) / 1000, quantile(way.slice_step, 0.5),
                    step_max, quantile(way.button, 0.5), button_max, quantile(way.stall, 0.99), stall_max,
                    way.inputs_during_accumulation, way.inputs);
        char line[512];
        std::snprintf(line, sizeof line, "%s,%d,%d,%d,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%d,%d\n",
                      way.thread ? "thread" : "gui", size.width(), size.height(), trials,
                      quantile(way.first_still, 0.5), quantile(way.converged, 0.5), quantile(way.slice_step, 0.5),
                      step_max, quantile(way.button, 0.5), button_max, quantile(way.stall, 0.99), stall_max,
                      way.inputs_during_accumulation, way.inputs);
        out += line;
    }
    try {
        bench::write_text(csv, out);
    } catch (const std::exception& e) {
        return fail(e.what());
    }
    std::printf("\nwrote %s\n", csv.c_str());
    return 0;
}
