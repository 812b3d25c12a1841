// The 3D view's ray-traced AO (docs/gui.md, "Ray-traced AO in the 3D
// view"): refined progressively on a worker thread while the view is still,
// each finished batch handed to the GUI thread, which only uploads it with
// its next frame. A new camera, size, look or scene cancels the job and
// starts another.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <QPointer>

#include "io/image.hpp"
#include "renderer/ao/progressive.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"

class QObject;

namespace iso::core {
class Scene;
}

namespace iso::gui {

// One batch's estimate, as the GUI thread receives it.
struct RaytracedBatch {
    std::uint64_t job = 0; // which job made it (a later job's restart makes earlier batches stale)
    std::shared_ptr<const Image> image;
    ProgressiveAoStats stats;
};

class RaytracedRefiner {
public:
    // `on_batch` runs on `receiver`'s (the GUI) thread, through its event
    // queue, after each batch of the current job.
    RaytracedRefiner(QObject* receiver, std::function<void(const RaytracedBatch&)> on_batch);
    ~RaytracedRefiner(); // cancels and waits for the workers
    RaytracedRefiner(const RaytracedRefiner&) = delete;
    RaytracedRefiner& operator=(const RaytracedRefiner&) = delete;

    // Starts refining for `key` (what the job is for: the caller's key of
    // what the AO depends on) unless the current job has it: the previous
    // job is cancelled (it stops within one image row of rays). The visible
    // opaque meshes are copied here (the worker never reads the scene);
    // the BVH is rebuilt only when they changed.
    void ensure(const std::vector<double>& key, const core::Scene& scene, const Camera& cam, int width, int height,
                const FrameLook& look);
    void cancel();
    std::uint64_t job() const { return job_; }
    const std::vector<double>& current_key() const { return key_; }

private:
    struct Geometry;
    struct Job;
    static void run(std::shared_ptr<Job> job);
    void reap(bool all);
    QPointer<QObject> receiver_;
    std::function<void(const RaytracedBatch&)> on_batch_;
    std::vector<double> key_, geometry_key_;
    std::shared_ptr<Geometry> geometry_;
    std::shared_ptr<Job> running_;
    std::uint64_t job_ = 0;
    std::vector<std::pair<std::shared_ptr<Job>, std::thread>> workers_;
};

} // namespace iso::gui
