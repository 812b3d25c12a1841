// Ray-traced AO of a scene's view (docs/ao.md, "Definition and ground truth",
// "Progressive ray-traced AO"): what the core's render_image and the 3D view
// both trace, on the CPU (renderer/ao/progressive.hpp), and hand to the GL
// frame as RenderOptions::ao_image.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "io/image.hpp"
#include "io/mesh.hpp"
#include "io/progress.hpp"
#include "renderer/ao/progressive.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"

namespace iso::core {

class Scene;

// The surfaces ray-traced AO sees: the visible ones drawn opaque (opacity 1,
// or every one with look.transparency off), as the G-buffer does. They are
// the occluders and the primary rays' targets; translucent surfaces get no
// AO with this method (docs/ao.md).
std::vector<const Mesh*> raytraced_ao_meshes(const Scene& scene, const FrameLook& look);

// The tracer's options from a look: R, the target standard error
// (look.ao_error), the ray cap (look.ao_rays).
ProgressiveAoOptions raytraced_ao_options(const FrameLook& look);

// A traced (or cached) AO term and how far it got.
struct RaytracedAo {
    Image image; // one float channel, rows from the top, NaN: background
    ProgressiveAoStats stats;
    double target_se = 0;
    int max_rays = 0;
    bool cache_hit = false;
};

// The version of the definition the cache keys carry: a change to what is
// traced makes new entries.
inline constexpr const char* kRaytracedAoVersion =
    "ao-raytraced v2 (Embree primary ray per pixel centre, geometric normal facing the camera, Malley over rotated "
    "Halton 2,3, seed 1, per-pixel standard-error stop with p=(u+1)/(n+2))";

// The AO term of `cam`'s width x height view of the scene, traced until the
// stop rule holds (progress: stage "ray-traced AO"; throws Cancelled), from
// the cache folder `cache_dir` (empty: none) when the same `scene_key`
// (inputs, surfaces, camera), size and settings were traced before.
RaytracedAo raytraced_ao(const Scene& scene, const Camera& cam, int width, int height, const FrameLook& look,
                         const std::string& scene_key, const std::string& cache_dir, const ProgressFn& progress);

} // namespace iso::core
