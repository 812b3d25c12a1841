// The slice views' annotations and controls (docs/gui.md "Slice views"):
// the patient letters at the edges, the scale bar, the hover probe, the
// slice slider, Fit, and the actions that wait for data. Driven in-process
// through QTest under Xvfb (CTest runs this program under xvfb-run; it skips
// without a display). Expected values come from the radiological table
// written out here, the volume's header (headsq: 64 x 64 x 93 voxels of 3.2
// x 3.2 x 1.5 mm), and the core API (core::pixel_to_lps,
// core::sample_at_pixel, core::default_plane, core::slice_range), never
// from the widgets' own text.
#include <QAction>
#include <QCoreApplication>
#include <QLabel>
#include <QMouseEvent>
#include <QSlider>
#include <QStatusBar>
#include <QTest>
#include <QToolButton>
#include <QWheelEvent>

#include <cmath>
#include <cstdio>
#include <optional>
#include <span>
#include <string>

#include <glm/geometric.hpp>

#include "app/gui/main_window.hpp"
#include "app/gui/slice_view.hpp"
#include "gui_test_util.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/slices.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/surface/analysis.hpp"

using namespace iso;
using test::button_drag;
using test::wait_until;

namespace {

constexpr core::SliceOrientation kOrientations[3] = {core::SliceOrientation::Axial, core::SliceOrientation::Coronal,
                                                     core::SliceOrientation::Sagittal};
constexpr core::SliceEdge kEdges[4] = {core::SliceEdge::Left, core::SliceEdge::Right, core::SliceEdge::Top,
                                       core::SliceEdge::Bottom};

} // namespace

// The window shown at 1400 x 1000 with headsq open (no surfaces). (Outside
// the anonymous namespace: g++ flags a test's base class in one inside a
// unity batch, -Wsubobject-linkage.)
class GuiSlices : public ::testing::Test {
protected:
    void SetUp() override {
        ISO_SKIP_WITHOUT_DISPLAY();
        app_ = test::make_app("gui_slices_test", dir_ / "config");
        window_ = std::make_unique<gui::MainWindow>();
        window_->resize(1400, 1000);
        window_->show();
        ASSERT_TRUE(QTest::qWaitForWindowExposed(window_.get()));
    }
    void open_head() {
        window_->open_path(QString::fromStdString(test::data("headsq.nhdr")));
        ASSERT_TRUE(wait_until([&] { return !window_->busy(); }, 60000)) << "the load did not finish";
        ASSERT_TRUE(window_->scene().has_volume());
        QTest::qWait(50);
    }
    gui::MainWindow& w() { return *window_; }
    gui::SliceView* view(core::SliceOrientation o) { return w().slice_view(o); }
    QSlider* slider(core::SliceOrientation o) {
        return w().findChild<QSlider*>(QString(core::slice_orientation_name(o)) + "_slider");
    }

private:
    test::TempDir dir_;
    std::unique_ptr<QApplication> app_;
    std::unique_ptr<gui::MainWindow> window_;
};

namespace {

void send_mouse(QWidget* target, QEvent::Type type, Qt::MouseButton button, Qt::MouseButtons held, QPointF at) {
    QMouseEvent e(type, at, target->mapToGlobal(at), button, held, Qt::NoModifier);
    QCoreApplication::sendEvent(target, &e);
}

void hover(QWidget* target, QPointF at) { send_mouse(target, QEvent::MouseMove, Qt::NoButton, Qt::NoButton, at); }

void wheel(QWidget* target, int notches) {
    const QPointF at(target->width() / 2.0, target->height() / 2.0);
    QWheelEvent e(at, target->mapToGlobal(at), QPoint(), QPoint(0, 120 * notches), Qt::NoButton, Qt::NoModifier,
                  Qt::NoScrollPhase, false);
    QCoreApplication::sendEvent(target, &e);
}

struct Probe {
    glm::dvec3 lps{0.0};
    double value = 0;
    long i = -1, j = -1, k = -1;
};
// "LPS (x, y, z) mm, value V, voxel (i, j, k)" (headsq has no unit: "value V").
std::optional<Probe> parse(const QString& text) {
    Probe p;
    if (std::sscanf(text.toStdString().c_str(), "LPS (%lf, %lf, %lf) mm, value %lf, voxel (%ld, %ld, %ld)", &p.lps.x,
                    &p.lps.y, &p.lps.z, &p.value, &p.i, &p.j, &p.k) != 7)
        return std::nullopt;
    return p;
}

} // namespace

