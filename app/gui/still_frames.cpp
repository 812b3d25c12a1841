#include "app/gui/still_frames.hpp"

#include <QMetaObject>
#include <QObject>

#include <algorithm>
#include <chrono>
#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "io/error.hpp"
#include "renderer/core/drag_pacing.hpp"
#include "renderer/gl/context.hpp"

namespace iso::gui {

namespace {
std::int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

// A surface this large is not drawn whole while its levels of detail are
// being built: its frames wait for them (on llvmpipe, 32 M triangles take
// 20-30 s to draw whole the first time, their levels 9 s to build, and a
// frame of the levels a second). Picks are drawn meanwhile (they use every
// triangle anyway). A build that has not given levels after kLevelsWaitNs
// (it failed: out of memory) is no longer waited for.
constexpr std::size_t kWaitForLevels = 4'000'000;
constexpr std::int64_t kLevelsWaitNs = 120'000'000'000;

// Whether a visible surface of `r` is waiting for its levels (their build started here if not yet).
bool levels_on_their_way(const StillRequest& r) {
    if (!r.opt.look.lod.enabled) return false;
    bool waiting = false;
    const std::size_t large = std::max(kWaitForLevels, r.opt.look.lod.min_triangles);
    for (const auto& s : r.scene.surfaces)
        if (s.lod && s.mesh && s.object.visible && s.mesh->triangles.size() >= large && !s.lod->get()) {
            s.lod->build_in_background();
            waiting = true;
        }
    return waiting;
}
} // namespace

QImage screen_image(const Image& image) {
    if (image.is_float || image.channels != 4 || image.width < 1 || image.height < 1 ||
        image.bytes.size() != std::size_t(image.width) * std::size_t(image.height) * 4)
        throw Error("3D view", "a frame that is not an 8-bit RGBA image of its stated size");
    // RGBX: the alpha is ignored (the frames are opaque); the conversion to
    // RGB32 is a byte swizzle per pixel.
    const QImage rgba(image.bytes.data(), image.width, image.height, image.width * 4, QImage::Format_RGBX8888);
    return rgba.convertToFormat(QImage::Format_RGB32);
}

StillFrames::StillFrames(QObject* receiver, std::function<void(const StillFrame&)> on_frame)
    : receiver_(receiver), on_frame_(std::move(on_frame)) {
    thread_ = std::thread([this] { run(); });
}

StillFrames::~StillFrames() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
}

void StillFrames::request(StillRequest r) {
    {
        std::lock_guard lock(mutex_);
        pending_ = std::move(r);
    }
    wake_.notify_all();
}

void StillFrames::pick(PickJob job, std::function<void(PickFrame)> done) {
    std::function<void(PickFrame)> replaced;
    {
        std::lock_guard lock(mutex_);
        if (job.replaceable && !picks_.empty() && picks_.back().job.replaceable) {
            replaced = std::move(picks_.back().done);
            picks_.back() = Pick{std::move(job), std::move(done)};
        } else {
            picks_.push_back(Pick{std::move(job), std::move(done)});
        }
    }
    wake_.notify_all();
    if (replaced) {
        PickFrame f;
        f.replaced = true;
        replaced(std::move(f));
    }
}

void StillFrames::hold_for(int ms) {
    const std::int64_t until = now_ns() + std::int64_t(ms) * 1000000;
    std::int64_t seen = hold_until_ns_.load(std::memory_order_relaxed);
    while (seen < until && !hold_until_ns_.compare_exchange_weak(seen, until, std::memory_order_relaxed)) {}
}

// Waits until there is a request not yet drawn to the end and the input has
// settled; false: the thread is to stop.
bool StillFrames::wait_for_work(std::unique_lock<std::mutex>& lock) {
    bool counted = false;
    for (;;) {
        wake_.wait(lock, [this] { return stop_ || !picks_.empty() || (pending_ && pending_->id != done_); });
        if (stop_) return false;
        if (!picks_.empty()) return true;       // a pick is never held back
        if (pending_->interactive) return true; // the frame a drag waits for
        const std::int64_t hold = hold_until_ns_.load(std::memory_order_relaxed) - now_ns();
        if (hold <= 0) return true;
        if (!counted) ++held_;
        counted = true;
        // Woken early by a new request or the end of the hold: look again.
        wake_.wait_for(lock, std::chrono::nanoseconds(hold));
    }
}

void StillFrames::run() {
#ifdef __linux__
    // Below the GUI thread, and so are the rasterizer threads the context
    // starts (a thread inherits its creator's nice value): the GUI thread's
    // slice steps and clicks take the processors first.
    setpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid)), 10);
