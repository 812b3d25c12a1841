// The desktop app on a massive volume (issue 39, item 4): what a user waits
// for, and how long the GUI thread is ever away from its event loop, from
// opening a 1024^3 micro-CT to measuring on its 30 M-triangle surface, on
// this machine's GL (llvmpipe here). As the user does it, in one window:
//
//   0. show the window and let it paint (1 s);
//   1. open the volume (File > Open's path);
//   2. add its isosurface in the Surfaces panel, press the progress
//      dialog's Cancel after 1.5 s (the time until the work stopped), then
//      add it again and let it finish;
//   3. wait for the 3D view's converged picture (the levels of detail are
//      built in the background meanwhile);
//   4. rotate: a left drag as a 60 Hz pointer makes it (180 moves 16 ms
//      apart, not waiting for frames): frames drawn in its first second
//      (the drag frames adapt: half size, then the stand-ins) and per
//      second after it;
//   5. hover: 2 s of pointer moves over the surface: hover picks answered,
//      and the time from each question to its answer;
//   6. measure: the Ruler, two clicks on the surface: the time from each
//      click to its readout, and the ruler's length against the distance
//      between the two points the core API picks at those pixels;
//   7. the Measurements table's answers for the ruler (the surface under
//      each point, the surfaces its line passes through), worked out off
//      the GUI thread: the time until they show;
// then the peak memory (VmHWM), and whether the GUI thread's GL context
// holds a copy of the scene (it should not: frames and picks are drawn on
// the frame thread's).
//
// Throughout, a 10 ms timer measures how late the GUI thread came back to
// its loop: "input <= 150 ms" is the largest lateness in each phase.
//
//   xvfb-run -a -s '-screen 0 1600x1200x24' build/tests/bench/gui_massive_bench VOLUME [--iso 300.5]
//       [--csv docs/gui_massive.csv] [--phases N] [--trace-events MS]
//
// --phases N: stop after the first N phases (four at least; to profile one;
// no CSV written).
// --trace-events MS: print each event the GUI thread took MS ms or more to
// handle (the receiver's class and name, the event's type): what a stall was.
//
// VOLUME: the 1024^3 phantom (`scale_bench --sizes 1024 --generate-only`),
// or any volume. Prints a markdown table; writes the CSV (one row per phase).
#include <QApplication>
#include <QMouseEvent>
#include <QTableWidget>
#include <QThread>
#include <QWindow>
#include <QProgressDialog>
#include <QPushButton>
#include <QStatusBar>
#include <QTimer>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "app/gui/main_window.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/measurements_panel.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/viewer.hpp"
#include "gui_bench_util.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/workspace.hpp"

using namespace iso;
using bench::now_ms;
using bench::post_mouse;
using bench::Probe;
using bench::quantile;
using bench::wait_ms;
using bench::wait_until;

namespace {

int fail(const std::string& why) { return bench::fail("gui_massive_bench", why); }

struct Phase {
    std::string name;
    double seconds = 0;                // the phase's own time (what the user waited for)
    double away_p99 = 0, away_max = 0; // the GUI thread's lateness meanwhile, ms
    std::string result;                // what came out
};

// Runs `step` with a probe; the phase's time is what `step` returns (s).
template <class F> Phase phase(const std::string& name, F&& step) {
    Probe probe;
    Phase p;
    p.name = name;
    p.seconds = step(p.result);
    p.away_p99 = quantile(probe.late, 0.99);
    p.away_max = probe.max();
    std::printf("  %s: %.2f s, GUI thread away at most %.0f ms; %s\n", name.c_str(), p.seconds, p.away_max,
                p.result.c_str());
    std::fflush(stdout);
    return p;
}

// The application, timing every event the GUI thread handles (outermost
// only: an event handled inside another's handler is part of it).
class TracingApp : public QApplication {
public:
    using QApplication::QApplication;
    double threshold_ms = 0; // 0: no tracing
    bool notify(QObject* receiver, QEvent* e) override {
        if (threshold_ms <= 0 || depth_ > 0 || QThread::currentThread() != thread())
            return QApplication::notify(receiver, e);
        // Read before: the handler may delete either.
        const std::string what = std::string(receiver->metaObject()->className()) + " '" +
                                 receiver->objectName().toStdString() + "' event " + std::to_string(int(e->type()));
        ++depth_;
        const double t0 = now_ms();
        const bool handled = QApplication::notify(receiver, e);
        const double ms = now_ms() - t0;
        --depth_;
        if (ms >= threshold_ms) std::printf("    [%.0f ms] %s\n", ms, what.c_str());
        return handled;
    }

private:
    int depth_ = 0;
};

// kB of a /proc/self/status field ("VmHWM", "VmRSS").
double status_mib(const char* field) {
    std::ifstream f("/proc/self/status");
    std::string line;
    const std::string key = std::string(field) + ":";
    while (std::getline(f, line))
        if (line.rfind(key, 0) == 0) return std::atof(line.c_str() + key.size()) / 1024.0;
    return 0;
}

// Two pixels of the view that show the surface, 40 pixels apart near the
// middle: the view's own picks (the frame thread draws them).
std::vector<QPointF> surface_pixels(gui::Viewer& v) {
    std::vector<QPointF> out;
    const QSize s = v.image_size();
    for (int j = 0; j < 9 && out.size() < 2; ++j)
        for (int i = 0; i < 9 && out.size() < 2; ++i) {
            const QPointF px(s.width() * (0.3 + 0.05 * i) + 0.5, s.height() * (0.3 + 0.05 * j) + 0.5);
            if (!out.empty() && std::hypot(px.x() - out[0].x(), px.y() - out[0].y()) < 40) continue;
            try {
                const core::PickResult r = v.pick_at(px);
                if (r.visible && !r.layers[*r.visible].volume) out.push_back(px);
            } catch (const std::exception&) {}
        }
    return out;
}

} // namespace

