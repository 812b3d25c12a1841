// A surface's clusters and levels of detail (docs/lod.md), built once per
// mesh and shared by every renderer that draws it (the desktop app's 3D
// view and its still-frame thread each upload it into their own context):
// built in the frame that first asks for it (the CLI), or in the background
// (the desktop app), so that no frame of an interactive view waits for it;
// frames drawn meanwhile draw every triangle.
#pragma once

#include <atomic>
#include <future>
#include <memory>
#include <mutex>

#include "io/mesh.hpp"
#include "renderer/lod/cluster_lod.hpp"

namespace iso::core {

class SurfaceLod {
public:
    explicit SurfaceLod(std::shared_ptr<const Mesh> mesh);
    ~SurfaceLod(); // cancels a build in progress and waits for it
    SurfaceLod(const SurfaceLod&) = delete;
    SurfaceLod& operator=(const SurfaceLod&) = delete;

    // The levels once built (null: not yet, or the build failed).
    std::shared_ptr<const lod::ClusterLod> get() const;
    // Builds them in this thread unless they are built (or being built:
    // then waits). Returns the seconds spent building here.
    double build_now();
    // Starts building them on a thread of its own, once.
    void build_in_background();

private:
    void build();
    std::shared_ptr<const Mesh> mesh_;
    mutable std::mutex mutex_;
    std::shared_ptr<const lod::ClusterLod> lod_;
    std::future<void> job_;
    std::atomic<bool> cancel_{false};
};

} // namespace iso::core
