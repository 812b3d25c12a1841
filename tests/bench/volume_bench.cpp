// Volume rendering benchmark (docs/volume_bench.md): our GPU ray casting
// (composite; pre-integrated and sampled, flat and lit) against the CPU
// reference march of the stated model (renderer/volume/reference.hpp,
// double precision, a fine step; lit: the GPU's gradient and lights) and VTK
// 9.1's vtkGPUVolumeRayCastMapper (volume_peer under xvfb-run) on the same
// volume, transfer function, camera and image size, in the same run.
//
// Per case: the references (flat and lit, step --ref-step voxels, TBB over
// rows) and their times; ours at each step (voxels of the smallest
// spacing): pre-integrated with and without empty-space skipping, sampled,
// and both lit, frames alternated across them, each timed as a
// frame drawn into an offscreen framebuffer and finished (glFinish), warm-up
// frames dropped, the median of --reps; the samples taken and skipped; the
// image with skipping against the one without (max difference, which should
// be 0); the error of every image against the reference (RMSE, p99 and max
// over all pixels and over the volume's pixels, sRGB units 0..1); 36 frames
// of a rotation at the moving step; VTK at the same steps (in mm) and its
// rotation. Prints a table per case, the fastest frame of each at equal
// error (volume-pixel RMSE <= 0.003), and writes volume_bench.csv and a
// time-vs-error plot.
//
//   volume_bench [--out DIR] [--size N] [--reps N] [--cases headsq,cta,ct512] [--steps 0.25,0.5,1,2,4]
//                [--ref-step 0.05] [--rotate 36] [--budget SECONDS] [--zoom 1.4]
//                [--no-ref-check] [--quick] [--no-vtk] [--peer PATH]
// --budget caps the timed frames of one setting (default 15 s; never fewer
// than 3 frames): the large volume's fine steps take seconds per frame here.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "bench_util.hpp"
#include "image_error.hpp"
#include "io/color.hpp"
#include "io/error.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/volume/reference.hpp"
#include "volume_phantoms.hpp"

using namespace iso;

