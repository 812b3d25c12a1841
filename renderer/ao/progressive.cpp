#include "renderer/ao/progressive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "io/error.hpp"
#include "renderer/ao/sequences.hpp"

namespace iso {

namespace {

using sequences::radical_inverse2;
using sequences::unit;
double radical_inverse3(std::uint32_t i) { return sequences::radical_inverse(i, 3); }

// The primary ray of image point (x, y) (pixels from the top-left): its
// direction has unit length along the view axis, so t is the eye depth.
struct PrimaryRays {
    glm::dvec3 eye, fw, right, up;
    double th, aspect;
    PrimaryRays(const Camera& cam, int w, int h)
        : eye(cam.eye), fw(cam.forward()), right(glm::normalize(glm::cross(fw, cam.up))), up(glm::cross(right, fw)),
          th(std::tan(glm::radians(cam.fov_y_degrees) * 0.5)), aspect(double(w) / h) {}
    glm::dvec3 dir(double x, double y, int w, int h) const {
        const double nx = x / w * 2.0 - 1.0, ny = 1.0 - y / h * 2.0;
        return fw + right * (nx * th * aspect) + up * (ny * th);
    }
};

} // namespace

double ProgressiveAo::binomial_se(int unoccluded, int rays) {
    if (rays <= 0) return std::numeric_limits<double>::infinity();
    const double p = (unoccluded + 1.0) / (rays + 2.0);
    return std::sqrt(p * (1.0 - p) / rays);
}

ProgressiveAo::ProgressiveAo(const AoReference& tracer, const Camera& cam, int width, int height,
                             const ProgressiveAoOptions& opt)
    : tracer_(tracer), cam_(cam), width_(width), height_(height), opt_(opt) {
    if (width < 1 || height < 1) throw Error("ray-traced AO", "the image must be at least 1 x 1 pixels");
    if (!(opt.radius_mm > 0)) throw Error("ambient occlusion radius", "must be positive");
    if (opt.batch_rays < 1 || opt.min_rays < 0 || opt.max_rays < 1)
        throw Error("ambient occlusion rays", "batch and cap must be positive");
    if (!(opt.target_se > 0)) throw Error("ambient occlusion error", "the target standard error must be positive");
    if (!(opt.quantile > 0 && opt.quantile <= 1)) throw Error("ambient occlusion error quantile", "must be in (0, 1]");
    if (!(opt.offset_scale > 0)) throw Error("ray-traced AO", "the ray offset scale must be positive");
    pixels_.resize(std::size_t(width) * height);
    const PrimaryRays pr(cam, width, height);
    tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(0, height, [&](int y) {
            for (int x = 0; x < width; ++x) {
                const glm::dvec3 d = pr.dir(x + 0.5, y + 0.5, width, height);
                const auto h = tracer_.intersect(pr.eye, d, cam.near_plane, cam.far_plane);
                if (!h.hit) continue;
                Pixel& px = pixels_[std::size_t(y) * width + x];
                px.hit = true;
                px.point = h.point;
                px.normal = glm::vec3(glm::dot(h.normal, d) > 0 ? -h.normal : h.normal);
            }
        });
    });
    for (const Pixel& px : pixels_) foreground_ += px.hit;
    update_done();
}

void ProgressiveAo::trace_pixel(int x, int y, int rays) {
    const std::size_t i = std::size_t(y) * width_ + x;
    Pixel& px = pixels_[i];
    glm::dvec3 p(px.point), n(px.normal);
    const auto seed = std::uint32_t(opt_.seed * 0x9E3779B9u + i * 0x85EBCA6Bu);
    if (opt_.jitter) { // a new point of the pixel's footprint for this batch
        const PrimaryRays pr(cam_, width_, height_);
        const auto s = seed + std::uint32_t(px.rays) * 0x27d4eb2du;
        const glm::dvec3 d = pr.dir(x + unit(s), y + unit(s ^ 0x5bd1e995u), width_, height_);
        const auto h = tracer_.intersect(pr.eye, d, cam_.near_plane, cam_.far_plane);
        if (!h.hit) return; // this batch's point is background: nothing to add
        p = h.point;
        n = glm::dot(h.normal, d) > 0 ? -h.normal : h.normal;
    }
    const glm::dvec3 origin = p + n * (tracer_.ray_offset() * opt_.offset_scale);
    const glm::dvec3 t =
        glm::normalize(std::abs(n.x) > 0.9 ? glm::cross(n, glm::dvec3(0, 1, 0)) : glm::cross(n, glm::dvec3(1, 0, 0)));
    const glm::dvec3 b = glm::cross(n, t);
    const double u0 = unit(seed), v0 = unit(seed + 1u); // Cranley-Patterson rotation per pixel
    int unoccluded = 0;
    for (int k = 0; k < rays; ++k) {
        const auto j = std::uint32_t(px.rays + k);
        double u = radical_inverse2(j) + u0, v = radical_inverse3(j) + v0;
        u -= std::floor(u);
        v -= std::floor(v);
        // Malley: a uniform point of the unit disk, lifted to the hemisphere.
        const double r = std::sqrt(u), phi = 2.0 * M_PI * v;
        const glm::dvec3 d = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1.0 - u)) * n;
        unoccluded += !tracer_.occluded(origin, d, opt_.radius_mm);
    }
    px.unoccluded += unoccluded;
    px.rays += rays;
}

