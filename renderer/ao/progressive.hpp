// Ray-traced AO of a view, refined progressively (docs/ao.md, "Definition
// and ground truth" and "Progressive ray-traced AO"): for each pixel the
// primary ray from the camera through the pixel's centre is traced with
// Embree; at the triangle it hits, AO is the cosine-weighted fraction of the
// hemisphere about that triangle's geometric normal (flipped to face the
// camera) whose rays, leaving from the hit point offset along that normal,
// meet no triangle within R. 1 = unoccluded.
//
// Each pixel accumulates its unoccluded and total ray counts; add_batch()
// traces one more batch for every pixel whose estimate is not yet good
// enough, on TBB's worker threads. A pixel is done when the standard error
// of its estimate is at most the target (or it reached the ray cap); the
// image is done when every foreground pixel (or the stated quantile of them)
// is.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "io/image.hpp"
#include "io/progress.hpp"
#include "renderer/ao/reference.hpp"
#include "renderer/frame/camera.hpp"

namespace iso {

struct ProgressiveAoOptions {
    double radius_mm = 10.0; // R
    // Stop rule: a pixel is done when the standard error of its estimate is
    // at most target_se (after at least min_rays) or it has max_rays; the
    // image when a fraction `quantile` of its foreground pixels are.
    double target_se = 0.005;
    double quantile = 1.0;
    int batch_rays = 32; // rays per pixel per batch
    int min_rays = 64;
    int max_rays = 4096;
    // The rays' origin offset along the normal, times AoReference::ray_offset().
    double offset_scale = 1.0;
    // Off: every batch uses the pixel centre's hit. On: each batch traces a
    // new primary ray through a random point of the pixel, so the estimate
    // is AO averaged over the pixel's footprint (its foreground part).
    bool jitter = false;
    unsigned seed = 1;
    int threads = 0; // 0: all
};

struct ProgressiveAoStats {
    int pixels = 0;                 // foreground pixels (the centre ray hits a triangle)
    int pixels_done = 0;            // standard error at most the target, or capped
    int capped = 0;                 // of them, stopped by the ray cap above the target
    int batches = 0;                // add_batch calls that traced something
    std::uint64_t rays = 0;         // AO rays traced, all pixels
    int rays_min = 0, rays_max = 0; // per foreground pixel
    double se_max = 0;              // largest standard error of a foreground pixel
    double se_quantile = 0;         // the standard error at ProgressiveAoOptions::quantile
    bool done = false;
};

class ProgressiveAo {
public:
    // Traces the primary rays (pixel centres). The tracer must outlive this.
    ProgressiveAo(const AoReference& tracer, const Camera& cam, int width, int height, const ProgressiveAoOptions& opt);

    // One batch for every foreground pixel not yet done, in parallel; stops
    // early (leaving every pixel's counts consistent) when `cancel` becomes
    // true. Returns done().
    bool add_batch(const std::atomic<bool>* cancel = nullptr);
    bool done() const { return done_; }
    // Batches until done; `progress` after each (fraction of the pixels
    // done, stage "ray-traced AO"). Throws Cancelled when it returns false
    // or `cancel` becomes true.
    void run(const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);

    // The estimate: one float channel, rows from the top, NaN where the
    // centre ray hits nothing.
    Image image() const;
    ProgressiveAoStats stats() const;
    int width() const { return width_; }
    int height() const { return height_; }

    // Per pixel (row from the top * width + column): rays traced, the
    // estimate's standard error, the centre ray's hit point and normal
    // (flipped to face the camera) if it hit.
    int rays(std::size_t pixel) const { return pixels_[pixel].rays; }
    double standard_error(std::size_t pixel) const;
    std::optional<std::pair<glm::dvec3, glm::dvec3>> surface(std::size_t pixel) const;

    // The standard error of a binomial fraction u / n, estimated with
    // p = (u + 1) / (n + 2) so that a pixel whose rays all agree so far is not
    // taken as exact: sqrt(p (1 - p) / n).
    static double binomial_se(int unoccluded, int rays);

private:
    struct Pixel {
        glm::dvec3 point{0.0};
        glm::vec3 normal{0.0f};
        int unoccluded = 0, rays = 0;
        bool hit = false, finished = false;
    };
    void trace_pixel(int x, int y, int rays);
    void update_done();
    const AoReference& tracer_;
    Camera cam_;
    int width_, height_;
    ProgressiveAoOptions opt_;
    std::vector<Pixel> pixels_;
    int foreground_ = 0, batches_ = 0;
    std::uint64_t rays_ = 0;
    bool done_ = false;
};

} // namespace iso