namespace {

struct Args {
    std::string out = "bench-results", peer = ISOSCOPE_VOLUME_PEER;
    int size = 384, reps = 10, rotate = 36;
    std::vector<std::string> cases{"headsq", "cta", "ct512"};
    std::vector<double> steps{0.25, 0.5, 1.0, 2.0, 4.0};
    double ref_step = 0.05;
    double zoom = 1.4;    // the camera moved closer than the fitted view by this factor
    double budget_s = 15; // per setting's timed frames, at most (at least 3 frames)
    bool vtk = true, quick = false;
    bool ref_check = true; // the reference again at twice its step: how far from converged it is
};

struct Case {
    std::string name, description, tf_name;
    Volume volume;
    TransferFunction tf;
};

// A transfer function for the bundled head CT (its own units, not HU: skin
// about 500, bone about 1150): faint skin and soft tissue, opaque bone.
const char* kHeadsqTf = "450:0:#a0522d,600:0.015:#e0a080,1000:0.015:#e8c0a0,1150:0.5:#f4ecd8,4000:0.8:#ffffff";

Case make_case(const std::string& name, bool quick) {
    Case c;
    c.name = name;
    if (name == "headsq") {
        c.volume = core::open_volume(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr");
        c.tf_name = "custom (skin faint, bone opaque)";
        c.tf = TransferFunction::parse(kHeadsqTf);
        c.description = "bundled CT headsq.nhdr, 64x64x93 int16, 3.2x3.2x1.5 mm, directions (-1,1,-1)";
    } else if (name == "cta") {
        const std::array<std::int64_t, 3> d =
            quick ? std::array<std::int64_t, 3>{128, 128, 100} : std::array<std::int64_t, 3>{256, 256, 200};
        const double sp = quick ? 1.4 : 0.7;
        c.volume = bench::cta_phantom(d, sp);
        c.tf_name = "vessels";
        c.tf = transfer_function_from("vessels");
        c.description = "CT angiogram phantom " + std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" +
                        std::to_string(d[2]) + " int16 HU, " + std::to_string(sp).substr(0, 3) + " mm";
    } else if (name == "ct512") {
        const std::array<std::int64_t, 3> d =
            quick ? std::array<std::int64_t, 3>{256, 256, 200} : std::array<std::int64_t, 3>{512, 512, 400};
        const double sp = quick ? 1.4 : 0.7;
        c.volume = bench::scale_ct(d, sp);
        c.tf_name = "bone";
        c.tf = transfer_function_from("bone");
        c.description = "CT-like volume (scale_volume.hpp) " + std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" +
                        std::to_string(d[2]) + " int16 HU, " + std::to_string(sp).substr(0, 3) + " mm";
    } else {
        throw Error("volume_bench", "unknown case '" + name + "' (headsq, cta, ct512)");
    }
    return c;
}

// The colour the GPU pass composites over: the background as the opaque
// image holds it (sRGB, 8 bits), back in linear light.
glm::dvec3 stored_background(const glm::vec3& linear) {
    glm::dvec3 b;
    for (int i = 0; i < 3; ++i) b[i] = linear_from_srgb(std::lround(srgb_from_linear(linear[i]) * 255.0) / 255.0);
    return b;
}

// The stated model marched per pixel centre (Camera::pixel_ray), flat, from
// the near plane to the far plane, over the background; RGBA8 sRGB.
Image reference_image(const Volume& v, const VolumeLook& look, const Camera& cam, int W, int H, double step_voxels,
                      const glm::vec3& background, double& ms, bool lit = false) {
    const VolumeSampler sampler(v);
    const VolumeLighting lighting = volume_lighting(sampler, look.tf, glm::dmat3(cam.view()));
    const double step_mm = step_voxels * sampler.min_spacing();
    const glm::dvec3 bg = stored_background(background);
    Image img;
    img.width = W;
    img.height = H;
    img.channels = 4;
    img.bytes.resize(std::size_t(W) * std::size_t(H) * 4);
    const double t0 = bench::now_s();
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5, W, H);
            const double cosine = glm::dot(ray.dir, cam.forward());
            const RayResult r =
                march_ray(sampler, look, Clip{}, ray.origin, ray.dir, cam.near_plane / cosine, cam.far_plane / cosine,
                          {}, step_mm, 1e-5, nullptr, lit ? &lighting : nullptr);
            const glm::dvec3 c = r.color + r.transmittance * bg;
            auto* px = &img.bytes[(std::size_t(y) * std::size_t(W) + std::size_t(x)) * 4];
            for (int i = 0; i < 3; ++i)
                px[i] = std::uint8_t(std::lround(std::clamp(srgb_from_linear(c[i]), 0.0, 1.0) * 255.0));
            px[3] = 255;
        }
    });
    ms = 1000.0 * (bench::now_s() - t0);
    return img;
}

// Largest difference of a colour channel between two images of one size, 0..255.
int max_channel_diff(const Image& a, const Image& b) {
    int m = 0;
    for (std::size_t i = 0; i < a.bytes.size(); ++i)
        if (i % 4 != 3) m = std::max(m, std::abs(int(a.bytes[i]) - int(b.bytes[i])));
    return m;
}

struct Row {
    std::string renderer, config;
    double step_vox = 0, step_mm = 0;
    double ms = 0, ms_lo = 0, ms_hi = 0; // median and p25/p75 (rotation: p95 as hi)
    double rmse = -1, p99 = -1, max_err = -1;
    double fg_rmse = -1; // over the pixels where the reference is not the background
    std::uint64_t samples = 0, skipped = 0, rays = 0;
    std::string note;
};

// The background's bytes in the images (sRGB), for telling the volume's pixels apart.
glm::ivec3 background_bytes() {
    const glm::vec3 bg = FrameLook{}.background;
    return {int(std::lround(srgb_from_linear(bg.r) * 255)), int(std::lround(srgb_from_linear(bg.g) * 255)),
            int(std::lround(srgb_from_linear(bg.b) * 255))};
}

