#include "renderer/core/raytraced_ao.hpp"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "renderer/core/scene.hpp"

namespace iso::core {

std::vector<const Mesh*> raytraced_ao_meshes(const Scene& scene, const FrameLook& look) {
    std::vector<const Mesh*> meshes;
    for (const SurfaceId id : scene.surfaces()) {
        const auto& info = scene.info(id);
        if (info.visible && (!look.transparency || info.opacity >= 1.0f)) meshes.push_back(&scene.mesh(id));
    }
    return meshes;
}

ProgressiveAoOptions raytraced_ao_options(const FrameLook& look) {
    ProgressiveAoOptions o;
    o.radius_mm = look.cone.radius_mm;
    o.target_se = look.ao_error;
    o.max_rays = look.ao_rays;
    o.min_rays = std::min(64, look.ao_rays);
    o.batch_rays = std::min(32, look.ao_rays);
    return o;
}

namespace {

// The stop rule's outcome, kept with a cached image.
std::string stats_text(const ProgressiveAoStats& s) {
    std::ostringstream o;
    o.precision(17);
    o << s.pixels << ' ' << s.pixels_done << ' ' << s.capped << ' ' << s.batches << ' ' << s.rays << ' ' << s.rays_min
      << ' ' << s.rays_max << ' ' << s.se_max << ' ' << s.se_quantile << ' ' << s.done;
    return o.str();
}

bool parse_stats(const std::string& text, ProgressiveAoStats& s) {
    std::istringstream in(text);
    in >> s.pixels >> s.pixels_done >> s.capped >> s.batches >> s.rays >> s.rays_min >> s.rays_max >> s.se_max >>
        s.se_quantile >> s.done;
    return !in.fail();
}

} // namespace

RaytracedAo raytraced_ao(const Scene& scene, const Camera& cam, int width, int height, const FrameLook& look,
                         const std::string& scene_key, const std::string& cache_dir, const ProgressFn& progress) {
    const ProgressiveAoOptions opt = raytraced_ao_options(look);
    RaytracedAo out;
    out.target_se = opt.target_se;
    out.max_rays = opt.max_rays;
    std::ostringstream key;
    key.precision(17);
    key << kRaytracedAoVersion << "\n"
        << scene_key << "\n"
        << width << "x" << height << "\n"
        << "transparency " << look.transparency << "\n"
        << opt.radius_mm << "\n"
        << opt.max_rays << " " << opt.min_rays << " " << opt.batch_rays << " " << opt.target_se;
    const auto file = cache_dir.empty()
                          ? std::filesystem::path()
                          : std::filesystem::path(cache_dir) / "ao" / (sha256_of_string(key.str()) + ".exr");
    std::error_code ec;
    if (!file.empty() && std::filesystem::exists(file, ec)) {
        try {
            ImageMetadata m;
            Image img = load_image(file.string(), &m);
            if (img.is_float && img.channels == 1 && img.width == width && img.height == height &&
                parse_stats(m.text["isoscope:ao_stats"], out.stats)) {
                out.image = std::move(img);
                out.cache_hit = true;
                return out;
            }
        } catch (const Error&) {
            // A damaged cache entry is recomputed and replaced below.
        }
    }
    const AoReference tracer(raytraced_ao_meshes(scene, look));
    ProgressiveAo ao(tracer, cam, width, height, opt);
    ao.run(progress);
    out.image = ao.image();
    out.stats = ao.stats();
    if (!file.empty()) {
        std::filesystem::create_directories(file.parent_path(), ec);
        try {
            ImageMetadata m;
            m.text["isoscope:cache_key"] = key.str();
            m.text["isoscope:ao_stats"] = stats_text(out.stats);
            save_image(out.image, file.string(), m);
        } catch (const Error&) {
            // An unwritable cache only costs time.
        }
    }
    return out;
}

} // namespace iso::core
