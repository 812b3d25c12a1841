#include "app/gui/raytraced_refiner.hpp"

#include <QMetaObject>
#include <QObject>

#include <algorithm>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "renderer/core/raytraced_ao.hpp"
#include "renderer/core/scene.hpp"

namespace iso::gui {

// The surfaces' copies and, once a job built it, their BVH (shared by the
// jobs while the surfaces stay the same).
struct RaytracedRefiner::Geometry {
    std::vector<Mesh> meshes;
    std::once_flag built;
    std::unique_ptr<AoReference> tracer;
};

struct RaytracedRefiner::Job {
    std::uint64_t id = 0;
    std::shared_ptr<Geometry> geometry;
    Camera camera;
    int width = 1, height = 1;
    ProgressiveAoOptions options;
    QObject* receiver = nullptr; // outlives the job: the refiner waits for it first
    std::function<void(const RaytracedBatch&)> on_batch;
    std::atomic<bool> cancel{false}, finished{false};
};

RaytracedRefiner::RaytracedRefiner(QObject* receiver, std::function<void(const RaytracedBatch&)> on_batch)
    : receiver_(receiver), on_batch_(std::move(on_batch)) {}

RaytracedRefiner::~RaytracedRefiner() {
    cancel();
    reap(true);
}

void RaytracedRefiner::ensure(const std::vector<double>& key, const core::Scene& scene, const Camera& cam, int width,
                              int height, const FrameLook& look) {
    if (running_ && key == key_) return;
    cancel();
    reap(false);
    key_ = key;
    // The key's tail (after the 18 view and look numbers) is the geometry's.
    const std::vector<double> geometry_key(key.begin() + std::min<std::size_t>(18, key.size()), key.end());
    if (!geometry_ || geometry_key != geometry_key_) {
        geometry_ = std::make_shared<Geometry>();
        for (const Mesh* m : core::raytraced_ao_meshes(scene, look)) {
            Mesh copy; // what the BVH needs: positions and triangles
            copy.positions = m->positions;
            copy.triangles = m->triangles;
            geometry_->meshes.push_back(std::move(copy));
        }
        geometry_key_ = geometry_key;
    }
    auto job = std::make_shared<Job>();
    job->id = ++job_;
    job->geometry = geometry_;
    job->camera = cam;
    job->width = width;
    job->height = height;
    job->options = core::raytraced_ao_options(look);
    // Leave a core to the GUI thread (its frames and events).
    job->options.threads = std::max(1, int(std::thread::hardware_concurrency()) - 1);
    job->receiver = receiver_.data();
    job->on_batch = on_batch_;
    running_ = job;
    workers_.emplace_back(job, std::thread(&RaytracedRefiner::run, job));
}

void RaytracedRefiner::cancel() {
    if (running_) running_->cancel = true;
    running_.reset();
    key_.clear();
}

// Joins the workers that have finished (all: waits for every one).
void RaytracedRefiner::reap(bool all) {
    for (auto it = workers_.begin(); it != workers_.end();) {
        if (all || it->first->finished) {
            it->second.join();
            it = workers_.erase(it);
        } else {
            ++it;
        }
    }
}

void RaytracedRefiner::run(std::shared_ptr<Job> job) {
#ifdef __linux__
    // Below the GUI thread: its frames and events come first.
    setpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid)), 10);
#endif
    struct Finished {
        Job& j;
        ~Finished() { j.finished = true; }
    } finished{*job};
    try {
        Geometry& g = *job->geometry;
        std::call_once(g.built, [&] {
            std::vector<const Mesh*> ptrs;
            for (const Mesh& m : g.meshes) ptrs.push_back(&m);
            g.tracer = std::make_unique<AoReference>(ptrs);
        });
        if (job->cancel) return;
        ProgressiveAo ao(*g.tracer, job->camera, job->width, job->height, job->options);
        // At least one batch is handed over (a view of nothing is done at once).
        while (!job->cancel) {
            if (!ao.done()) ao.add_batch(&job->cancel);
            if (job->cancel) return;
            RaytracedBatch b{job->id, std::make_shared<const Image>(ao.image()), ao.stats()};
            QMetaObject::invokeMethod(
                job->receiver, [on_batch = job->on_batch, b] { on_batch(b); }, Qt::QueuedConnection);
            if (b.stats.done) return;
        }
    } catch (const std::exception&) {
        // An Embree failure leaves the view with its cone AO: nothing to hand over.
    }
}

} // namespace iso::gui