void add_error(Row& r, const Image& img, const Image& ref) {
    const auto e = bench::compare(img, ref);
    r.rmse = e.rmse;
    r.p99 = e.p99;
    r.max_err = max_channel_diff(img, ref) / 255.0;
    const glm::ivec3 bg = background_bytes();
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < ref.bytes.size(); p += 4) {
        if (ref.bytes[p] == bg.r && ref.bytes[p + 1] == bg.g && ref.bytes[p + 2] == bg.b) continue;
        for (int c = 0; c < 3; ++c) {
            const double d = (int(img.bytes[p + std::size_t(c)]) - int(ref.bytes[p + std::size_t(c)])) / 255.0;
            sum += d * d / 3.0;
        }
        ++n;
    }
    r.fg_rmse = n ? std::sqrt(sum / double(n)) : 0.0;
}

double quantile(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

// Our renderer on one scene and camera. A timed frame is the whole
// Scene::render with the image read back (about a millisecond of a frame
// of 100+ ms here), so that the last timed frame gives the image and the
// volume's statistics; VTK's frames are timed with their read-back too.
struct Ours {
    core::Scene& scene;
    Camera cam;
    int W, H;

    RenderOptions options(const VolumeLook& vl, bool flat) const {
        RenderOptions o;
        o.width = W;
        o.height = H;
        o.look.flat_shading = flat;
        o.look.aa.samples = 1;
        o.look.aa.frames = 1;
        o.look.volume = vl;
        return o;
    }
    double timed(const Camera& c, const RenderOptions& o, RenderResult* out = nullptr) {
        const double t0 = bench::now_s();
        RenderResult r = scene.render(c, o);
        glFinish();
        const double ms = 1000.0 * (bench::now_s() - t0);
        if (out) *out = std::move(r);
        return ms;
    }
};

// Timed frames per setting: --reps, fewer (at least 3) where a frame is so
// slow that they would take more than --budget seconds.
int reps_within(const Args& a, double first_ms) {
    return std::clamp(int(a.budget_s * 1000.0 / std::max(first_ms, 1.0)), std::min(3, a.reps), a.reps);
}

// Frames of options `o` (after one warm-up frame): their times and the last one's result.
std::vector<double> frames(Ours& ours, const Args& a, const RenderOptions& o, RenderResult& last) {
    std::vector<double> ms{ours.timed(ours.cam, o, &last)};
    for (int f = 1, n = reps_within(a, ms[0]); f < n; ++f) ms.push_back(ours.timed(ours.cam, o, &last));
    return ms;
}

Row timed_row(const std::string& config, const std::vector<double>& ms, const RenderResult& r, double step) {
    Row row{"isoscope GPU", config, step, r.volume.step_mm};
    row.ms = bench::median(ms);
    row.ms_lo = quantile(ms, 0.25);
    row.ms_hi = quantile(ms, 0.75);
    row.samples = r.volume.samples;
    row.skipped = r.volume.skipped;
    row.rays = r.volume.rays;
    row.note = std::to_string(ms.size()) + " frames";
    return row;
}

// One configuration of ours at a step.
struct Config {
    std::string name;
    VolumeIntegration integration;
    bool skip, lit;
};

// Ours at each step: pre-integrated with and without empty-space skipping
// and sampled, flat, then both lit; frames of a step alternated across the
// configurations (as many rounds as --reps and --budget allow); errors of
// flat images against the flat reference, of lit ones against the lit
// reference; the skipping image against the one without. One warm-up round
// first (shaders, the texture upload); then a frame without the volume.
std::vector<Row> run_ours(Ours& ours, const Case& c, const Args& a, const Image& ref, const Image& lit_ref,
                          const std::string& out_prefix) {
    const std::vector<Config> configs{
        {"flat, preintegrated", VolumeIntegration::Preintegrated, true, false},
        {"flat, preintegrated, no skipping", VolumeIntegration::Preintegrated, false, false},
        {"flat, sampled", VolumeIntegration::Sampled, true, false},
        {"lit, preintegrated", VolumeIntegration::Preintegrated, true, true},
        {"lit, sampled", VolumeIntegration::Sampled, true, true}};
    std::vector<Row> rows;
    auto options = [&](const Config& k, double step) {
        VolumeLook vl;
        vl.enabled = true;
        vl.tf = c.tf;
        vl.step = step;
        vl.skip_empty = k.skip;
        vl.integration = k.integration;
        return ours.options(vl, !k.lit);
    };
    std::vector<RenderResult> r(configs.size());
    for (std::size_t k = 0; k < configs.size(); ++k) ours.timed(ours.cam, options(configs[k], a.steps.back()));
    for (double step : a.steps) {
        std::vector<std::vector<double>> ms(configs.size());
        for (int f = 0, n = 1; f < n; ++f) {
            double round = 0;
            for (std::size_t k = 0; k < configs.size(); ++k) {
                ms[k].push_back(ours.timed(ours.cam, options(configs[k], step), &r[k]));
                round += ms[k].back();
            }
            if (f == 0) n = reps_within(a, round);
        }
        const int diff = max_channel_diff(r[0].image, r[1].image);
        for (std::size_t k = 0; k < configs.size(); ++k) {
            Row row = timed_row(configs[k].name, ms[k], r[k], step);
            add_error(row, r[k].image, configs[k].lit ? lit_ref : ref);
            if (k == 0)
                row.note += "; vs no skipping: max diff " + std::to_string(diff) + "/255; " +
                            std::to_string(r[0].volume.empty_chunks) + " of " + std::to_string(r[0].volume.chunks) +
                            " chunks empty";
            rows.push_back(row);
        }
        for (std::size_t k : {std::size_t(0), std::size_t(2), std::size_t(3)}) {
            char name[96];
            std::snprintf(name, sizeof name, "_ours_%s_%s_step%g.png", configs[k].lit ? "lit" : "flat",
                          volume_integration_name(configs[k].integration), step);
            save_image(r[k].image, out_prefix + name);
        }
    }
    RenderOptions none = options(configs[0], 0.5);
    none.look.volume.enabled = false;
    const auto ms = frames(ours, a, none, r[1]);
    rows.push_back(timed_row("no volume (the frame's other passes)", ms, r[1], 0));
    return rows;
}

// `frames` frames of a rotation (10 degrees each about the camera's up
// through the target) at the moving step: median and p95 ms.
Row run_rotation(Ours& ours, const TransferFunction& tf, double min_spacing, int frames, bool flat) {
    VolumeLook vl;
    vl.enabled = true;
    vl.tf = tf;
    RenderOptions o = ours.options(vl, flat);
    o.moving = true;
    Camera cam = ours.cam;
    ours.timed(cam, o); // warm
    std::vector<double> ms;
    for (int f = 0; f < frames; ++f) {
        cam.orbit(10.0, 0.0);
        cam.fit_planes(ours.scene.bounds(o.look));
        ms.push_back(ours.timed(cam, o));
    }
    Row row{"isoscope GPU", flat ? "rotation, flat" : "rotation, lit", vl.moving_step, vl.moving_step * min_spacing};
    row.ms = bench::median(ms);
    row.ms_lo = quantile(ms, 0.05);
    row.ms_hi = quantile(ms, 0.95);
    row.note = std::to_string(frames) + " frames, moving step; lo/hi = p5/p95";
    return row;
}

std::string v3(const glm::dvec3& v) {
    std::ostringstream s;
    s.precision(17);
    s << v.x << "," << v.y << "," << v.z;
    return s.str();
}

// VTK's command line for the case: the volume (written raw to `raw`), its
// placement, the transfer function in linear RGB, the camera and the steps.
std::string peer_command(const Args& a, const Case& c, const Volume& v, const Camera& cam, const std::string& raw,
                         const std::string& dir, const glm::vec3& background, double min_spacing) {
    std::ofstream(raw, std::ios::binary)
        .write(reinterpret_cast<const char*>(v.bytes().data()), std::streamsize(v.bytes().size()));
    const glm::dvec3 sp = v.spacing();
    std::ostringstream cmd;
    cmd.precision(17);
    cmd << "xvfb-run -a -s '-screen 0 " << std::max(a.size + 64, 1280) << "x" << std::max(a.size + 64, 1024) << "x24' '"
        << a.peer << "' --raw '" << raw << "' --dims " << v.dims[0] << "," << v.dims[1] << "," << v.dims[2]
        << " --origin " << v3(glm::dvec3(v.index_to_lps[3])) << " --spacing " << v3(sp) << " --direction ";
    for (int r = 0; r < 3; ++r) // row r of the 3x3 direction matrix: component r of each unit axis
        for (int k = 0; k < 3; ++k) cmd << (r || k ? "," : "") << v.index_to_lps[k][r] / sp[k];
    cmd << " --tf '";
    for (std::size_t i = 0; i < c.tf.points().size(); ++i)
        cmd << (i ? ";" : "") << c.tf.points()[i].value << "," << c.tf.points()[i].opacity << ","
            << v3(c.tf.linear_color(i));
    cmd << "' --eye " << v3(cam.eye) << " --target " << v3(cam.target) << " --up " << v3(cam.up) << " --fov "
        << cam.fov_y_degrees << " --near " << cam.near_plane << " --far " << cam.far_plane << " --size " << a.size
        << "x" << a.size << " --background " << v3(glm::dvec3(background)) << " --steps ";
    for (std::size_t i = 0; i < a.steps.size(); ++i) cmd << (i ? "," : "") << a.steps[i] * min_spacing;
    cmd << " --reps " << a.reps << " --warmup 2 --rotate " << a.rotate << " --rotate-step " << 2.0 * min_spacing
        << " --out '" << dir << "' 2>'" << dir << "/vtk.log'";
    return cmd.str();
}

// VTK's rows (images against `ref`), or one row saying why it failed.
std::vector<Row> run_vtk(const Args& a, const Case& c, const Volume& v, const Camera& cam, const Image& ref,
                         const glm::vec3& background, std::string& renderer, std::string& failure) {
    const std::string dir = a.out + "/vtk_" + c.name;
    std::filesystem::create_directories(dir);
    const double min_sp = std::min({v.spacing().x, v.spacing().y, v.spacing().z});
    const std::string raw = (std::filesystem::temp_directory_path() / ("volume_bench_" + c.name + ".raw")).string();
    const std::string text = bench::capture(peer_command(a, c, v, cam, raw, dir, background, min_sp));
    std::filesystem::remove(raw);
    std::vector<Row> rows;
    std::stringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        if (line.empty() || line[0] != '{') continue;
        const auto j = nlohmann::json::parse(line);
        if (j.contains("error")) {
            failure = j.at("error").get<std::string>();
            continue;
        }
        const std::string kind = j.at("kind").get<std::string>();
        Row r{"VTK 9.1 GPU mapper", kind == "still" ? "flat" : kind == "rotate" ? "rotation" : "rotation, interactive"};
        r.step_mm = j.at("step_mm").get<double>();
        r.step_vox = r.step_mm / min_sp;
        r.ms = j.at("ms_median").get<double>();
        if (kind == "still") {
            r.ms_lo = j.at("ms_p25").get<double>();
            r.ms_hi = j.at("ms_p75").get<double>();
            add_error(r, load_image(j.at("png").get<std::string>()), ref);
            renderer = j.at("renderer").get<std::string>();
            r.note =
                std::string("direction matrix honoured: ") + (j.at("direction_honoured").get<bool>() ? "yes" : "NO");
        } else {
            r.ms_lo = j.at("ms_p5").get<double>();
            r.ms_hi = j.at("ms_p95").get<double>();
            r.note = std::to_string(j.at("frames").get<int>()) + " frames; image sample distance up to " +
                     std::to_string(j.at("image_sample_distance_max").get<double>()).substr(0, 4) + "; lo/hi = p5/p95";
        }
        rows.push_back(r);
    }
    if (rows.empty() && failure.empty()) {
        std::ifstream log(dir + "/vtk.log");
        std::stringstream err;
        err << log.rdbuf();
        failure = "no result; stdout: " + text.substr(0, 500) + "; stderr: " + err.str().substr(0, 1500);
    }
    return rows;
}