// Radiological letters: the patient's right on the image's left in axial and
// coronal views, the face on the left in the sagittal view; each the core's.
TEST_F(GuiSlices, EdgeLettersAreRadiological) {
    for (auto o : kOrientations) EXPECT_TRUE(view(o)->edge_letter(core::SliceEdge::Left).isEmpty()) << "no volume";
    ASSERT_NO_FATAL_FAILURE(open_head());
    // left, right, top, bottom
    const char* want[3][4] = {{"R", "L", "A", "P"}, {"R", "L", "S", "I"}, {"A", "P", "S", "I"}};
    for (int i = 0; i < 3; ++i) {
        gui::SliceView* v = view(kOrientations[i]);
        for (int e = 0; e < 4; ++e) {
            EXPECT_EQ(v->edge_letter(kEdges[e]).toStdString(), want[i][e])
                << core::slice_orientation_name(kOrientations[i]) << " edge " << e;
            EXPECT_EQ(v->edge_letter(kEdges[e]).toStdString(), core::slice_edge_letter(*v->plane(), kEdges[e]));
        }
    }
    // The left letter is drawn: light pixels at the left edge's middle
    // (headsq's axial view is black there: air outside the head).
    gui::SliceView* axial = view(core::SliceOrientation::Axial);
    const QImage shot = axial->grab().toImage().convertToFormat(QImage::Format_RGB32);
    int light = 0;
    for (int y = shot.height() / 2 - 10; y < shot.height() / 2 + 10; ++y)
        for (int x = 2; x < 16; ++x) light += qGray(shot.pixel(x, y)) > 200;
    EXPECT_GT(light, 5) << "no letter at the axial view's left edge";
}

// The bar: a round length (1, 2 or 5 x 10^k mm) not above a fifth of the
// view at the grid's pixel size, drawn that many pixels long; it follows a zoom.
TEST_F(GuiSlices, ScaleBarIsARoundLengthOfTheGridsPixelSize) {
    ASSERT_NO_FATAL_FAILURE(open_head());
    gui::SliceView* v = view(core::SliceOrientation::Coronal);
    const auto check = [&](const char* when) {
        const core::SliceGrid& g = v->grid();
        const double mm = v->scale_bar_mm(), fifth = 0.2 * g.width * g.pixel_mm;
        const double decade = std::pow(10.0, std::floor(std::log10(mm)));
        const double m = mm / decade;
        EXPECT_TRUE(std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9) << when << ": " << mm;
        EXPECT_LE(mm, fifth * (1 + 1e-12)) << when;
        EXPECT_GT(mm, 0.4 * fifth) << when;
        EXPECT_NEAR(v->scale_bar_pixels(), mm / g.pixel_mm, 1e-9) << when;
        // Drawn: the bar's row is the bar's colour along its length (bottom right, 12 pixels in).
        const QImage shot = v->grab().toImage().convertToFormat(QImage::Format_RGB32);
        const int x1 = shot.width() - 12, x0 = int(std::ceil(x1 - mm / g.pixel_mm)), y = shot.height() - 13;
        int bar = 0;
        for (int x = x0 + 2; x <= x1 - 2; ++x) bar += qGray(shot.pixel(x, y)) > 200;
        EXPECT_GE(bar, x1 - x0 - 4) << when << ": the bar is not drawn " << mm / g.pixel_mm << " pixels long";
        return mm;
    };
    const double before = check("fitted");
    // Right drag up: magnifies, the bar gets shorter in mm.
    const QPointF c(v->width() / 2.0, v->height() / 2.0);
    button_drag(v, Qt::RightButton, c, c - QPointF(0, v->height() / 2.0));
    const double after = check("zoomed in 2x");
    EXPECT_LE(after, before);
}