#endif
    std::unique_ptr<gl::HeadlessContext> context;
    core::SnapshotRenderer renderer;
    renderer.set_background_lod(true); // shared with the 3D view's frames: built once, off both threads
    std::string failed;
    try {
        context = std::make_unique<gl::HeadlessContext>();
        context->make_current();
    } catch (const std::exception& e) {
        failed = std::string("the still-frame thread has no GL context: ") + e.what();
    }
    std::uint64_t drawing = 0;      // the request the frames are accumulating for
    bool after_drag = false;        // the last frame drawn was a drag's
    bool slow_stills = false;       // the last still frame took over core::DragPacing::kSlowStillMs
    std::int64_t waiting_since = 0; // since when frames wait for levels of detail (0: they do not)
    int frames_left = 0;
    std::unique_lock lock(mutex_);
    while (wait_for_work(lock)) {
        if (!picks_.empty()) {
            draw_picks(context ? &renderer : nullptr, failed, lock);
            continue;
        }
        StillRequest r = *pending_; // shares the meshes, annotations and AO image
        if (failed.empty() && levels_on_their_way(r)) {
            if (waiting_since == 0) waiting_since = now_ns();
            if (now_ns() - waiting_since < kLevelsWaitNs) {
                wake_.wait_for(lock, std::chrono::milliseconds(100)); // picks, a stop or new requests come first
                continue;
            }
        } else {
            waiting_since = 0;
        }
        lock.unlock();
        StillFrame f;
        if (!failed.empty()) {
            f.request = r.id;
            f.error = failed;
            f.last = true;
        } else {
            if (r.id != drawing) {
                frames_left = std::max({1, r.ao_frames, r.aa_frames});
                if (after_drag && !r.interactive && slow_stills && r.ao_frames > 0) post(draw_plain(renderer, r));
            }
            drawing = r.id;
            f = draw(renderer, r, frames_left);
            after_drag = r.interactive;
            if (!r.interactive) slow_stills = f.ms > core::DragPacing::kSlowStillMs;
        }
        lock.lock();
        if (f.last && pending_ && pending_->id == r.id) done_ = r.id;
        lock.unlock();
        post(std::move(f));
        lock.lock();
    }
    // Picks still waiting get their answer: nobody is left to draw them.
    for (Pick& p : picks_) {
        PickFrame f;
        f.error = "the 3D view is closing";
        p.done(std::move(f));
    }
    picks_.clear();
    lock.unlock();
    if (context) renderer.release(); // the context is still current on this thread
}

// Draws the waiting picks' frames, first come first drawn (the lock is
// held on entry and exit, released while drawing).
void StillFrames::draw_picks(core::SnapshotRenderer* renderer, const std::string& failed,
                             std::unique_lock<std::mutex>& lock) {
    while (!picks_.empty()) {
        Pick p = std::move(picks_.front());
        picks_.pop_front();
        lock.unlock();
        PickFrame f;
        const auto t0 = std::chrono::steady_clock::now();
        if (!renderer) {
            f.error = failed;
        } else {
            try {
                f.list = std::move(renderer->render(p.job.scene, p.job.camera, p.job.opt).pick);
            } catch (const std::exception& e) {
                f.error = e.what();
            }
        }
        f.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        p.done(std::move(f));
        lock.lock();
    }
}

// The still view's plain frame (no AO, one sample, not accumulated),
// shown while its first AO frame is drawn after a drag: on a massive
// surface that frame voxelizes the scene again for the new view (3.5-4.8 s
// for the 1024^3 phantom's 32.5 M triangles on llvmpipe) and the drag's
// last, coarse, half-size picture stayed up meanwhile.
StillFrame StillFrames::draw_plain(core::SnapshotRenderer& renderer, const StillRequest& r) {
    StillRequest plain = r;
    plain.opt.look.ao = AoMethod::Off;
    plain.opt.look.aa.samples = 1;
    plain.opt.accumulate = false;
    plain.opt.ao_image = nullptr;
    plain.ao_image = nullptr;
    plain.ao_frames = 0;
    plain.aa_frames = 1;
    int frames_left = 1;
    StillFrame f = draw(renderer, plain, frames_left);
    f.last = false; // the still frames follow
    f.ao_frames = f.aa_frames = 0;
    return f;
}

StillFrame StillFrames::draw(core::SnapshotRenderer& renderer, const StillRequest& r, int& frames_left) {
    StillFrame f;
    f.request = r.id;
    f.interactive = r.interactive;
    const auto t0 = std::chrono::steady_clock::now();
    try {
        RenderOptions opt = r.opt;
        opt.annotations = r.annotations.get();
        opt.ao_image = r.ao_image.get();
        opt.present = false;
        opt.target_framebuffer = 0;
        RenderResult res = renderer.render(r.scene, r.camera, opt);
        f.image = std::make_shared<const Image>(std::move(res.image));
        f.picture = screen_image(*f.image);
        f.ao_frames = r.ao_frames > 0 ? res.ao_frames : 0;
        f.aa_frames = res.aa_frames;
        f.labels = std::move(res.labels);
        f.volume = res.volume;
        f.gl_renderer = res.gl_renderer;
        f.gl_objects = renderer.renderer().gl_objects_created();
        // Done when the AO and the average have their frames (a restart
        // inside the renderer, such as a grown translucency pool, is counted in them).
        --frames_left;
        const bool ao_done = r.ao_frames <= 0 || f.ao_frames >= r.ao_frames;
        const bool aa_done = !opt.accumulate || f.aa_frames >= r.aa_frames;
        f.last = (ao_done && aa_done) || frames_left < -4 * std::max(r.ao_frames, r.aa_frames);
    } catch (const std::exception& e) {
        f.error = e.what();
        f.last = true;
    }
    f.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return f;
}

void StillFrames::post(StillFrame f) {
    // The callback is copied into the event: it never reaches back into this object.
    QMetaObject::invokeMethod(
        receiver_, [cb = on_frame_, f = std::move(f)] { cb(f); }, Qt::QueuedConnection);
}

} // namespace iso::gui