// At equal error: per renderer and configuration, the fastest frame whose
// volume-pixel RMSE is at most kEqualError, and the time the error reaches
// it (between the two steps around it: step and time interpolated
// log-log); ours against VTK's.
constexpr double kEqualError = 0.003;
struct EqualError {
    const Row* fastest = nullptr; // the fastest measured frame within the error
    double ms = -1, step = -1;    // interpolated where the error crosses kEqualError
};

EqualError equal_error(const std::vector<Row>& rows, const std::string& renderer, const std::string& config) {
    std::vector<const Row*> s;
    for (const auto& r : rows)
        if (r.renderer == renderer && r.config == config && r.fg_rmse > 0) s.push_back(&r);
    std::sort(s.begin(), s.end(), [](const Row* a, const Row* b) { return a->step_vox < b->step_vox; });
    EqualError e;
    for (const Row* r : s)
        if (r->fg_rmse <= kEqualError && (!e.fastest || r->ms < e.fastest->ms)) e.fastest = r;
    for (std::size_t i = 0; i + 1 < s.size(); ++i) {
        const Row &a = *s[i], &b = *s[i + 1];
        if (a.fg_rmse <= kEqualError && b.fg_rmse > kEqualError) {
            const double f = std::log(kEqualError / a.fg_rmse) / std::log(b.fg_rmse / a.fg_rmse);
            e.step = std::exp(std::log(a.step_vox) + f * std::log(b.step_vox / a.step_vox));
            e.ms = std::exp(std::log(a.ms) + f * std::log(b.ms / a.ms));
        }
    }
    if (e.ms < 0 && e.fastest) { // within it at every step measured: the coarsest
        e.step = e.fastest->step_vox;
        e.ms = e.fastest->ms;
    }
    return e;
}

