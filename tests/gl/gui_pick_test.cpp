// Picking in the desktop app's 3D view (docs/gui.md "Pick and measure"),
// driven in-process through QTest in a real X server (CTest runs this
// program under xvfb-run; it skips without a display): a click's readout,
// hover, a click after rotating, and what a pick leaves alone. Expected
// values come from `isoscope pick` (core::pick, render_image's own frame in
// another process) and core::pick on a fresh scene, not from the window's
// own state.
#include <QElapsedTimer>
#include <QStatusBar>
#include <QMouseEvent>
#include <QTest>
#include <QWheelEvent>

#include <algorithm>
#include <cstdio>
#include <thread>

#include "app/gui/slice_view.hpp"
#include "gui_measure_util.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/scene.hpp"

using namespace iso;
using namespace iso::test;
using GuiPick = HeadWindow;

TEST_F(GuiPick, ClickShowsTheCliPickAndMovesTheCrosshair) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    const QPoint at = face_pixel(size);
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, at));
    const std::string msg = w.statusBar()->currentMessage().toStdString();
    std::printf("3D click at %d,%d: %s\n", at.x(), at.y(), msg.c_str());
    const auto shown = parse_readout(msg);
    ASSERT_TRUE(shown) << msg;
    nlohmann::json layer;
    ASSERT_NO_FATAL_FAILURE(cli_pick(size, at, layer));
    EXPECT_EQ(layer["surface"], "iso 1150") << "through the skin at 0.3 the bone is what is seen: " << layer;
    const glm::dvec3 expected = json_lps(layer);
    EXPECT_NEAR(shown->lps.x, expected.x, kPrinted);
    EXPECT_NEAR(shown->lps.y, expected.y, kPrinted);
    EXPECT_NEAR(shown->lps.z, expected.z, kPrinted);
    EXPECT_NEAR(shown->value, layer["value"].get<double>(), kPrinted);
    EXPECT_EQ(shown->surface, layer["surface"].get<std::string>());
    // ... and the slice views' crosshair moved there (each plane through the point).
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Axial)->grid().offset_mm, expected.z, 1e-6);
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Coronal)->grid().offset_mm, expected.y, 1e-6);
    EXPECT_NEAR(w.slice_view(core::SliceOrientation::Sagittal)->grid().offset_mm, expected.x, 1e-6);

    // The click's readout stays in its own field while hovering shows others.
    auto* tools = w.measure_tools();
    EXPECT_EQ(tools->click_readout().toStdString(), "Click: " + msg);
    const int before = tools->hover_picks();
    hover(viewer, QPoint(at.x() - 40, at.y() + 20));
    ASSERT_TRUE(wait_until([&] { return tools->hover_picks() > before; }, 30000)) << "no hover pick";
    EXPECT_NE(w.statusBar()->currentMessage().toStdString(), msg) << "the hover readout shows elsewhere";
    EXPECT_EQ(tools->click_readout().toStdString(), "Click: " + msg) << "hovering overwrote the click's readout";

    // A background pixel says so.
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, QPoint(3, 3)));
    EXPECT_EQ(w.statusBar()->currentMessage(), "background");
    EXPECT_EQ(tools->click_readout(), "Click: background");
}

// Throttled picks, the latest position wins.
TEST_F(GuiPick, HoverPicksAreThrottledAndFollowThePointer) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QPoint at = face_pixel(viewer->image_size());
    auto* tools = w.measure_tools();
    const int before = tools->hover_picks();
    hover(viewer, QPoint(at.x() - 30, at.y()));
    ASSERT_TRUE(wait_until([&] { return tools->hover_picks() > before; }, 30000)) << "no hover pick";
    const auto hovered = viewer->pick_at(QPointF(at.x() - 30 + 0.5, at.y() + 0.5));
    EXPECT_EQ(w.statusBar()->currentMessage(), tools->readout(hovered));
    // A burst of moves at once: one pick, for the last position.
    const int burst = tools->hover_picks();
    const QPoint last(at.x() + 20, at.y() + 25);
    QTest::qWait(2 * tools->hover_interval_ms()); // an idle pointer
    for (int k = 0; k < 10; ++k) hover(viewer, QPoint(at.x() - 20 + 4 * k, at.y() + 2 * k + 7));
    hover(viewer, last);
    QTest::qWait(3 * tools->hover_interval_ms());
    // The pick is answered by the frame thread, after the still frame it may be drawing.
    ASSERT_TRUE(wait_until([&] { return viewer->picks_waiting() == 0; }, 30000));
    EXPECT_EQ(tools->hover_picks() - burst, 1) << "hover picks are not throttled";
    EXPECT_EQ(w.statusBar()->currentMessage(), tools->readout(viewer->pick_at(QPointF(last) + QPointF(0.5, 0.5))));
    // A pointer moving for 2 s, a move every 10 ms: at most one pick per
    // interval (80 ms or more), and the readout follows.
    const int moving = tools->hover_picks();
    QElapsedTimer t;
    t.start();
    // At least 2 s; on a loaded machine (picks slow, the interval adapts
    // upwards) on until two picks came, at most 30 s (the frame thread answers after its still frame).
    for (int k = 0; t.elapsed() < 2000 || (tools->hover_picks() - moving < 2 && t.elapsed() < 30000); ++k) {
        hover(viewer, QPoint(at.x() - 40 + (k % 80), at.y() + 30));
        QTest::qWait(10);
    }
    const double seconds = t.elapsed() / 1000.0;
    const int picks = tools->hover_picks() - moving;
    std::printf("hover: %d picks in %.2f s of moving, interval now %d ms\n", picks, seconds,
                tools->hover_interval_ms());
    EXPECT_GE(picks, 2) << "the readout does not follow a moving pointer";
    EXPECT_LE(picks, int(seconds * 1000 / 80) + 1) << "hover picks are not throttled";
}