int main(int argc, char** argv) {
    std::string input, csv = std::string(ISOSCOPE_SOURCE_DIR) + "/docs/gui_massive.csv";
    double iso = 300.5;
    std::size_t stop_after = 99;
    double trace_ms = 0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--iso" && i + 1 < argc)
            iso = std::atof(argv[++i]);
        else if (a == "--phases" && i + 1 < argc)
            stop_after = std::size_t(std::atoi(argv[++i]));
        else if (a == "--trace-events" && i + 1 < argc)
            trace_ms = std::atof(argv[++i]);
        else if (a == "--csv" && i + 1 < argc)
            csv = argv[++i];
        else if (a[0] != '-' && input.empty())
            input = a;
        else {
            std::printf(
                "usage: gui_massive_bench VOLUME [--iso V] [--csv FILE] [--phases N] [--trace-events MS]  (under "
                "xvfb-run)\n");
            return a == "--help" ? 0 : 2;
        }
    }
    if (input.empty()) return fail("no volume given");
    bench::set_gl_format();
    int qargc = 1;
    char* qargv[] = {argv[0], nullptr};
    TracingApp app(qargc, qargv);
    app.threshold_ms = trace_ms;
    QApplication::setOrganizationName("isoscope-bench");
    QApplication::setApplicationName("gui_massive_bench");
    gui::MainWindow w;
    std::printf("gui_massive_bench: %s, iso %g\n", input.c_str(), iso);
    std::vector<Phase> phases;
    bool ok = true;

    // The window's first paints are a phase of their own: a user opens a
    // file once the window is there, while they happened during the opening
    // (the window composed through OpenGL: the GL libraries and llvmpipe's
    // shaders paged in and compiled, waiting on the disk behind the volume's
    // read, 250 ms blocked in one run's perf).
    // --phases N: after the Nth phase, a pause apart from the teardown (for a
    // profile), then the end, with no CSV.
    const auto stopped = [&] {
        if (phases.size() < stop_after) return false;
        wait_ms(2000);
        return true;
    };
    phases.push_back(phase("show the window (1 s)", [&](std::string& res) {
        const double t0 = now_ms();
        w.show();
        ok = wait_until([&] { return w.isVisible() && w.windowHandle() && w.windowHandle()->isExposed(); }, 10000);
        wait_ms(1000);
        res = std::to_string(w.width()) + "x" + std::to_string(w.height());
        return (now_ms() - t0) / 1000;
    }));
    if (!ok) return fail("the window did not show");

    phases.push_back(phase("open the volume", [&](std::string& res) {
        const double t0 = now_ms();
        w.open_path(QString::fromStdString(input));
        ok = wait_until([&] { return !w.busy(); }, 600000) && w.scene().has_volume();
        const auto& d = ok ? w.scene().volume().dims : std::array<std::int64_t, 3>{0, 0, 0};
        res = std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
        return (now_ms() - t0) / 1000;
    }));
    if (!ok) return fail("cannot open " + input);

    phases.push_back(phase("extract, cancelled after 1.5 s", [&](std::string& res) {
        w.surfaces_panel()->add_surface(iso);
        wait_ms(1500);
        auto* dialog = w.findChild<QProgressDialog*>();
        if (!dialog || !w.busy()) {
            res = "no progress dialog to cancel";
            return 0.0;
        }
        const double t0 = now_ms();
        // As the user presses it (QProgressDialog::cancel() alone does not say canceled()).
        auto* button = dialog->findChild<QPushButton*>();
        if (!button) {
            res = "no Cancel button";
            return 0.0;
        }
        QMetaObject::invokeMethod(
            button, [button] { button->click(); }, Qt::QueuedConnection);
        ok = wait_until([&] { return !w.busy(); }, 120000);
        res = std::to_string(w.scene().surfaces().size()) + " surfaces after the cancel";
        return (now_ms() - t0) / 1000; // the cancel's answer
    }));

    phases.push_back(phase("extract", [&](std::string& res) {
        const double t0 = now_ms();
        w.surfaces_panel()->add_surface(iso);
        ok = ok && wait_until([&] { return !w.busy(); }, 600000) && !w.scene().surfaces().empty();
        if (ok) res = std::to_string(w.scene().mesh(w.scene().surfaces().back()).triangles.size()) + " triangles";
        return (now_ms() - t0) / 1000;
    }));
    if (!ok) return fail("the extraction did not finish");
    if (stopped()) return 0;
    gui::Viewer* v = w.viewer();

    phases.push_back(phase("first picture, then converged", [&](std::string& res) {
        const double t0 = now_ms();
        ok = wait_until([&] { return v->frames() > 0 || !v->error().empty(); }, 600000);
        const double first = now_ms() - t0;
        ok = ok && wait_until([&] { return v->converged() || !v->error().empty(); }, 1200000) && v->error().empty();
        char b[160];
        std::snprintf(b, sizeof b, "first frame after %.1f s, %d frames from the frame thread", first / 1000,
                      v->thread_frames());
        res = b;
        return (now_ms() - t0) / 1000;
    }));
    if (!ok) return fail("no converged picture: " + v->error());

    if (stopped()) return 0;
    phases.push_back(phase("rotate (60 Hz drag, 3 s)", [&](std::string& res) {
        const QPointF mid(v->width() / 2.0, v->height() / 2.0);
        const int before = v->thread_frames();
        int after_1s = before;
        const double t0 = now_ms();
        post_mouse(v, QEvent::MouseButtonPress, mid, Qt::LeftButton, Qt::LeftButton);
        for (int k = 1; k <= 180; ++k) {
            wait_ms(16);
            post_mouse(v, QEvent::MouseMove, mid + QPointF(3 * (k % 40), 0), Qt::NoButton, Qt::LeftButton);
            if (k == 60) after_1s = v->thread_frames();
        }
        wait_ms(16);
        const double s = (now_ms() - t0) / 1000;
        post_mouse(v, QEvent::MouseButtonRelease, mid + QPointF(80, 0), Qt::LeftButton, Qt::NoButton);
        char b[200];
        std::snprintf(b, sizeof b, "%d frames in the first second, %.1f frames/s after it, the last in %.0f ms",
                      after_1s - before, (v->thread_frames() - after_1s) / (s - 1.0), v->last_thread_frame_ms());
        res = b;
        ok = wait_until([&] { return v->converged(); }, 1200000);
        return s;
    }));

    const std::vector<QPointF> on_surface = surface_pixels(*v);
    if (on_surface.size() < 2) return fail("fewer than two view pixels show the surface");
    auto* tools = w.measure_tools();

    if (stopped()) return 0;
    phases.push_back(phase("hover (60 Hz, 2 s)", [&](std::string& res) {
        const int before = tools->hover_picks();
        const double t0 = now_ms();
        const QPointF a = on_surface[0] / v->devicePixelRatioF(), b = on_surface[1] / v->devicePixelRatioF();
        for (int k = 0; k < 120; ++k) {
            post_mouse(v, QEvent::MouseMove, a + (b - a) * (k % 30) / 30.0, Qt::NoButton, Qt::NoButton);
            wait_ms(16);
        }
        ok = wait_until([&] { return v->picks_waiting() == 0; }, 60000);
        char s[160];
        std::snprintf(s, sizeof s, "%d hover picks answered, interval now %d ms", tools->hover_picks() - before,
                      tools->hover_interval_ms());
        res = s;
        return (now_ms() - t0) / 1000;
    }));

    if (stopped()) return 0;
    phases.push_back(phase("measure: Ruler, two clicks", [&](std::string& res) {
        tools->set_tool(gui::MeasureTools::Tool::Ruler);
        const std::size_t markups = w.workspace().markups().size();
        std::vector<double> answered;
        for (int k = 0; k < 2; ++k) {
            const QPointF at = on_surface[k] / v->devicePixelRatioF();
            const double t0 = now_ms();
            post_mouse(v, QEvent::MouseButtonPress, at, Qt::LeftButton, Qt::LeftButton);
            post_mouse(v, QEvent::MouseButtonRelease, at, Qt::LeftButton, Qt::NoButton);
            // The first click leaves a point waiting, the second makes the ruler.
            ok = ok &&
                 wait_until(
                     [&] {
                         return v->picks_waiting() == 0 &&
                                (k == 0 ? tools->pending().size() == 1 : w.workspace().markups().size() == markups + 1);
                     },
                     60000);
            answered.push_back(now_ms() - t0);
        }
        ok = ok && w.workspace().markups().size() == markups + 1;
        double length = NAN, expected = NAN;
        if (ok) {
            const auto& pts = w.workspace().markups().back().points;
            length = glm::distance(pts[0].position, pts[1].position);
            const core::PickResult p0 = v->pick_at(on_surface[0]), p1 = v->pick_at(on_surface[1]);
            expected = glm::distance(p0.layers[*p0.visible].lps, p1.layers[*p1.visible].lps);
        }
        char s[200];
        std::snprintf(s, sizeof s, "clicks answered in %.0f / %.0f ms; ruler %.4f mm, the core's picks %.4f mm",
                      answered[0], answered.size() > 1 ? answered[1] : 0.0, length, expected);
        res = s;
        return *std::max_element(answered.begin(), answered.end()) / 1000;
    }));
    if (!ok) return fail("the ruler was not placed");

    // The Measurements table's answers for the ruler (the surface each point
    // lies on, the surfaces its line passes through): worked out off the GUI
    // thread on a search tree of every triangle, "..." until then.
    auto* table = w.measurements_panel();
    if (stopped()) return 0;
    phases.push_back(phase("the ruler's surfaces in the table", [&](std::string& res) {
        const double t0 = now_ms();
        const auto row_text = [&] {
            const int row = table->row_of(w.workspace().markups().size() - 1);
            QString cells;
            for (int c = 0; row >= 0 && c < table->table()->columnCount(); ++c)
                if (const auto* item = table->table()->item(row, c); item && !item->text().isEmpty())
                    cells += (cells.isEmpty() ? "" : "; ") + item->text();
            return cells;
        };
        ok = wait_until([&] { return !table->looking_up() && !row_text().contains("..."); }, 1200000);
        const double s = (now_ms() - t0) / 1000;
        const QString cells = row_text();
        char b[64];
        std::snprintf(b, sizeof b, "shown after %.1f s: ", s);
        res = b + cells.toStdString();
        return s;
    }));
    if (!ok) return fail("the table's answers did not arrive");

    const double hwm = status_mib("VmHWM"), rss = status_mib("VmRSS");
    const std::size_t tris = w.scene().mesh(w.scene().surfaces().back()).triangles.size();
    const std::size_t verts = w.scene().mesh(w.scene().surfaces().back()).positions.size();
    std::printf("\npeak memory (VmHWM) %.0f MiB, now %.0f MiB; the surface: %zu triangles, %zu vertices; the GUI "
                "thread's context holds %s\n\n",
                hwm, rss, tris, verts, w.scene().has_gpu_data() ? "a copy of the scene" : "no copy of the scene");

    std::printf("| phase | seconds | GUI thread away, p99 / max ms | result |\n|---|---:|---:|---|\n");
    std::string out = "phase,seconds,away_p99_ms,away_max_ms,result\n";
    for (const Phase& p : phases) {
        std::printf("| %s | %.2f | %.0f / %.0f | %s |\n", p.name.c_str(), p.seconds, p.away_p99, p.away_max,
                    p.result.c_str());
        char line[512];
        std::snprintf(line, sizeof line, "%s,%.3f,%.1f,%.1f,\"%s\"\n", p.name.c_str(), p.seconds, p.away_p99,
                      p.away_max, p.result.c_str());
        out += line;
    }
    char mem[200];
    std::snprintf(mem, sizeof mem, "peak memory,%.0f,0,0,\"VmHWM MiB; GUI context scene copy: %s\"\n", hwm,
                  w.scene().has_gpu_data() ? "yes" : "no");
    out += mem;
    return bench::write_csv("gui_massive_bench", csv, out);
}