bool ProgressiveAo::add_batch(const std::atomic<bool>* cancel) {
    if (done_) return true;
    std::atomic<std::uint64_t> traced{0};
    tbb::task_arena arena(opt_.threads > 0 ? opt_.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(0, height_, [&](int y) {
            if (cancel && cancel->load(std::memory_order_relaxed)) return;
            std::uint64_t row = 0;
            for (int x = 0; x < width_; ++x) {
                Pixel& px = pixels_[std::size_t(y) * width_ + x];
                if (!px.hit || px.finished) continue;
                const int n = std::min(opt_.batch_rays, opt_.max_rays - px.rays);
                const int before = px.rays;
                trace_pixel(x, y, n);
                row += std::uint64_t(px.rays - before);
            }
            traced += row;
        });
    });
    rays_ += traced;
    if (traced > 0) ++batches_;
    update_done();
    return done_;
}

double ProgressiveAo::standard_error(std::size_t i) const {
    const Pixel& px = pixels_[i];
    return px.hit ? binomial_se(px.unoccluded, px.rays) : 0.0;
}

// A pixel is finished when its standard error reached the target after
// min_rays, or it reached the cap; the image when the quantile of its
// foreground pixels are.
void ProgressiveAo::update_done() {
    int finished = 0;
    for (Pixel& px : pixels_) {
        if (!px.hit) continue;
        const bool enough = px.rays >= opt_.min_rays && binomial_se(px.unoccluded, px.rays) <= opt_.target_se;
        px.finished = enough || px.rays >= opt_.max_rays;
        finished += px.finished;
    }
    done_ = foreground_ == 0 || finished >= int(std::ceil(opt_.quantile * foreground_ - 1e-9));
}

void ProgressiveAo::run(const ProgressFn& progress, const std::atomic<bool>* cancel) {
    while (!done_) {
        add_batch(cancel);
        if (cancel && cancel->load()) throw Cancelled("ray-traced AO");
        const auto s = stats();
        report(progress, s.pixels ? double(s.pixels_done) / s.pixels : 1.0, "ray-traced AO", "ray-traced AO");
    }
}

Image ProgressiveAo::image() const {
    Image img;
    img.width = width_;
    img.height = height_;
    img.channels = 1;
    img.is_float = true;
    img.floats.assign(pixels_.size(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < pixels_.size(); ++i)
        if (pixels_[i].hit && pixels_[i].rays > 0)
            img.floats[i] = float(double(pixels_[i].unoccluded) / pixels_[i].rays);
    return img;
}

ProgressiveAoStats ProgressiveAo::stats() const {
    ProgressiveAoStats s;
    std::vector<double> se;
    s.rays_min = std::numeric_limits<int>::max();
    for (std::size_t i = 0; i < pixels_.size(); ++i) {
        const Pixel& px = pixels_[i];
        if (!px.hit) continue;
        ++s.pixels;
        s.pixels_done += px.finished;
        const double e = standard_error(i);
        s.capped += px.finished && e > opt_.target_se;
        s.rays_min = std::min(s.rays_min, px.rays);
        s.rays_max = std::max(s.rays_max, px.rays);
        se.push_back(e);
    }
    if (s.pixels == 0) s.rays_min = 0;
    s.batches = batches_;
    s.rays = rays_;
    s.done = done_;
    if (!se.empty()) {
        std::sort(se.begin(), se.end());
        s.se_max = se.back();
        const auto q = std::size_t(std::ceil(opt_.quantile * double(se.size()))) - 1;
        s.se_quantile = se[std::min(q, se.size() - 1)];
    }
    return s;
}

std::optional<std::pair<glm::dvec3, glm::dvec3>> ProgressiveAo::surface(std::size_t i) const {
    const Pixel& px = pixels_[i];
    if (!px.hit) return std::nullopt;
    return std::make_pair(px.point, glm::dvec3(px.normal));
}

} // namespace iso
