// The 3D view's frames (AO accumulation, anti-aliasing, DSRAA, and the
// frames of a drag) drawn on a thread of their own (docs/gui.md, "Frames
// off the GUI thread"): its own headless GL context and renderer draw a
// snapshot of the scene (core::SceneSnapshot: the meshes shared, not
// copied), read the image back, convert it to the screen's pixel format
// and hand it to the GUI thread, which only paints it. The thread runs
// below the GUI thread's priority (so do the software rasterizer's threads
// it starts) and starts no still frame while the user's input is recent (a
// drag's own frames excepted).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <QImage>

#include "renderer/core/scene.hpp"
#include "renderer/frame/annotations.hpp"
#include "renderer/frame/frame.hpp"

class QObject;

namespace iso::gui {

// What to draw: the frames of one view, accumulated until done.
struct StillRequest {
    std::uint64_t id = 0; // increasing: a frame answers the request it was drawn for
    core::SceneSnapshot scene;
    Camera camera;
    RenderOptions opt; // annotations and ao_image are taken from the two below
    std::shared_ptr<const Annotations> annotations;
    std::shared_ptr<const Image> ao_image;
    int ao_frames = 0; // cone AO frames to accumulate (0: the AO is done in one frame)
    int aa_frames = 1; // frames the anti-aliasing averages
    // A frame the user is waiting for while the camera moves (a drag's):
    // never held back by input (hold_for), drawn once.
    bool interactive = false;
};

// One frame, as the GUI thread receives it.
struct StillFrame {
    std::uint64_t request = 0;
    std::shared_ptr<const Image> image; // 8-bit RGBA, rows top-down
    // The same picture in the raster engine's own format (screen_image),
    // converted on the frame thread: the GUI thread paints it as it is.
    QImage picture;
    int ao_frames = 0, aa_frames = 0;
    bool last = false;        // the request's frames are all drawn: the picture stopped changing
    bool interactive = false; // drawn for a drag (StillRequest::interactive)
    std::vector<LabelBox> labels;
    // The volume's ray casting in this frame.
    VolumeStats volume;
    double ms = 0;              // render and read-back time of this frame
    std::string error;          // the thread could not draw (no context, a rendering error): no image
    std::string gl_renderer;    // the thread's GL renderer and version
    std::size_t gl_objects = 0; // GL objects its renderer has made so far
};

// A pick asked of the thread: one frame of the view with the pick riding on
// it (RenderOptions::pick set, no image), drawn for its lists. The thread
// keeps the scene on its GPU, so the GUI thread's context holds none of it.
struct PickJob {
    core::SceneSnapshot scene;
    Camera camera;
    RenderOptions opt;
    // A hover's pick: a newer replaceable job replaces it while it waits
    // (only the pointer's latest position is worth a frame).
    bool replaceable = false;
};

// What the thread returns: the frame's lists (resolved against the scene by
// the caller, core::resolve_pick) or why there are none.
struct PickFrame {
    PickList list;
    double ms = 0; // the frame's render time
    std::string error;
    bool replaced = false; // a newer replaceable job took its place: not drawn
};

// An 8-bit RGBA frame (rows top-down, opaque) as the window's raster
// engine paints it fastest (QImage::Format_RGB32, 0xffRRGGBB): a copy.
QImage screen_image(const Image& image);

class StillFrames {
public:
    // `on_frame` runs on `receiver`'s (the GUI) thread, through its event
    // queue; the receiver must outlive this object.
    StillFrames(QObject* receiver, std::function<void(const StillFrame&)> on_frame);
    ~StillFrames(); // the frame being drawn finishes, then the thread ends
    StillFrames(const StillFrames&) = delete;
    StillFrames& operator=(const StillFrames&) = delete;

    // Replaces what was asked before (a frame being drawn for it finishes,
    // and arrives with the older id).
    void request(StillRequest r);
    // Draws `job`'s pick frame before any waiting still frame (input never
    // holds it back) and hands the result to `done` on the frame thread
    // (the caller posts it on, or wakes a waiting thread). Every job gets
    // its `done` once: drawn, replaced, or with an error.
    void pick(PickJob job, std::function<void(PickFrame)> done);
    // Input: no frame starts within `ms` of now (called on every input event: cheap).
    void hold_for(int ms);
    // The input that held the frames back is over (the view's own drag ended).
    void release_hold() {
        hold_until_ns_.store(0, std::memory_order_relaxed);
        wake_.notify_all();
    }
    // Frames that waited for the input to settle before they started.
    int held() const { return held_; }

private:
    void run();
    bool wait_for_work(std::unique_lock<std::mutex>& lock);
    StillFrame draw(core::SnapshotRenderer& renderer, const StillRequest& r, int& frames_left);
    StillFrame draw_plain(core::SnapshotRenderer& renderer, const StillRequest& r);
    struct Pick {
        PickJob job;
        std::function<void(PickFrame)> done;
    };
    void draw_picks(core::SnapshotRenderer* renderer, const std::string& failed, std::unique_lock<std::mutex>& lock);
    void post(StillFrame f);

    QObject* receiver_; // outlives this object: its owner waits for the thread first
    std::function<void(const StillFrame&)> on_frame_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::optional<StillRequest> pending_; // guarded by mutex_
    std::deque<Pick> picks_;              // guarded by mutex_, first come first drawn
    std::uint64_t done_ = 0;              // the last request drawn to the end
    bool stop_ = false;
    std::atomic<std::int64_t> hold_until_ns_{0}; // steady clock
    std::atomic<int> held_{0};
    std::thread thread_;
};

} // namespace iso::gui