// Rotate with the mouse (left drag), then click: the readout is core::pick's
// with the view's camera (a fresh scene of the same state, on a worker
// thread: render_image has its own EGL context).
TEST_F(GuiPick, ClickAfterRotatingIsCorePickWithTheViewsCamera) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    const Camera before = viewer->camera();
    const QPoint from(size.width() / 2, size.height() / 2), to = from + QPoint(70, -25);
    // Events straight to the view (QTest::mouseMove moves the X pointer, whose events arrive later).
    const auto send = [&](QEvent::Type type, QPoint at, Qt::MouseButtons held) {
        const Qt::MouseButton button = type == QEvent::MouseMove ? Qt::NoButton : Qt::LeftButton;
        QMouseEvent e(type, QPointF(at), viewer->mapToGlobal(QPointF(at)), button, held, Qt::NoModifier);
        QCoreApplication::sendEvent(viewer, &e);
    };
    send(QEvent::MouseButtonPress, from, Qt::LeftButton);
    for (int k = 1; k <= 5; ++k) send(QEvent::MouseMove, from + (to - from) * k / 5, Qt::LeftButton);
    send(QEvent::MouseButtonRelease, to, Qt::NoButton);
    const Camera turned = viewer->camera();
    ASSERT_GT(glm::length(turned.eye - before.eye), 1.0) << "the left drag did not rotate the view";
    const int drawn = viewer->frames();
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > drawn; }, 30000));
    const QPoint px(size.width() / 2 - 14, int(size.height() * 0.47));
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, px));
    const std::string turned_msg = w.statusBar()->currentMessage().toStdString();
    std::printf("3D click after rotating, at %d,%d: %s\n", px.x(), px.y(), turned_msg.c_str());
    const auto got = parse_readout(turned_msg);
    ASSERT_TRUE(got) << turned_msg;
    core::PickResult ref;
    std::string error;
    std::thread worker([&] {
        try {
            core::Scene s;
            s.open(headsq());
            const auto ids = s.add_isosurfaces({500, 1150});
            s.info(ids[0]).opacity = 0.3f;
            core::RenderRequest req;
            req.width = size.width();
            req.height = size.height();
            req.camera = turned;
            core::PickRequest at_px;
            at_px.x = px.x();
            at_px.y = px.y();
            ref = core::pick(s, req, at_px);
        } catch (const std::exception& e) {
            error = e.what();
        }
    });
    worker.join();
    ASSERT_TRUE(error.empty()) << error;
    ASSERT_TRUE(ref.visible.has_value()) << "the pixel should see the head after the turn";
    const auto& l = ref.layers[*ref.visible];
    EXPECT_NEAR(got->lps.x, l.lps.x, kPrinted);
    EXPECT_NEAR(got->lps.y, l.lps.y, kPrinted);
    EXPECT_NEAR(got->lps.z, l.lps.z, kPrinted);
    ASSERT_TRUE(l.value.has_value());
    EXPECT_NEAR(got->value, *l.value, kPrinted);
    EXPECT_EQ(got->surface, l.name);
}

