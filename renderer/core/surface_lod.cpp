#include "renderer/core/surface_lod.hpp"

#include <chrono>

namespace iso::core {

SurfaceLod::SurfaceLod(std::shared_ptr<const Mesh> mesh) : mesh_(std::move(mesh)) {}

SurfaceLod::~SurfaceLod() {
    cancel_ = true;
    if (job_.valid()) job_.wait();
}

std::shared_ptr<const lod::ClusterLod> SurfaceLod::get() const {
    std::lock_guard lock(mutex_);
    return lod_;
}

void SurfaceLod::build() {
    try {
        auto l = std::make_shared<const lod::ClusterLod>(
            lod::build_cluster_lod(*mesh_, {}, [this](double, std::string_view) { return !cancel_.load(); }));
        std::lock_guard lock(mutex_);
        lod_ = std::move(l);
    } catch (const std::exception&) {
        // Cancelled (the surface went) or out of memory: frames draw every triangle.
    }
}

double SurfaceLod::build_now() {
    std::unique_lock lock(mutex_);
    if (lod_) return 0.0;
    if (job_.valid()) {
        lock.unlock();
        job_.wait();
        return 0.0;
    }
    job_ = std::async(std::launch::deferred, [this] { build(); });
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    job_.wait();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void SurfaceLod::build_in_background() {
    std::lock_guard lock(mutex_);
    if (lod_ || job_.valid()) return;
    job_ = std::async(std::launch::async, [this] { build(); });
}

} // namespace iso::core
