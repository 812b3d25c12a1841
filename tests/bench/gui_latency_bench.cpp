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
// Before that, the drag itself: 60 moves 16 ms apart as a hand makes them
// (not waiting for frames): the frames drawn per second and how late the
// GUI thread came back to its loop meanwhile.
// Two ways, taking turns trial by trial so a shared machine's load reaches
// both alike: frames drawn on the GUI thread (ViewerOptions::still_thread
// off) and on the frame thread (the default: still frames and a drag's).
// --volume TF: the volume ray cast with that transfer function instead,
// the surfaces hidden (issue 41: the volume follows the surfaces' rules).
//
//   xvfb-run -a -s '-screen 0 1600x1200x24' build/tests/bench/gui_latency_bench [--trials 4] [--csv docs/gui_latency.csv]
//       [--volume "450:0:#a0522d,600:0.015:#e0a080,1000:0.015:#e8c0a0,1150:0.5:#f4ecd8,4000:0.8:#ffffff"]
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
using bench::post_mouse;
using bench::Probe;
using bench::quantile;
using bench::wait_ms;
using bench::wait_until;

namespace {

int fail(const std::string& why) { return bench::fail("gui_latency_bench", why); }

struct Way {
    const char* name;
    bool thread;
    std::vector<double> first_still, converged, slice_step, button, stall;
    std::vector<double> drag_fps, drag_stall; // frames drawn per second of a drag; the GUI thread's lateness then
    int inputs_during_accumulation = 0, inputs = 0;
};

// A left drag of the 3D view as a hand makes it: press, 60 moves of 3
// pixels 16 ms apart (a 60 Hz pointer; the moves do not wait for frames), release. Returns
// the time of the release; `fps`: the frames the view drew meanwhile per
// second (on the frame thread: the frames that arrived from it), `stall`:
// how late the GUI thread came back to its loop meanwhile (10 ms timer).
double drag(gui::Viewer& v, bool thread, double& fps, std::vector<double>& stall) {
    const QPointF mid(v.width() / 2.0, v.height() / 2.0);
    Probe probe;
    const int before = thread ? v.thread_frames() : v.frames();
    const double t0 = now_ms();
    post_mouse(&v, QEvent::MouseButtonPress, mid, Qt::LeftButton, Qt::LeftButton);
    for (int k = 1; k <= 60; ++k) {
        wait_ms(16);
        post_mouse(&v, QEvent::MouseMove, mid + QPointF(3 * (k % 40), 0), Qt::NoButton, Qt::LeftButton);
    }
    wait_ms(16);
    const double t = now_ms();
    fps = ((thread ? v.thread_frames() : v.frames()) - before) / ((t - t0) / 1000.0);
    stall = probe.late;
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
    double fps = 0;
    std::vector<double> drag_stall;
    const double released = drag(v, way.thread, fps, drag_stall);
    way.drag_fps.push_back(fps);
    way.drag_stall.insert(way.drag_stall.end(), drag_stall.begin(), drag_stall.end());
    Probe probe; // from the release on
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

double max_of(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }

// The table (markdown) and the CSV, one row per way; throws iso::Error.
void report(const std::vector<Way>& ways, QSize size, int trials, const std::string& scene, const std::string& csv) {
    std::printf("| frames drawn on | drag frames per s, median | GUI thread away during the drag, p99 / max ms | "
                "first AO frame after release, median ms | converged, median s | slice step median / max ms | "
                "button median / max ms | GUI thread away after, p99 / max ms | inputs while accumulating |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    std::string out = "scene,way,width,height,trials,drag_fps_median,drag_stall_p99_ms,drag_stall_max_ms,"
                      "first_still_median_ms,converged_median_ms,slice_step_median_ms,slice_step_max_ms,"
                      "button_median_ms,button_max_ms,stall_p99_ms,stall_max_ms,inputs_accumulating,inputs\n";
    for (const auto& way : ways) {
        std::printf("| %s | %.1f | %.0f / %.0f | %.0f | %.1f | %.0f / %.0f | %.0f / %.0f | %.0f / %.0f | %d of %d |\n",
                    way.name, quantile(way.drag_fps, 0.5), quantile(way.drag_stall, 0.99), max_of(way.drag_stall),
                    quantile(way.first_still, 0.5), quantile(way.converged, 0.5) / 1000, quantile(way.slice_step, 0.5),
                    max_of(way.slice_step), quantile(way.button, 0.5), max_of(way.button), quantile(way.stall, 0.99),
                    max_of(way.stall), way.inputs_during_accumulation, way.inputs);
        char line[512];
        std::snprintf(line, sizeof line,
                      "%s,%s,%d,%d,%d,%.2f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%.1f,%d,%d\n", scene.c_str(),
                      way.thread ? "thread" : "gui", size.width(), size.height(), trials, quantile(way.drag_fps, 0.5),
                      quantile(way.drag_stall, 0.99), max_of(way.drag_stall), quantile(way.first_still, 0.5),
                      quantile(way.converged, 0.5), quantile(way.slice_step, 0.5), max_of(way.slice_step),
                      quantile(way.button, 0.5), max_of(way.button), quantile(way.stall, 0.99), max_of(way.stall),
                      way.inputs_during_accumulation, way.inputs);
        out += line;
    }
    bench::write_text(csv, out);
}

} // namespace

int main(int argc, char** argv) {
    int trials = 4;
    std::string csv = std::string(ISOSCOPE_SOURCE_DIR) + "/docs/gui_latency.csv";
    std::string input = std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr";
    std::string volume; // --volume TF: the volume ray cast, the surfaces hidden
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--trials" && i + 1 < argc)
            trials = std::max(1, std::atoi(argv[++i]));
        else if (a == "--csv" && i + 1 < argc)
            csv = argv[++i];
        else if (a == "--input" && i + 1 < argc)
            input = argv[++i];
        else if (a == "--volume" && i + 1 < argc)
            volume = argv[++i];
        else {
            std::printf("usage: gui_latency_bench [--trials N] [--csv FILE] [--input VOLUME] [--volume TF]  (under "
                        "xvfb-run)\n");
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
    std::string scene = "skin 500 at 0.3 + bone 1150";
    if (!volume.empty()) { // the volume alone, as the Volume dock shows it
        for (auto id : ids) {
            core::SurfaceInfo info = w.scene().info(id);
            info.visible = false;
            w.workspace().set_surface_info(id, info);
        }
        FrameLook look = w.workspace().look();
        look.volume.enabled = true;
        look.volume.tf = transfer_function_from(volume);
        w.workspace().set_look(look);
        scene = "the volume ray cast (" + volume + "), surfaces hidden";
    }
    gui::Viewer* v = w.viewer();
    if (!v || !wait_until([&] { return v->frames() > 0 || !v->error().empty(); }, 60000)) return fail("no 3D frame");
    if (!v->error().empty()) return fail(v->error());
    const QSize size = v->image_size();
    std::printf("gui_latency_bench: %s, %s, 3D view %d x %d, cone AO %d still frames, %d trials per way\n\n",
                input.c_str(), scene.c_str(), size.width(), size.height(), v->options().look.ao_frames, trials);

    std::vector<Way> ways = {{"GUI thread", false, {}, {}, {}, {}, {}, {}, {}, 0, 0},
                             {"frame thread", true, {}, {}, {}, {}, {}, {}, {}, 0, 0}};
    std::mt19937 rng(7);
    for (int t = 0; t < trials; ++t)
        for (auto& way : ways)
            if (!trial(w, way, button, rng)) return fail(std::string("a trial timed out (") + way.name + ")");

    try {
        report(ways, size, trials, volume.empty() ? "surfaces" : "volume", csv);
    } catch (const std::exception& e) {
        return fail(e.what());
    }
    std::printf("\nwrote %s\n", csv.c_str());
    return 0;
}