// What a pick costs in the view (docs/gui.md: the frame it rides on,
// presented, and the resolve; printed), and picks leave the view's AO
// accumulation alone: the picture stays the converged one.
TEST_F(GuiPick, PicksLeaveTheAoAccumulationAlone) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    const QSize size = viewer->image_size();
    const QPoint at = face_pixel(size);
    std::vector<double> ms;
    for (int k = 0; k < 5; ++k) ms.push_back(viewer->pick_at(QPointF(at) + QPointF(0.5, 0.5)).frame_ms);
    std::sort(ms.begin(), ms.end());
    std::printf("3D view pick at %dx%d: median %.1f ms, min %.1f, max %.1f of 5\n", size.width(), size.height(), ms[2],
                ms[0], ms[4]);
    if (viewer->options().look.ao != AoMethod::Off) {
        ASSERT_TRUE(wait_until([&] { return viewer->converged(); }, 120000)) << "the AO did not converge";
        const int ao_frames = viewer->ao_frames(), drawn = viewer->frames();
        viewer->pick_at(QPointF(at));
        viewer->update();
        ASSERT_TRUE(wait_until([&] { return viewer->frames() > drawn; }, 10000));
        EXPECT_TRUE(viewer->converged()) << "a pick changed the view's picture";
        EXPECT_EQ(viewer->ao_frames(), ao_frames) << "a pick restarted the view's AO accumulation";
    }
}

// The still-frame thread runs below the GUI thread: slice steps and clicks
// elsewhere do not hold it (its frames keep coming while the user works:
// the picture converges sooner for the same input latency,
// gui_latency_bench), but a drag elsewhere does (a window/level drag on the
// axial view: from the hold on no still frame comes until it ends); then the
// accumulation resumes and converges.
TEST_F(GuiPick, ADragElsewhereHoldsTheStillFramesBackAndSliceStepsDoNot) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    gui::SliceView* axial = w.slice_view(core::SliceOrientation::Axial);
    Camera turned = viewer->camera();
    turned.orbit(20, 0);
    viewer->set_camera(turned); // the accumulation starts again
    ASSERT_TRUE(wait_until([&] { return viewer->frames() > 0 && !viewer->converged(); }, 20000));
    QTest::qWait(50);
    const QPointF mid(axial->width() / 2.0, axial->height() / 2.0);
    // Slice steps 100 ms apart (counted, not timed): the thread's frames keep coming.
    const int before = viewer->thread_frames(), held = viewer->still_frames_held();
    for (int k = 0; k < 600 && viewer->thread_frames() == before && !viewer->converged(); ++k) {
        QWheelEvent wheel(mid, axial->mapToGlobal(mid), QPoint(), QPoint(0, k % 2 ? 120 : -120), Qt::NoButton,
                          Qt::NoModifier, Qt::NoScrollPhase, false);
        QCoreApplication::sendEvent(axial, &wheel);
        QTest::qWait(100);
    }
    EXPECT_GT(viewer->thread_frames(), before) << "slice steps held the still frames back";
    EXPECT_EQ(viewer->still_frames_held(), held);
    // A left drag on the axial view (window/level), a move every 100 ms,
    // until the still frames are held (the frame in progress finishes
    // first), then 10 more moves: none comes meanwhile.
    turned.orbit(20, 0);
    viewer->set_camera(turned);
    ASSERT_TRUE(wait_until([&] { return !viewer->converged(); }, 20000));
    const auto send = [&](QEvent::Type type, QPointF at, Qt::MouseButtons buttons) {
        QMouseEvent e(type, at, axial->mapToGlobal(at), type == QEvent::MouseMove ? Qt::NoButton : Qt::LeftButton,
                      buttons, Qt::NoModifier);
        QCoreApplication::sendEvent(axial, &e);
    };
    send(QEvent::MouseButtonPress, mid, Qt::LeftButton);
    int k = 0;
    const auto move = [&] {
        send(QEvent::MouseMove, mid + QPointF(5 + k % 20, 0), Qt::LeftButton);
        ++k;
        QTest::qWait(100);
    };
    const int held2 = viewer->still_frames_held();
    while (viewer->still_frames_held() == held2 && k < 600) move();
    ASSERT_GT(viewer->still_frames_held(), held2) << "the still frames were never held back";
    QTest::qWait(50); // a frame finished just before the hold is shown
    const int drawn = viewer->thread_frames();
    for (int n = 0; n < 10; ++n) move();
    send(QEvent::MouseButtonRelease, mid + QPointF(5, 0), Qt::NoButton);
    std::printf("held after %d drag steps; during 10 more the 3D view showed %d still frames\n", k - 10,
                viewer->thread_frames() - drawn);
    EXPECT_EQ(viewer->thread_frames() - drawn, 0) << "still frames kept coming during a drag elsewhere";
    // Quiet input: the accumulation resumes and converges.
    ASSERT_TRUE(wait_until([&] { return viewer->converged(); }, 180000)) << "the still frames did not resume";
}