void print_equal_error(const std::vector<Row>& rows) {
    std::printf("\nAt equal error (volume-pixel RMSE <= %.3f): the fastest frame measured within it, and the time "
                "where the error crosses it (step and time interpolated log-log between the steps around it):\n\n",
                kEqualError);
    const EqualError vtk = equal_error(rows, "VTK 9.1 GPU mapper", "flat");
    for (const char* config : {"flat, preintegrated", "flat, sampled", "lit, preintegrated", "lit, sampled"}) {
        const EqualError e = equal_error(rows, "isoscope GPU", config);
        if (!e.fastest) {
            std::printf("- isoscope %s: no step reaches it\n", config);
            continue;
        }
        std::printf("- isoscope %s: %.1f ms at step %g (RMSE %.4f); crossing at step %.2f, %.1f ms", config,
                    e.fastest->ms, e.fastest->step_vox, e.fastest->fg_rmse, e.step, e.ms);
        if (vtk.fastest && std::string(config).rfind("flat", 0) == 0)
            std::printf("; %.2fx VTK's time (measured), %.2fx (crossing)", e.fastest->ms / vtk.fastest->ms,
                        e.ms / vtk.ms);
        std::printf("\n");
    }
    if (vtk.fastest)
        std::printf("- VTK flat: %.1f ms at step %g (RMSE %.4f); crossing at step %.2f, %.1f ms\n", vtk.fastest->ms,
                    vtk.fastest->step_vox, vtk.fastest->fg_rmse, vtk.step, vtk.ms);
    else
        std::printf("- VTK flat: no step reaches it (or VTK did not run)\n");
}