// The probe: the pointer over a view writes the core's point, value and
// voxel in the view's corner; the status bar keeps the last click's text.
TEST_F(GuiSlices, HoverProbeReadsTheCoreWithoutReplacingTheClick) {
    ASSERT_NO_FATAL_FAILURE(open_head());
    gui::SliceView* v = view(core::SliceOrientation::Axial);
    const QPoint click(v->width() / 2 + 7, v->height() / 2 - 11);
    QTest::mouseClick(v, Qt::LeftButton, {}, click);
    const QString clicked = w().statusBar()->currentMessage();
    ASSERT_TRUE(parse(clicked)) << clicked.toStdString();
    const Volume& vol = w().scene().volume();
    for (const QPointF at : {QPointF(v->width() / 2.0 - 30.5, v->height() / 2.0 + 20.25), QPointF(200.0, 180.0)}) {
        hover(v, at);
        const core::SliceGrid& g = v->grid();
        const auto got = parse(v->probe_text());
        ASSERT_TRUE(got) << v->probe_text().toStdString();
        const glm::dvec2 px{at.x(), at.y()};
        const glm::dvec3 lps = core::pixel_to_lps(g, px);
        const auto s = core::sample_at_pixel(vol, g, px);
        ASSERT_TRUE(s);
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(got->lps[a], lps[a], 0.0051);
        EXPECT_NEAR(got->value, s->value, 0.0051);
        EXPECT_EQ(got->i, s->voxel[0]);
        EXPECT_EQ(got->j, s->voxel[1]);
        EXPECT_EQ(got->k, s->voxel[2]);
        // The value is the volume's at that point (sample_volume, the core's value_at).
        EXPECT_NEAR(s->value, sample_volume(vol, lps)->value, 1e-9);
        EXPECT_EQ(w().statusBar()->currentMessage(), clicked) << "the hover replaced the click's readout";
    }
    // Outside the volume: pan the head away (middle drag) and hover where the core finds nothing.
    button_drag(v, Qt::MiddleButton, QPointF(10, 10), QPointF(v->width() - 10, v->height() - 10));
    const QPointF out(20.5, 20.5);
    ASSERT_FALSE(core::sample_at_pixel(vol, v->grid(), {out.x(), out.y()})) << "the pixel should be outside";
    hover(v, out);
    EXPECT_TRUE(v->probe_text().endsWith(", outside the volume")) << v->probe_text().toStdString();
    const glm::dvec3 lps = core::pixel_to_lps(v->grid(), {out.x(), out.y()});
    glm::dvec3 printed;
    ASSERT_EQ(std::sscanf(v->probe_text().toStdString().c_str(), "LPS (%lf, %lf, %lf) mm", &printed.x, &printed.y,
                          &printed.z),
              3);
    EXPECT_NEAR(glm::length(printed - lps), 0.0, 0.009);
    // Leaving the view clears it.
    QEvent leave(QEvent::Leave);
    QCoreApplication::sendEvent(v, &leave);
    EXPECT_TRUE(v->probe_text().isEmpty());
}

