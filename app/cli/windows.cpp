// `isoscope view` (a window drawing the core Scene) and `isoscope gui` (the
// desktop app): the only commands that open windows, and the only file of
// the command line that includes Qt.
#include <iostream>
#include <memory>

#include <QApplication>
#include <QIcon>
#include <QImage>
#include <QTimer>

#include "app/cli/commands.hpp"
#include "app/cli/frame_options.hpp"
#include "app/gui/main_window.hpp"
#include "app/gui/viewer.hpp"
#include "renderer/core/workspace.hpp"

namespace iso::cli {

namespace {

// The windows' icon (the pictures the desktop entry's icon theme gets, as Qt
// resources) and the desktop entry they belong to (window matching on Wayland).
void set_app_identity() {
    QIcon icon;
    for (int size : {48, 64, 128, 256}) icon.addFile(QString(":/isoscope/isoscope-%1.png").arg(size));
    QApplication::setWindowIcon(icon);
    QGuiApplication::setDesktopFileName("isoscope");
}

struct ViewArgs {
    std::string in, view = "anterior", screenshot, series, ao = "cone", volume, volume_mode = "composite";
    std::vector<double> isos;
    iso::gui::ViewerOptions opt;
    Look look;
};

int run_view(ViewArgs a, char* argv0) {
    const auto initial = iso::patient_view_from_name(a.view);
    if (!a.look.background.empty()) a.opt.look.background = hex_option("--background", a.look.background);
    a.opt.look.flat_shading = a.look.shading == "flat";
    a.opt.look.ao = iso::ao_method_from_name(a.ao);
    apply_volume_options(a.volume, a.volume_mode, a.opt.look.volume);
    iso::validate(a.opt.look); // before the long part
    auto scene = std::make_unique<iso::core::Scene>();
    open_input(*scene, a.in, a.series, a.isos, a.look, "view", a.opt.look.volume.enabled);
    // The view draws a workspace (its camera and picture key are the workspace's).
    iso::core::Workspace workspace(a.opt.look);
    workspace.reset(std::move(scene), a.in, a.series);
    int qargc = 1;
    char* qargv[] = {argv0, nullptr};
    QApplication qapp(qargc, qargv);
    set_app_identity();
    iso::gui::Viewer w(workspace, initial, a.opt);
    w.setWindowTitle(QString::fromStdString("isoscope - " + a.in));
    w.resize(800, 600);
    w.show();
    QTimer poll;
    if (!a.screenshot.empty()) {
        // Grab once the picture has converged (the first frame without AO;
        // all still frames with it), then quit.
        QObject::connect(&poll, &QTimer::timeout, [&] {
            if (!w.converged() && w.error().empty()) return;
            poll.stop();
            if (!w.error().empty()) {
                qapp.exit(1);
                return;
            }
            if (!w.grab().save(QString::fromStdString(a.screenshot))) {
                std::cerr << "isoscope: error: " << a.screenshot << ": cannot save the screenshot\n";
                qapp.exit(1);
                return;
            }
            std::cout << "view: " << w.frames() << " frames; " << w.gl_objects_since_first_frame()
                      << " GL objects created after the first -> " << a.screenshot << "\n";
            qapp.exit(0);
        });
        poll.start(50);
    }
    return qapp.exec();
}

} // namespace

RunFn add_view(CLI::App& cmd, char* argv0) {
    const auto args = std::make_shared<ViewArgs>();
    ViewArgs& a = *args;
    CLI::App* c = &cmd;
    c->add_option("input", a.in, "Volume file, DICOM folder, or mesh")->required();
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--view", a.view, "Initial view: anterior, posterior, left, right, superior or inferior");
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--screenshot", a.screenshot, "Save the first converged frame to this PNG and quit (tests)");
    c->add_option("--ao", a.ao,
                  "Ambient occlusion: cone (default), raytraced (Embree, refined while the view is still) or off; "
                  "key O toggles it")
        ->check(CLI::IsMember({"cone", "raytraced", "off"}));
    c->add_option("--ao-error", a.opt.look.ao_error,
                  "--ao raytraced: refine until every pixel's standard error is at most this (default 0.02)")
        ->check(CLI::Range(1e-4, 0.5));
    c->add_option("--ao-rays", a.opt.look.ao_rays, "--ao raytraced: the most rays per pixel (default 1024)")
        ->check(CLI::Range(1, 1 << 20));
    c->add_option("--ao-radius", a.opt.look.cone.radius_mm, "AO radius R_max in mm")->check(CLI::PositiveNumber);
    add_cone_options(c, a.opt.look.cone);
    c->add_option("--ao-frames", a.opt.look.ao_frames,
                  "Still frames accumulated with new jitter sets while nothing moves")
        ->check(CLI::Range(1, 4096));
    add_volume_options(c, a.volume, a.volume_mode);
    add_look_options(c, a.look);
    return [args, argv0] { return run_view(*args, argv0); };
}

// The desktop app (docs/gui.md); also what `isoscope` with no arguments
// starts where there is a display.
int run_gui(const std::string& in, char* argv0) {
    int qargc = 1;
    char* qargv[] = {argv0, nullptr};
    QApplication qapp(qargc, qargv);
    QApplication::setOrganizationName("isoscope");
    QApplication::setApplicationName("isoscope");
    set_app_identity();
    iso::gui::MainWindow w;
    w.show();
    // Unsaved work of a run that was killed first (ISOSCOPE_RECOVERY=restore
    // or discard answers without asking); the input when it is not restored.
    w.offer_recovery([&w, in] {
        // A session (.json: no volume or mesh format uses it) restores what it saved.
        const std::string json = ".json";
        const bool session = in.size() > json.size() && in.compare(in.size() - json.size(), json.size(), json) == 0;
        if (session)
            w.open_session(QString::fromStdString(in));
        else if (!in.empty())
            w.open_path(QString::fromStdString(in));
    });
    return qapp.exec();
}

RunFn add_gui(CLI::App& cmd, char* argv0) {
    const auto in = std::make_shared<std::string>();
    cmd.add_option("input", *in, "Volume file, DICOM folder, mesh, or session (.json) to open");
    return [in, argv0] { return run_gui(*in, argv0); };
}

} // namespace iso::cli
