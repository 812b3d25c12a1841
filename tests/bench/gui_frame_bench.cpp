// Frame times of the desktop app's 3D view while rotating
// ("Interaction stays responsive", docs/gui.md): the main window opens
// datasets/headsq.nhdr, adds the skin (iso 500) and the bone (1150), and the
// 3D view turns about its target in N steps; each frame is timed from the
// camera change (Viewer::set_camera, which calls update()) to the end of
// the paint that shows it (Viewer::frames() counts it), i.e. what a user
// dragging the mouse waits for. Four
// cases: ambient occlusion on/off x skin translucent (opacity 0.3) or opaque,
// at the view's size in the window. Each rotation frame is the first frame
// of a new camera (AO accumulation restarts on every change: the look's ao_frames is
// 1 here so no extra still frame slips between two steps). The frames are
// drawn on the GUI thread (ViewerOptions::still_thread off): what a frame
// costs; gui_latency_bench measures the frame thread's drag. The cases take
// turns in three blocks each, so a shared machine's changing load reaches
// them alike.
//
//   xvfb-run -a -s '-screen 0 1600x1200x24' build/tests/bench/gui_frame_bench [--steps 90] [--csv docs/gui_frames.csv]
//            [--input VOLUME | --mesh FILE]
// With --mesh, the window opens a mesh file instead (its one surface is the
// "skin" of the cases) and the rotation starts once the surface's levels of
// detail are built (docs/lod.md; a massive surface: the 1024^3 phantom's).
//
// Prints a markdown table; writes the CSV (one row per case).
#include <QApplication>
#include <QEventLoop>
#include <QSurfaceFormat>
#include <QTimer>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "app/gui/main_window.hpp"
#include "gui_bench_util.hpp"
#include "app/gui/viewer.hpp"
#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "renderer/core/scene.hpp"

using namespace iso;
using bench::now_ms;
using bench::quantile;
using bench::wait_until;