// Still frames come from their own thread (ViewerOptions::still_thread, on
// by default): after a camera change the GUI thread draws one plain frame
// and then only shows the thread's frames; the converged picture is the one
// the GUI thread draws itself when asked to (the way it was drawn before),
// pixel for pixel within rounding, and right side up.
TEST_F(GuiPick, StillFramesComeFromTheirThreadAndMatchTheGuiThreads) {
    gui::MainWindow& w = window();
    // The app's count of still frames, not the fixture's 4: two converged
    // pictures are compared, and at 4 their jitter noise alone is 0.003.
    const FrameLook app = gui::ViewerOptions::interactive_look();
    fewer_still_frames(w, app.ao_frames);
    gui::Viewer* viewer = w.viewer();
    ASSERT_EQ(viewer->options().look.aa.view_frames, app.aa.view_frames);
    ASSERT_TRUE(viewer->options().still_thread);
    ASSERT_NE(viewer->options().look.ao, AoMethod::Off);
    Camera turned = viewer->camera();
    turned.orbit(25, 10);
    const int frames = viewer->frames(), thread_frames = viewer->thread_frames();
    viewer->set_camera(turned);
    ASSERT_TRUE(wait_until([&] { return viewer->converged() || !viewer->error().empty(); }, 180000));
    ASSERT_EQ(viewer->error(), "");
    const int gui_frames = (viewer->frames() - frames) - (viewer->thread_frames() - thread_frames);
    std::printf("after the turn: %d frame(s) drawn on the GUI thread, %d from the still-frame thread (last %.0f ms)\n",
                gui_frames, viewer->thread_frames() - thread_frames, viewer->last_thread_frame_ms());
    EXPECT_LE(gui_frames, 1) << "the GUI thread drew still frames";
    EXPECT_GE(viewer->thread_frames() - thread_frames, viewer->options().look.ao_frames);
    EXPECT_EQ(viewer->ao_frames(), viewer->options().look.ao_frames);
    const QImage threaded = viewer->grab().toImage().convertToFormat(QImage::Format_RGB32);

    gui::ViewerOptions o = viewer->options();
    o.still_thread = false;
    const int before = viewer->frames(), shown_from_thread = viewer->thread_frames();
    viewer->set_options(o);
    ASSERT_TRUE(wait_until(
        [&] { return (viewer->frames() > before && viewer->converged()) || !viewer->error().empty(); }, 180000));
    EXPECT_EQ(viewer->thread_frames(), shown_from_thread) << "the thread's frames were shown with it off";
    const QImage here = viewer->grab().toImage().convertToFormat(QImage::Format_RGB32);
    ASSERT_EQ(threaded.size(), here.size());
    double sum = 0;
    int worst = 0;
    for (int y = 0; y < here.height(); ++y)
        for (int x = 0; x < here.width(); ++x) {
            const QRgb a = threaded.pixel(x, y), b = here.pixel(x, y);
            for (const int d : {qRed(a) - qRed(b), qGreen(a) - qGreen(b), qBlue(a) - qBlue(b)}) {
                sum += double(d) * d;
                worst = std::max(worst, std::abs(d));
            }
        }
    const double rmse = std::sqrt(sum / (3.0 * here.width() * here.height())) / 255.0;
    std::printf("thread's picture against the GUI thread's: RMSE %.5f, largest difference %d of 255\n", rmse, worst);
    EXPECT_LT(rmse, 0.002);
    // Upside down or shifted pictures differ by far more; so does a picture without AO.
    o.still_thread = true;
    viewer->set_options(o);
}

// Frames and picks are drawn on the frame thread, which keeps the scene on
// its own GPU context: the GUI thread's context never gets a copy of the
// meshes (on a 32 M-triangle surface a second copy is over a gigabyte), and
// a click's pick is answered without the GUI thread waiting for its frame.
TEST_F(GuiPick, TheGuiContextHoldsNoCopyOfTheScene) {
    gui::MainWindow& w = window();
    gui::Viewer* viewer = w.viewer();
    ASSERT_TRUE(viewer->options().still_thread);
    ASSERT_TRUE(wait_until([&] { return viewer->converged() || !viewer->error().empty(); }, 180000));
    const QPoint at = face_pixel(viewer->image_size());
    ASSERT_NO_FATAL_FAILURE(click_3d(viewer, at));
    auto* tools = w.measure_tools();
    const int before = tools->hover_picks();
    hover(viewer, at + QPoint(9, 4));
    ASSERT_TRUE(wait_until([&] { return tools->hover_picks() > before; }, 30000)) << "no hover pick";
    const core::PickResult r = viewer->pick_at(QPointF(at) + QPointF(0.5, 0.5));
    ASSERT_TRUE(r.visible);
    EXPECT_EQ(tools->click_readout(), "Click: " + tools->readout(r)) << "the click's answer is the pick's";
    EXPECT_GT(viewer->thread_frames(), 0);
    EXPECT_FALSE(w.scene().has_gpu_data()) << "the GUI thread's context uploaded the scene";
}
