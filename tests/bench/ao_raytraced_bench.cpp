// Ray-traced AO (docs/ao.md, "Definition and ground truth", "Progressive
// ray-traced AO"): on the bundled head CT (skin 500, bone 1150) and the
// thin-vessel phantom (iso 150),
//  1. the stop rule: rays, time and error against a fixed high-count image
//     for a few target standard errors;
//  2. the ray offset: x10 and x0.1 the default against the image's noise;
//  3. the gap to a shading-normal definition (the interpolated vertex
//     normal at the same hit point), against the noise.
//
//   ao_raytraced_bench [--size N] [--rays N] [--truth N]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/ao/progressive.hpp"
#include "renderer/core/scene.hpp"
#include "tests/bench/bench_util.hpp"
#include "tests/support/thin_phantom.hpp"

using namespace iso;

namespace {

struct Case {
    std::string name;
    core::Scene scene;
    Camera cam;
    std::vector<const Mesh*> meshes;
};

void load(Case& c, const std::string& path, std::vector<double> isos, PatientView view) {
    c.scene.open(path);
    c.scene.add_isosurfaces(std::move(isos));
    for (const auto id : c.scene.surfaces()) c.meshes.push_back(&c.scene.mesh(id));
    c.cam = c.scene.camera(view, 1.0);
}

struct Diff {
    double rmse = 0, bias = 0;
    std::size_t n = 0;
};
Diff diff(const Image& a, const Image& b) {
    Diff d;
    for (std::size_t i = 0; i < a.floats.size(); ++i)
        if (std::isfinite(a.floats[i]) && std::isfinite(b.floats[i])) {
            const double e = double(a.floats[i]) - b.floats[i];
            d.rmse += e * e;
            d.bias += e;
            ++d.n;
        }
    if (d.n) {
        d.rmse = std::sqrt(d.rmse / d.n);
        d.bias /= d.n;
    }
    return d;
}

ProgressiveAoOptions fixed(int rays, unsigned seed = 1, double offset = 1) {
    ProgressiveAoOptions o;
    o.min_rays = o.max_rays = o.batch_rays = rays;
    o.target_se = 1e-9;
    o.seed = seed;
    o.offset_scale = offset;
    return o;
}

Image trace(const AoReference& t, const Camera& cam, int size, const ProgressiveAoOptions& o) {
    ProgressiveAo ao(t, cam, size, size, o);
    ao.run();
    return ao.image();
}

// AO about the interpolated vertex normal (flipped to the camera's side)
// at the same hit points as the geometric definition, rays leaving along it.
Image shading_normal_image(const AoReference& t, const Case& c, int size, int rays, unsigned seed) {
    Image img;
    img.width = img.height = size;
    img.channels = 1;
    img.is_float = true;
    img.floats.assign(std::size_t(size) * size, NAN);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const Ray r = c.cam.pixel_ray(x + 0.5, y + 0.5, size, size);
            const auto h = t.intersect(r.origin, r.dir, 0.0, 1e9);
            if (!h.hit) continue;
            const Mesh& m = *c.meshes[h.mesh];
            if (m.normals.empty()) continue;
            const auto& tri = m.triangles[h.triangle];
            glm::dvec3 n = (1 - h.u - h.v) * glm::dvec3(m.normals[tri[0]]) + h.u * glm::dvec3(m.normals[tri[1]]) +
                           h.v * glm::dvec3(m.normals[tri[2]]);
            if (!(glm::length(n) > 0)) continue;
            n = glm::normalize(n);
            if (glm::dot(h.normal, r.dir) > 0 ? glm::dot(n, h.normal) > 0 : glm::dot(n, h.normal) < 0) n = -n;
            const std::size_t i = std::size_t(y) * size + x;
            img.floats[i] = float(t.at(h.point, n, {.radius_mm = 10, .rays = rays, .seed = seed}, unsigned(i)));
        }
    return img;
}

void stop_rule(const AoReference& t, const Case& c, int size, int truth_rays) {
    const Image truth = trace(t, c.cam, size, fixed(truth_rays, 7));
    for (const double target : {0.02, 0.01, 0.005}) {
        ProgressiveAoOptions o;
        o.target_se = target;
        o.max_rays = 4096;
        const double t0 = bench::now_s();
        ProgressiveAo ao(t, c.cam, size, size, o);
        ao.run();
        const double secs = bench::now_s() - t0;
        const auto s = ao.stats();
        const Diff d = diff(ao.image(), truth);
        std::printf("| %s | %.3f | %.1f | %d | %.4f | %d | %.2f | %.4f | %.4f |\n", c.name.c_str(), target,
                    double(s.rays) / s.pixels, s.rays_max, s.se_max, s.capped, secs, d.rmse, d.bias);
    }
}

void offsets_and_normals(const AoReference& t, const Case& c, int size, int rays) {
    const Image base = trace(t, c.cam, size, fixed(rays, 1)), other = trace(t, c.cam, size, fixed(rays, 2));
    const Diff noise = diff(base, other);
    const Diff x10 = diff(trace(t, c.cam, size, fixed(rays, 1, 10)), base);
    const Diff x01 = diff(trace(t, c.cam, size, fixed(rays, 1, 0.1)), base);
    const Image sn1 = shading_normal_image(t, c, size, rays, 1);
    const Diff gap = diff(sn1, base), sn_noise = diff(sn1, shading_normal_image(t, c, size, rays, 2));
    std::printf("| %s | %.4g | %.4f | %.4f | %.4f | %.4f | %.4f (%+.4f) | %.4f |\n", c.name.c_str(), t.ray_offset(),
                noise.rmse, x10.rmse, x01.rmse, sn_noise.rmse, gap.rmse, gap.bias,
                std::sqrt(std::max(0.0, gap.rmse * gap.rmse -
                                            0.5 * (noise.rmse * noise.rmse + sn_noise.rmse * sn_noise.rmse))));
}

} // namespace

int main(int argc, char** argv) {
    int size = 128, rays = 1024, truth = 8192;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--size")) size = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--rays")) rays = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--truth")) truth = std::atoi(argv[i + 1]);
    }
    const std::string data = ISOSCOPE_DATA_DIR;
    const auto thin = (std::filesystem::temp_directory_path() / "isoscope_thin_phantom.nhdr").string();
    bench::write_thin_phantom(thin);
    std::vector<std::unique_ptr<Case>> cases;
    auto add = [&](const char* name, const std::string& path, std::vector<double> isos, PatientView v) {
        cases.push_back(std::make_unique<Case>());
        cases.back()->name = name;
        load(*cases.back(), path, std::move(isos), v);
    };
    add("skin 500", data + "/headsq.nhdr", {500}, PatientView::Left);
    add("bone 1150", data + "/headsq.nhdr", {1150}, PatientView::Left);
    add("thin 150", thin, {150}, PatientView::Anterior);
    std::printf("%dx%d, R = 10 mm, %u threads, Embree on the CPU\n\n", size, size, std::thread::hardware_concurrency());
    std::printf("Stop rule (cap 4096 rays), against %d fixed rays:\n\n", truth);
    std::printf("| scene | target SE | mean rays | max rays | max SE | capped | s | RMSE | bias |\n"
                "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& c : cases) stop_rule(AoReference(c->meshes), *c, size, truth);
    std::printf("\nRay offset and the shading-normal definition, %d rays, RMSE:\n\n", rays);
    std::printf("| scene | offset mm | noise (2 seeds) | x10 offset | x0.1 offset | shading noise | gap geometric vs "
                "shading (bias) | gap less noise |\n|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& c : cases) offsets_and_normals(AoReference(c->meshes), *c, size, rays);
    return 0;
}