// The slider: one step per slice over the volume's voxels along the normal,
// following the wheel, the keys and the crosshair, and scrolling the view.
TEST_F(GuiSlices, SliderStepsOneSliceAndFollowsThePlane) {
    for (auto o : kOrientations) EXPECT_FALSE(slider(o)->isEnabled()) << "no volume";
    ASSERT_NO_FATAL_FAILURE(open_head());
    const Volume& vol = w().scene().volume();
    const int voxels[3] = {int(vol.dims[2]), int(vol.dims[1]), int(vol.dims[0])}; // along S, P, L
    for (int i = 0; i < 3; ++i) {
        const auto o = kOrientations[i];
        QSlider* s = slider(o);
        ASSERT_NE(s, nullptr);
        EXPECT_TRUE(s->isEnabled());
        EXPECT_EQ(s->minimum(), 0);
        EXPECT_EQ(s->maximum(), voxels[i] - 1) << core::slice_orientation_name(o);
        const core::SlicePlane start = core::default_plane(vol, o);
        const core::SliceRange r = core::slice_range(vol, start);
        EXPECT_EQ(s->value(), core::slice_index(r, start.offset_mm()));
        // Wheel: one notch, one slice, one step of the plane.
        gui::SliceView* v = view(o);
        const int at = s->value();
        wheel(v, 1);
        EXPECT_EQ(s->value(), at + 1);
        EXPECT_NEAR(v->plane()->offset_mm(), start.offset_mm() + start.step_mm, 1e-9);
        QTest::keyClick(v, Qt::Key_PageDown);
        QTest::keyClick(v, Qt::Key_PageDown);
        EXPECT_EQ(s->value(), at - 1);
        EXPECT_NEAR(v->plane()->offset_mm(), start.offset_mm() - start.step_mm, 1e-9);
        // The slider scrolls the view by its steps.
        s->setValue(at + 5);
        EXPECT_NEAR(v->plane()->offset_mm(), start.offset_mm() + 5 * start.step_mm, 1e-9);
        EXPECT_EQ(core::slice_index(r, v->plane()->offset_mm()), at + 5);
        // The label shows the offset in mm.
        auto* label = w().findChild<QLabel*>(QString(core::slice_orientation_name(o)) + "_offset");
        ASSERT_NE(label, nullptr);
        EXPECT_TRUE(label->text().contains(QString("%1 mm").arg(start.offset_mm() + 5 * start.step_mm, 0, 'f', 1)))
            << label->text().toStdString();
    }
    // A click in the axial view moves the coronal and sagittal slices: their sliders follow.
    gui::SliceView* axial = view(core::SliceOrientation::Axial);
    const QPoint click(axial->width() / 2 - 40, axial->height() / 2 + 25);
    const glm::dvec3 lps = core::pixel_to_lps(axial->grid(), {double(click.x()), double(click.y())});
    QTest::mouseClick(axial, Qt::LeftButton, {}, click);
    for (int i = 1; i < 3; ++i) {
        const auto o = kOrientations[i];
        const core::SliceRange r = core::slice_range(vol, core::default_plane(vol, o));
        EXPECT_EQ(slider(o)->value(), core::slice_index(r, i == 1 ? lps.y : lps.x)) << core::slice_orientation_name(o);
    }
}

// Fit (F, a double-click, the button) undoes pan and zoom: the centre back
// on the volume's, the pixel size zoom_to_fit's, the slice kept.
TEST_F(GuiSlices, FitRecentresAfterPanAndZoom) {
    ASSERT_NO_FATAL_FAILURE(open_head());
    const Volume& vol = w().scene().volume();
    gui::SliceView* v = view(core::SliceOrientation::Sagittal);
    auto* button = w().findChild<QToolButton*>("sagittal_fit");
    ASSERT_NE(button, nullptr);
    EXPECT_FALSE(button->toolTip().isEmpty());
    wheel(v, 2);
    const double offset = v->plane()->offset_mm();
    core::SlicePlane want = core::default_plane(vol, core::SliceOrientation::Sagittal);
    core::set_offset(want, offset);
    core::zoom_to_fit(want, v->width(), v->height());
    for (const char* how : {"F", "double-click", "button"}) {
        const QPointF c(v->width() / 2.0, v->height() / 2.0);
        button_drag(v, Qt::MiddleButton, c, c + QPointF(60, -35));
        button_drag(v, Qt::RightButton, c, c - QPointF(0, 80));
        ASSERT_GT(glm::length(v->plane()->center - want.center), 1.0) << how << ": the pan did nothing";
        ASSERT_GT(std::abs(v->plane()->pixel_mm - want.pixel_mm), 1e-3) << how << ": the zoom did nothing";
        if (std::string(how) == "F") {
            QTest::keyClick(v, Qt::Key_F);
        } else if (std::string(how) == "double-click") {
            // As a window system delivers it: press, release, double-click, release.
            send_mouse(v, QEvent::MouseButtonPress, Qt::LeftButton, Qt::LeftButton, c);
            send_mouse(v, QEvent::MouseButtonRelease, Qt::LeftButton, Qt::NoButton, c);
            send_mouse(v, QEvent::MouseButtonDblClick, Qt::LeftButton, Qt::LeftButton, c);
            send_mouse(v, QEvent::MouseButtonRelease, Qt::LeftButton, Qt::NoButton, c);
        } else {
            QTest::mouseClick(button, Qt::LeftButton);
        }
        EXPECT_NEAR(glm::length(v->plane()->center - want.center), 0.0, 1e-9) << how;
        EXPECT_NEAR(v->plane()->pixel_mm, want.pixel_mm, 1e-12) << how;
        EXPECT_NEAR(v->plane()->offset_mm(), offset, 1e-9) << how << ": the slice moved";
    }
}

