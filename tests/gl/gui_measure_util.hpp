// Shared by the desktop app's pick and measurement tests (gui_pick_test.cpp,
// gui_measure_test.cpp, gui_markups_file_test.cpp): the window each starts
// from (headsq, the skin at opacity 0.3 over the bone, the camera `isoscope
// pick` uses), the status bar readout parsed, the CLI's pick of a pixel, and
// markups placed by clicks on the axial view.
#pragma once

#include <QCoreApplication>
#include <QMouseEvent>
#include <QSlider>
#include <QTableWidget>
#include <QTest>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "app/gui/main_window.hpp"
#include "app/gui/surfaces_panel.hpp"
#include "app/gui/measure_tools.hpp"
#include "app/gui/measurements_panel.hpp"
#include "app/gui/slice_view.hpp"
#include "app/gui/viewer.hpp"
#include "gui_test_util.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"

namespace iso::test {

// The readout prints 2 decimals: the printed number is within half a unit of the last digit.
constexpr double kPrinted = 0.005 + 1e-9;

struct Readout {
    glm::dvec3 lps{0.0};
    double value = 0;
    std::string surface;
};

// "LPS (x, y, z) mm, value v, surface NAME" (headsq is not CT: "value", not "HU").
inline std::optional<Readout> parse_readout(const std::string& s) {
    Readout r;
    char name[128] = {};
    if (std::sscanf(s.c_str(), "LPS (%lf, %lf, %lf) mm, value %lf, surface %127[^\n]", &r.lps.x, &r.lps.y, &r.lps.z,
                    &r.value, name) != 5)
        return std::nullopt;
    r.surface = name;
    return r;
}

inline double parse_value(const QString& text) { return std::stod(text.toStdString()); }

inline QTableWidget* panel_table(gui::MainWindow& w) { return w.measurements_panel()->table(); }

// The pointer moving over the view with no button held, delivered at once
// (QTest::mouseMove also moves the X server's pointer, whose motion events
// arrive later, spread over time).
inline void hover(QWidget* w, QPoint at) {
    QMouseEvent e(QEvent::MouseMove, QPointF(at), w->mapToGlobal(QPointF(at)), Qt::NoButton, Qt::NoButton,
                  Qt::NoModifier);
    QCoreApplication::sendEvent(w, &e);
}

inline std::string headsq() { return data("headsq.nhdr"); }

// `w` shown at 1400 x 1000 with headsq open (4 still frames:
// fewer_still_frames), the skin (500) at opacity 0.3 (through the Surfaces
// dock's slider) over the bone (1150), and the 3D view's camera the scene's
// anterior one at the image's aspect (what `isoscope pick` uses), drawn
// once. Call through ASSERT_NO_FATAL_FAILURE.
inline void open_head_with_surfaces(gui::MainWindow& w) {
    fewer_still_frames(w);
    w.resize(1400, 1000);
    w.show();
    ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
    w.open_path(QString::fromStdString(headsq()));
    ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 60000)) << "the load did not finish";
    ASSERT_TRUE(w.scene().has_volume());
    for (const double iso : {500.0, 1150.0}) {
        w.surfaces_panel()->add_surface(iso);
        ASSERT_TRUE(wait_until([&] { return !w.busy(); }, 120000)) << "the extraction did not finish";
    }
    ASSERT_EQ(w.scene().surfaces().size(), 2u);
    auto* skin_opacity = w.findChild<QWidget*>("surface_1")->findChild<QSlider*>("opacity");
    ASSERT_NE(skin_opacity, nullptr);
    skin_opacity->setValue(30);
    ASSERT_FLOAT_EQ(w.scene().info(1).opacity, 0.3f);
    gui::Viewer* viewer = w.viewer();
    ASSERT_NE(viewer, nullptr);
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > 0 || !viewer->error().empty(); }, 60000));
    ASSERT_TRUE(viewer->error().empty()) << viewer->error();
    // Set here so that a resize between the view's first frame and now cannot matter.
    const QSize size = viewer->image_size();
    viewer->set_camera(w.scene().camera(PatientView::Anterior, double(size.width()) / double(size.height())));
    const int frames = viewer->frames();
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > frames; }, 30000));
}

// A pixel of the 3D view on the face (device pixel ratio 1 under Xvfb).
inline QPoint face_pixel(QSize size) { return {size.width() / 2 + 11, int(size.height() * 0.42)}; }