void print_rows(const std::string& title, const std::vector<Row>& rows) {
    std::printf("\n### %s\n\n", title.c_str());
    std::printf("| renderer | config | step vox | step mm | ms median | ms lo-hi | RMSE | volume px RMSE | p99 | max | "
                "samples | skipped | notes |\n|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|\n");
    for (const auto& r : rows) {
        char err[128] = "- | - | - | -";
        if (r.rmse >= 0)
            std::snprintf(err, sizeof err, "%.4f | %.4f | %.4f | %.4f", r.rmse, r.fg_rmse, r.p99, r.max_err);
        std::printf("| %s | %s | %.3g | %.3g | %.1f | %.1f-%.1f | %s | %llu | %llu | %s |\n", r.renderer.c_str(),
                    r.config.c_str(), r.step_vox, r.step_mm, r.ms, r.ms_lo, r.ms_hi, err, (unsigned long long)r.samples,
                    (unsigned long long)r.skipped, r.note.c_str());
    }
    std::fflush(stdout);
}

bool parse(int argc, char** argv, Args& a) {
    for (int i = 1; i < argc; ++i) {
        const std::string s = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("volume_bench", s + " needs a value");
            return argv[++i];
        };
        if (s == "--out")
            a.out = next();
        else if (s == "--size")
            a.size = std::stoi(next());
        else if (s == "--reps")
            a.reps = std::max(1, std::stoi(next()));
        else if (s == "--rotate")
            a.rotate = std::max(1, std::stoi(next()));
        else if (s == "--cases")
            a.cases = bench::split_list(next());
        else if (s == "--steps") {
            a.steps.clear();
            for (const auto& t : bench::split_list(next())) a.steps.push_back(std::stod(t));
        } else if (s == "--ref-step")
            a.ref_step = std::stod(next());
        else if (s == "--budget")
            a.budget_s = std::stod(next());
        else if (s == "--zoom")
            a.zoom = std::stod(next());
        else if (s == "--no-ref-check")
            a.ref_check = false;
        else if (s == "--peer")
            a.peer = next();
        else if (s == "--no-vtk")
            a.vtk = false;
        else if (s == "--quick") {
            a.quick = true;
            a.size = 256;
            a.reps = 3;
            a.rotate = 12;
            a.ref_step = 0.1;
        } else
            return false;
    }
    return true;
}

} // namespace