namespace {

// One frame: the camera turned by `degrees`, timed to the paint that shows it. Negative: timed out.
double timed_frame(gui::Viewer& v, double degrees) {
    const int before = v.frames();
    Camera cam = v.camera();
    cam.orbit(degrees, 0.0);
    const double t0 = now_ms();
    v.set_camera(cam);
    while (v.frames() == before && now_ms() - t0 < 30000)
        QCoreApplication::processEvents(QEventLoop::WaitForMoreEvents, 50);
    return v.frames() != before ? now_ms() - t0 : -1.0;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int fail(const std::string& why) { return bench::fail("gui_frame_bench", why); }

} // namespace

int main(int argc, char** argv) {
    int steps = 90;
    std::string csv = std::string(ISOSCOPE_SOURCE_DIR) + "/docs/gui_frames.csv";
    std::string input = std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr", mesh;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--steps" && i + 1 < argc)
            steps = std::max(8, std::atoi(argv[++i]));
        else if (a == "--csv" && i + 1 < argc)
            csv = argv[++i];
        else if (a == "--input" && i + 1 < argc)
            input = argv[++i];
        else if (a == "--mesh" && i + 1 < argc)
            mesh = argv[++i];
        else {
            std::printf(
                "usage: gui_frame_bench [--steps N] [--csv FILE] [--input VOLUME | --mesh FILE]  (under xvfb-run or a "
                "display)\n");
            return a == "--help" ? 0 : 2;
        }
    }
    bench::set_gl_format();
    int qargc = 1;
    char* qargv[] = {argv[0], nullptr};
    QApplication app(qargc, qargv);
    QApplication::setOrganizationName("isoscope-bench");
    QApplication::setApplicationName("gui_frame_bench");

    gui::MainWindow w; // its default size, as a user first sees it
    if (const std::string why = mesh.empty() ? bench::open_head(w, input) : bench::open_mesh(w, mesh); !why.empty())
        return fail(why);
    const auto ids = w.scene().surfaces();
    gui::Viewer* v = w.viewer();
    if (!v || !wait_until([&] { return v->frames() > 0 || !v->error().empty(); }, 60000)) return fail("no 3D frame");
    if (!v->error().empty()) return fail(v->error());
    const double lod_t0 = now_ms();
    if (!mesh.empty()) {
        // The levels are built off the GUI thread; until then frames draw every triangle.
        timed_frame(*v, 1.0); // the first frame asks for them
        if (!wait_until([&] { return w.scene().lod_ready(ids[0]); }, 600000)) return fail("no levels of detail");
        std::printf("gui_frame_bench: levels of detail ready %.1f s after the first frame\n",
                    (now_ms() - lod_t0) / 1000.0);
    }
    const std::string renderer = v->gl_renderer().empty() ? "?" : v->gl_renderer();
    std::size_t triangles = 0;
    for (auto id : ids) triangles += w.scene().mesh(id).triangles.size();
    const QSize size = v->image_size();
    std::printf("gui_frame_bench: %s, %s (%zu triangles), 3D view %d x %d, %d steps of %.1f degrees, "
                "GL: %s\n\n",
                mesh.empty() ? input.c_str() : mesh.c_str(), mesh.empty() ? "skin 500 + bone 1150" : "one mesh",
                triangles, size.width(), size.height(), steps, 360.0 / steps, renderer.c_str());

    struct Case {
        bool ao, translucent;
        std::vector<double> ms;
    };
    std::vector<Case> cases = {{false, false, {}}, {false, true, {}}, {true, false, {}}, {true, true, {}}};
    // The cases take turns in blocks (rounds), so a change in the machine's
    // load (a shared machine) reaches every case alike.
    const int rounds = 3;
    for (int round = 0; round < rounds; ++round)
        for (auto& c : cases) {
            gui::ViewerOptions o = v->options();
            o.look.ao = c.ao ? AoMethod::Cone : AoMethod::Off;
            o.look.ao_frames = 1; // every rotation frame is a first frame; no extra still frames in between
            o.look.transparency = true;
            // Frames drawn here, on the GUI thread: with the frame thread the
            // view would blit its last picture at once and the frame would
            // arrive later (gui_latency_bench measures that way).
            o.still_thread = false;
            v->set_options(o);
            {
                core::SurfaceInfo info = w.scene().info(ids[0]);
                info.opacity = c.translucent ? 0.3f : 1.0f;
                w.workspace().set_surface_info(ids[0], info);
            }
            if (round == 0) v->set_view(PatientView::Anterior);
            for (int i = 0; i < 3; ++i) timed_frame(*v, 360.0 / steps); // warm-up after the switch (pool sizes)
            const int n = steps / rounds + (round < steps % rounds ? 1 : 0);
            for (int i = 0; i < n; ++i) {
                const double ms = timed_frame(*v, 360.0 / steps);
                if (ms < 0) return fail("a frame did not arrive within 30 s");
                c.ms.push_back(ms);
            }
            if (!v->error().empty()) return fail(v->error());
        }
    struct Row {
        bool ao, translucent;
        double median, p95, min, max;
    };
    std::vector<Row> rows;
    for (const auto& c : cases)
        rows.push_back({c.ao, c.translucent, median(c.ms), quantile(c.ms, 0.95),
                        *std::min_element(c.ms.begin(), c.ms.end()), *std::max_element(c.ms.begin(), c.ms.end())});

    std::printf("| AO | skin | frames | median ms | p95 ms | min ms | max ms | median fps |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& r : rows)
        std::printf("| %s | %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f |\n", r.ao ? "on" : "off",
                    r.translucent ? "0.3" : "opaque", steps, r.median, r.p95, r.min, r.max, 1000.0 / r.median);

    std::string out = "ao,skin_opacity,width,height,triangles,frames,median_ms,p95_ms,min_ms,max_ms,gl_renderer\n";
    for (const auto& r : rows) {
        char line[512];
        std::snprintf(line, sizeof line, "%d,%.1f,%d,%d,%zu,%d,%.3f,%.3f,%.3f,%.3f,\"%s\"\n", r.ao ? 1 : 0,
                      r.translucent ? 0.3 : 1.0, size.width(), size.height(), triangles, steps, r.median, r.p95, r.min,
                      r.max, renderer.c_str());
        out += line;
    }
    return bench::write_csv("gui_frame_bench", csv, out);
}