// What `isoscope pick` (core::pick in another process) sees at `at` in the
// state open_head_with_surfaces makes: its visible layer's JSON.
inline void cli_pick(QSize size, QPoint at, nlohmann::json& layer) {
    const auto r = run_command(cli() + " pick " + headsq() + " --iso 500 --iso 1150 --opacity 0.3 --opacity 1 --size " +
                               std::to_string(size.width()) + "x" + std::to_string(size.height()) + " --at " +
                               std::to_string(at.x()) + "," + std::to_string(at.y()) + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_TRUE(j["visible"].is_number()) << "the pixel should see the head: " << r.out;
    layer = j["layers"][j["visible"].get<std::size_t>()];
}

inline glm::dvec3 json_lps(const nlohmann::json& layer) {
    return {layer["lps"][0].get<double>(), layer["lps"][1].get<double>(), layer["lps"][2].get<double>()};
}

// Pixels of the axial view, from its centre.
inline QPoint axial_pixel(gui::MainWindow& w, int dx, int dy) {
    auto* axial = w.slice_view(core::SliceOrientation::Axial);
    return {axial->width() / 2 + dx, axial->height() / 2 + dy};
}

// The ruler's two clicks and the angle's three (arm, vertex, arm) on the axial view.
inline std::vector<QPoint> ruler_pixels(gui::MainWindow& w) {
    return {axial_pixel(w, -60, 10), axial_pixel(w, 55, 10)};
}
inline std::vector<QPoint> angle_pixels(gui::MainWindow& w) {
    return {axial_pixel(w, -40, -50), axial_pixel(w, 0, -10), axial_pixel(w, 45, -70)};
}

// Clicks `pixels` on the axial view with `tool` on.
inline void click_on_axial(gui::MainWindow& w, gui::MeasureTools::Tool tool, const std::vector<QPoint>& pixels) {
    auto* tools = w.measure_tools();
    (tool == gui::MeasureTools::Tool::Ruler ? tools->ruler_action() : tools->angle_action())->trigger();
    ASSERT_EQ(tools->tool(), tool);
    for (const QPoint& p : pixels)
        QTest::mouseClick(w.slice_view(core::SliceOrientation::Axial), Qt::LeftButton, {}, p);
}

// The tests' fixture: an application, settings in a temporary folder, and
// the window open_head_with_surfaces makes (skips without a display).
class HeadWindow : public ::testing::Test {
protected:
    void SetUp() override {
        ISO_SKIP_WITHOUT_DISPLAY();
        app_ = make_app(::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name(), dir_ / "config");
        window_ = std::make_unique<gui::MainWindow>();
        ASSERT_NO_FATAL_FAILURE(open_head_with_surfaces(*window_));
    }
    gui::MainWindow& window() { return *window_; }
    const TempDir& dir() const { return dir_; }

private:
    TempDir dir_;
    std::unique_ptr<QApplication> app_; // before the window: it goes last
    std::unique_ptr<gui::MainWindow> window_;
};

// The LPS point of a pixel of a slice view's grid.
inline glm::dvec3 lps_of(const core::SliceGrid& grid, QPoint p) {
    return core::pixel_to_lps(grid, {double(p.x()), double(p.y())});
}

// The window's state on a scene of the test's own, on a worker thread (a
// one-off core::pick makes its own context): headsq, the skin (500) at 0.3
// over the bone (1150), seen with `camera` at `size` (the GUI tests' oracle:
// what the core says the window should show).
class HeadOracle {
public:
    HeadOracle(QSize size, const Camera& camera) : size_(size), camera_(camera) {
        run([&] {
            scene_.open(headsq());
            const auto ids = scene_.add_isosurfaces({500, 1150});
            scene_.info(ids[0]).opacity = 0.3f;
        });
    }
    // Every layer at the pixel, front to back.
    core::PickResult pick(QPoint px) {
        core::PickResult r;
        run([&] {
            core::RenderRequest req;
            req.width = size_.width();
            req.height = size_.height();
            req.camera = camera_;
            core::PickRequest at;
            at.x = px.x();
            at.y = px.y();
            at.all_layers = true;
            r = core::pick(scene_, req, at);
        });
        return r;
    }
    const core::Scene& scene() const { return scene_; }
    const std::string& error() const { return error_; }

private:
    template <class F> void run(F f) {
        std::thread worker([&] {
            try {
                f();
            } catch (const std::exception& e) {
                error_ = e.what();
            }
        });
        worker.join();
    }
    QSize size_;
    Camera camera_;
    core::Scene scene_;
    std::string error_;
};

} // namespace iso::test