namespace {

// One case end to end: the reference, ours, VTK; the table printed.
std::vector<Row> run_case(const Args& a, const std::string& name, std::string& description) {
    std::fprintf(stderr, "[volume_bench] %s: making the volume\n", name.c_str());
    Case c = make_case(name, a.quick);
    description = c.description + ", transfer function " + c.tf_name;
    core::Scene scene;
    scene.set_volume(std::move(c.volume), c.name);
    const Volume& v = scene.volume();
    FrameLook look;
    look.volume.enabled = true;
    look.volume.tf = c.tf;
    // The patient view fitted to the volume's box, moved closer so that the
    // volume, not the background, fills most of the image.
    Camera cam = scene.camera(PatientView::Anterior, 1.0, look);
    cam.zoom(a.zoom);
    cam.fit_planes(scene.bounds(look));
    const int S = a.size;
    std::fprintf(stderr, "[volume_bench] %s: reference (step %g voxel)\n", name.c_str(), a.ref_step);
    double ref_ms = 0;
    const Image ref = reference_image(v, look.volume, cam, S, S, a.ref_step, look.background, ref_ms);
    const std::string prefix = a.out + "/volume_" + name;
    save_image(ref, prefix + "_reference.png");
    std::fprintf(stderr, "[volume_bench] %s: lit reference (step %g voxel)\n", name.c_str(), a.ref_step);
    double lit_ms = 0;
    const Image lit_ref = reference_image(v, look.volume, cam, S, S, a.ref_step, look.background, lit_ms, true);
    save_image(lit_ref, prefix + "_reference_lit.png");
    Row ref_row{"CPU reference (march_ray)", "flat, double", a.ref_step,
                a.ref_step * std::min({v.spacing().x, v.spacing().y, v.spacing().z})};
    ref_row.ms = ref_ms;
    ref_row.note = "2 threads (TBB); one frame";
    Row lit_row = ref_row;
    lit_row.config = "lit (the GPU's gradient and lights), double";
    lit_row.ms = lit_ms;
    std::vector<Row> rows{ref_row, lit_row};
    if (a.ref_check) {
        double ms = 0;
        const Image coarse = reference_image(v, look.volume, cam, S, S, 2 * a.ref_step, look.background, ms);
        Row check{"CPU reference (march_ray)", "flat, twice the step, vs the reference", 2 * a.ref_step,
                  2 * ref_row.step_mm};
        check.ms = ms;
        add_error(check, coarse, ref);
        check.note = "the reference's own convergence";
        rows.push_back(check);
    }
    std::fprintf(stderr, "[volume_bench] %s: isoscope\n", name.c_str());
    Ours ours{scene, cam, S, S};
    for (auto& r : run_ours(ours, c, a, ref, lit_ref, prefix)) rows.push_back(r);
    const double min_spacing = VolumeSampler(v).min_spacing();
    rows.push_back(run_rotation(ours, c.tf, min_spacing, a.rotate, false));
    scene.release_gpu();
    std::string renderer = "-", failure;
    if (a.vtk) {
        std::fprintf(stderr, "[volume_bench] %s: VTK\n", name.c_str());
        for (auto& r : run_vtk(a, c, v, cam, ref, look.background, renderer, failure)) rows.push_back(r);
        if (!failure.empty()) {
            Row f{"VTK 9.1 GPU mapper", "FAILED"};
            f.note = failure;
            rows.push_back(f);
        }
    }
    char title[512];
    std::snprintf(title, sizeof title, "%s: %dx%d, VTK's GL renderer: %s", description.c_str(), S, S, renderer.c_str());
    print_rows(title, rows);
    print_equal_error(rows);
    return rows;
}

void write_plot(const Args& a, const std::vector<std::pair<std::string, std::vector<Row>>>& all) {
    const std::string gp_file = a.out + "/volume_bench.gp";
    std::ofstream gp(gp_file);
    gp << "set terminal pngcairo size " << 480 * int(all.size()) << ",560\nset output '" << a.out
       << "/volume_bench.png'\nset multiplot layout 1," << all.size()
       << "\nset logscale xy\nset xlabel 'ms per frame (llvmpipe, 2 cores)'\nset ylabel 'volume-pixel RMSE vs "
          "reference (sRGB)'\n"
       << "set key below font ',9'\nset grid\n";
    const std::vector<std::pair<std::string, std::string>> series{{"isoscope GPU", "flat, preintegrated"},
                                                                  {"isoscope GPU", "flat, sampled"},
                                                                  {"isoscope GPU", "lit, preintegrated"},
                                                                  {"VTK 9.1 GPU mapper", "flat"}};
    for (const auto& [name, rows] : all) {
        gp << "set title '" << name << " (labels: step in voxels)'\nplot";
        for (std::size_t i = 0; i < series.size(); ++i)
            gp << (i ? "," : "") << " '-' using 1:2 with linespoints pt 7 title '" << series[i].first << ", "
               << series[i].second << "', '-' using 1:2:3 with labels offset 1,0.6 notitle";
        gp << "\n";
        for (const auto& s : series)
            for (int pass = 0; pass < 2; ++pass) {
                for (const auto& r : rows)
                    if (r.renderer == s.first && r.config == s.second && r.fg_rmse >= 0)
                        gp << r.ms << " " << std::max(r.fg_rmse, 1e-4) << " " << r.step_vox << "\n";
                gp << "e\n";
            }
    }
    gp << "unset multiplot\n";
    gp.close();
    if (std::system(("gnuplot '" + gp_file + "' 2>/dev/null").c_str()) == 0)
        std::printf("\nwrote %s/volume_bench.png\n", a.out.c_str());
}

} // namespace