// What needs data is disabled, saying why, until headsq is open; what needs
// a surface until one is added.
TEST_F(GuiSlices, ActionsThatNeedDataWaitForIt) {
    const char* data[] = {"save_session", "export_image", "load_markups", "save_markups", "ruler", "angle", "point"};
    const char* volume[] = {"add_surface",      "add_iso_value", "iso_preset",    "add_smoothing",
                            "add_keep_largest", "window_preset", "window_center", "window_width"};
    const char* surface[] = {"save_surfaces", "isolate_tool", "distance_tool"};
    const auto enabled = [&](const char* name) -> std::optional<bool> {
        if (auto* a = w().findChild<QAction*>(name)) return a->isEnabled();
        if (auto* c = w().findChild<QWidget*>(name)) return c->isEnabled();
        return std::nullopt;
    };
    const auto tip = [&](const char* name) {
        if (auto* a = w().findChild<QAction*>(name)) return a->toolTip();
        return w().findChild<QWidget*>(name)->toolTip();
    };
    for (auto list : {std::span<const char* const>(data), std::span<const char* const>(volume),
                      std::span<const char* const>(surface)})
        for (const char* n : list) {
            ASSERT_TRUE(enabled(n)) << "no action or control named " << n;
            EXPECT_FALSE(*enabled(n)) << n << " is enabled with nothing open";
            EXPECT_TRUE(tip(n).contains("first")) << n << ": " << tip(n).toStdString();
        }
    ASSERT_NO_FATAL_FAILURE(open_head());
    for (const char* n : data) EXPECT_TRUE(*enabled(n)) << n;
    for (const char* n : volume) EXPECT_TRUE(*enabled(n)) << n;
    for (const char* n : surface) EXPECT_FALSE(*enabled(n)) << n << " with no surface";
    for (const char* n : data) EXPECT_FALSE(tip(n).startsWith("Open")) << n << ": " << tip(n).toStdString();
    ASSERT_NO_FATAL_FAILURE(test::add_through_panel(w(), 500));
    ASSERT_EQ(w().scene().surfaces().size(), 1u);
    for (const char* n : surface) EXPECT_TRUE(*enabled(n)) << n;
}

// Large volumes' slices come from a pool thread (SliceView::kInlineVoxels;
// 0 here sends headsq's there too): the slice shown before stays while the
// new one is on its way, and the one that comes is the core's reslice of
// the newest plane through the window, byte for byte.
TEST_F(GuiSlices, SlicesFromThePoolAreTheNewestPlanesThroughTheCore) {
    ASSERT_NO_FATAL_FAILURE(open_head());
    gui::SliceView* v = view(core::SliceOrientation::Sagittal);
    v->set_inline_voxels(0);
    const QImage before = v->image();
    const core::SliceGrid before_grid = v->image_grid();
    ASSERT_FALSE(before.isNull());
    wheel(v, 1);
    // Nothing comes back before the event loop runs: the old slice is shown.
    EXPECT_TRUE(v->slice_waiting());
    EXPECT_TRUE(v->has_image());
    EXPECT_EQ(v->image(), before);
    EXPECT_EQ(v->image_grid().corner, before_grid.corner);
    EXPECT_NE(v->grid().corner, before_grid.corner) << "the plane moved";
    // Three more steps before the first answer: the last plane's slice comes.
    for (int i = 0; i < 3; ++i) wheel(v, 1);
    ASSERT_TRUE(wait_until([&] { return !v->slice_waiting(); }, 30000));
    const core::SliceGrid& g = v->grid();
    EXPECT_EQ(v->image_grid().corner, g.corner);
    EXPECT_EQ(v->image_grid().dx, g.dx);
    EXPECT_EQ(v->image_grid().dy, g.dy);
    core::SliceImage values;
    core::reslice(w().scene().volume(), g, core::Interp::Linear, values);
    const std::vector<std::uint8_t> grey = core::apply_window(values, w().workspace().window());
    const QImage& shown = v->image();
    ASSERT_EQ(shown.width(), g.width);
    ASSERT_EQ(shown.height(), g.height);
    int differ = 0;
    for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x)
            differ += shown.constScanLine(y)[x] != grey[std::size_t(y) * std::size_t(g.width) + std::size_t(x)];
    EXPECT_EQ(differ, 0);
    EXPECT_NE(shown, before);
}