int main(int argc, char** argv) {
    Args a;
    try {
        if (!parse(argc, argv, a)) {
            std::cerr << "usage: volume_bench [--out DIR] [--size N] [--reps N] [--cases headsq,cta,ct512] "
                         "[--steps 0.25,0.5,1,2,4] [--ref-step 0.05] [--rotate 36] [--budget S] [--zoom F] "
                         "[--no-ref-check] [--quick] [--no-vtk] "
                         "[--peer PATH]\n";
            return 2;
        }
        std::filesystem::create_directories(a.out);
        gl::HeadlessContext ctx;
        ctx.make_current();
        std::printf("volume_bench at %dx%d, %d timed frames per setting (median), GL renderer %s, reference step %g "
                    "voxel\n",
                    a.size, a.size, a.reps, ctx.info().renderer.c_str(), a.ref_step);
        std::ofstream csv(a.out + "/volume_bench.csv");
        csv << "case,renderer,config,step_vox,step_mm,ms_median,ms_lo,ms_hi,rmse,fg_rmse,p99,max,samples,skipped,rays,"
               "note\n";
        std::vector<std::pair<std::string, std::vector<Row>>> all;
        for (const auto& name : a.cases) {
            std::string description;
            const auto rows = run_case(a, name, description);
            for (const auto& r : rows) {
                std::string note = r.note;
                std::replace(note.begin(), note.end(), '"', '\'');
                csv << name << ",\"" << r.renderer << "\",\"" << r.config << "\"," << r.step_vox << "," << r.step_mm
                    << "," << r.ms << "," << r.ms_lo << "," << r.ms_hi << "," << r.rmse << "," << r.fg_rmse << ","
                    << r.p99 << "," << r.max_err << "," << r.samples << "," << r.skipped << "," << r.rays << ",\""
                    << note << "\"\n";
            }
            csv.flush();
            all.emplace_back(name, rows);
        }
        write_plot(a, all);
    } catch (const std::exception& e) {
        std::cerr << "volume_bench: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
