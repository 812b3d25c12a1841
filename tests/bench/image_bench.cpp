// The whole image measured: each scene rendered in the live view's
// configuration (one frame: without anti-aliasing, with DSRAA) and in the
// export's (core::render_converged: DSRAA and jittered frames until the
// image stops changing), compared with a reference image of the same scene:
// exact coverage by 64 sub-samples per pixel (a stratified 8 x 8 grid of
// jittered frames, one sample each), exact compositing of the translucent
// layers (VOIT with a pool that holds every fragment) and, in the series
// with AO, ray-traced AO (standard error at most 0.0025 per pixel). Prints time and error (RMSE and p99 over all
// pixels and over edge pixels, sRGB units 0..1) per configuration, writes
// OUT/image_bench.csv, the images and a time-vs-error plot per scene
// (gnuplot, OUT/image_time_error.png).
//
//   image_bench [--out DIR] [--size WxH] [--reps N] [--scenes head,bunny,thin,dense] [--quick]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "aa_peer.hpp"
#include "bench_scenes.hpp"
#include "bench_util.hpp"
#include "image_error.hpp"
#include "io/image.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/raytraced_ao.hpp"
#include "renderer/gl/context.hpp"

using namespace iso;
namespace fs = std::filesystem;

namespace {

struct Args {
    std::string out = "bench-results/image";
    int width = 640, height = 480, reps = 3;
    std::vector<std::string> scenes{"head", "bunny", "thin", "dense"};
    bool quick = false;
};

// A text field of the CSV: its commas become semicolons (the configuration
// names have commas; the plot and spreadsheets split on every comma).
std::string csv_text(std::string s) {
    std::replace(s.begin(), s.end(), ',', ';');
    return s;
}

struct Config {
    std::string name;
    bool export_rule = false; // core::render_converged, else one frame
    int samples = 1;
    AoMethod ao = AoMethod::Off; // in the series with AO
};

core::RenderRequest request(const Args& a, const bench::BenchScene& s, AoMethod ao) {
    core::RenderRequest req;
    req.width = a.width;
    req.height = a.height;
    req.view = s.view;
    req.annotations = false;
    req.look.ao = ao;
    req.look.oit_memory_mib = 2048; // exact compositing: no fragment merged
    return req;
}

// One configuration's image and its time (median of reps, ms), the GL
// context current, the frame loop as the live view or an export runs it.
Image run(bench::BenchScene& s, const core::RenderRequest& base, const Config& c, int reps, double& ms, int& frames) {
    core::RenderRequest req = base;
    if (base.look.ao != AoMethod::Off) req.look.ao = c.ao;
    req.look.aa.samples = c.samples;
    if (!c.export_rule) req.look.aa.frames = 1;
    if (!c.export_rule) req.look.ao_frames = 1;
    const RenderOptions ro = core::frame_options(req);
    Image img;
    std::vector<double> times;
    for (int r = 0; r <= reps; ++r) { // the first run warms up (shaders, uploads)
        const double t0 = bench::now_s();
        // The export as render_image makes it: ray-traced AO traced once (no cache), then the frames.
        const Camera cam = core::frame_camera(s.scene, req);
        RenderOptions frame = ro;
        std::optional<core::RaytracedAo> ao;
        if (req.look.ao == AoMethod::Raytraced) {
            ao = core::raytraced_ao(s.scene, cam, req.width, req.height, req.look, "", "", {});
            frame.ao_image = &ao->image;
        }
        core::Convergence conv;
        img = core::render_converged(s.scene, cam, frame, req, conv).image;
        frames = conv.frames;
        if (r > 0) times.push_back((bench::now_s() - t0) * 1e3);
    }
    ms = bench::median(times);
    return img;
}

// The reference: 64 frames on a stratified 8 x 8 grid of sub-pixel offsets,
// one sample each, averaged by the renderer in linear light.
Image reference(bench::BenchScene& s, const core::RenderRequest& base, double& ms) {
    core::RenderRequest req = base;
    req.look.aa.samples = 1;
    RenderOptions ro = core::frame_options(req);
    ro.accumulate = true;
    const Camera cam = core::frame_camera(s.scene, req);
    const double t0 = bench::now_s();
    // Ray-traced AO with a standard error of at most 0.0025 per pixel (its noise well below 0.005).
    std::optional<core::RaytracedAo> ao;
    if (req.look.ao == AoMethod::Raytraced) {
        req.look.ao_error = 0.0025;
        req.look.ao_rays = 16384;
        ao = core::raytraced_ao(s.scene, cam, req.width, req.height, req.look, "", "", {});
        ro.ao_image = &ao->image;
    }
    RenderResult r;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            ro.restart_accumulation = i == 0 && j == 0;
            ro.jitter = glm::vec2((i + 0.5f) / 8.0f - 0.5f, (j + 0.5f) / 8.0f - 0.5f);
            r = s.scene.render(cam, ro);
        }
    ms = (bench::now_s() - t0) * 1e3;
    if (r.aa_frames != 64)
        throw Error("image_bench", "the reference averaged " + std::to_string(r.aa_frames) + " frames");
    return r.image;
}

// VTK's anti-aliasing on the same meshes, camera and size (no AO: VTK's
// SSAO is ao_bench's peer), each against VTK's own 8 x 8 supersampled
// reference, since its shading is not ours.
void peers(bench::BenchScene& s, const Args& a, std::ofstream& csv) {
    std::vector<bench::PeerMesh> meshes;
    bool translucent = false;
    for (const auto id : s.scene.surfaces()) {
        const auto& info = s.scene.info(id);
        if (!info.visible) continue;
        meshes.push_back({&s.scene.mesh(id), info.color, info.opacity});
        translucent |= info.opacity < 1.0f;
    }
    bench::AaPeerOptions opt;
    // VTK 9.1 drops translucent surfaces from multisampled depth peeling: its weighted-blended OIT then.
    opt.depth_peeling = !translucent;
    opt.reference_factor = s.triangles > 4000000 ? 4 : 8;
    const Camera cam = core::frame_camera(s.scene, request(a, s, AoMethod::Off));
    std::vector<std::string> failed;
    const auto images = bench::render_vtk_aa(meshes, cam, a.width, a.height, a.reps, opt, &failed);
    for (const auto& f : failed) std::cout << "<!-- VTK failed: " << f << " -->\n";
    const Image* ref = nullptr;
    for (const auto& p : images)
        if (p.name == "reference") ref = &p.image;
    if (!ref) return;
    save_image(*ref, a.out + "/" + s.name + "_vtk_reference.png", {});
    for (const auto& p : images) {
        if (p.name == "reference") continue;
        save_image(p.image, a.out + "/" + s.name + "_vtk_" + p.name + ".png", {});
        const bench::ImageError e = bench::compare(p.image, *ref);
        const std::string name =
            "VTK " + p.name + (p.samples_asked > 1 ? " (got " + std::to_string(p.samples_window) + ")" : "");
        std::printf("| %s | VTK, no AO | %s | 1 | %.1f | %.4f | %.4f | %.4f | %.4f |\n", s.name.c_str(), name.c_str(),
                    p.ms, e.rmse, e.p99, e.edge_rmse, e.edge_p99);
        csv << s.name << ",VTK no AO," << name << ",1," << p.ms << "," << e.rmse << "," << e.p99 << "," << e.edge_rmse
            << "," << e.edge_p99 << "," << s.triangles << "\n";
    }
}

void write_plot(const std::string& csv, const std::string& png) {
    const std::string gp = fs::path(png).replace_extension(".gp").string();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1200,800 font ',10'\nset output '" << png << "'\n"
      << "set datafile separator ','\nset logscale x\nset xlabel 'time per image (ms, log)'\n"
      << "set ylabel 'edge-pixel RMSE vs reference (sRGB)'\nset key outside right\nset grid\n"
      << "set title 'Whole image: time against error per configuration (each scene its own colour)'\n"
      << "plot '" << csv << "' skip 1 using 5:8:(stringcolumn(1).' '.stringcolumn(3)) with labels point pt 7 "
      << "offset char 0.5,0.5 font ',7' notitle\n";
    g.close();
    if (std::system(("gnuplot " + gp + " 2>/dev/null").c_str()) == 0) std::cout << "wrote " << png << "\n";
}

} // namespace

int main(int argc, char** argv) try {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("image_bench", arg + " needs a value");
            return argv[++i];
        };
        if (arg == "--out")
            a.out = next();
        else if (arg == "--size") {
            if (!bench::parse_size(next(), a.width, a.height)) throw Error("image_bench", "--size WxH");
        } else if (arg == "--reps")
            a.reps = std::max(1, std::stoi(next()));
        else if (arg == "--quick") {
            a.quick = true;
            a.reps = 1;
        } else if (arg == "--scenes") {
            a.scenes = bench::split_list(next());
        } else {
            std::cerr << "usage: image_bench [--out DIR] [--size WxH] [--reps N] [--scenes head,bunny,thin,dense] "
                         "[--quick]\n";
            return 2;
        }
    }
    fs::create_directories(a.out);
    const std::string csv_path = a.out + "/image_bench.csv";
    std::ofstream csv(csv_path);
    csv << "scene,series,config,frames,ms,rmse,p99,edge_rmse,edge_p99,triangles\n";
    std::cout << "| scene | series | configuration | frames | ms | RMSE | p99 | edge RMSE | edge p99 |\n"
              << "|---|---|---|---:|---:|---:|---:|---:|---:|\n";
    // The live view's frames have cone AO; exports cone or ray-traced AO.
    const std::vector<Config> configs = {
        {"live: 1 sample", false, 1, AoMethod::Cone},
        {"live: DSRAA 4", false, 4, AoMethod::Cone},
        {"export: 1 sample + frames", true, 1, AoMethod::Cone},
        {"export: DSRAA 4 + frames (default), cone AO", true, 4, AoMethod::Cone},
        {"export: DSRAA 4 + frames (default), ray-traced AO", true, 4, AoMethod::Raytraced}};
    const gl::ScopedCurrent context;
    for (const auto& name : a.scenes) {
        bench::BenchScene s;
        s.name = name;
        make_scene(s, ISOSCOPE_DATA_DIR, a.quick);
        std::cout << "<!-- " << name << ": " << s.triangles << " triangles -->\n";
        for (const AoMethod ao : {AoMethod::Off, AoMethod::Raytraced}) {
            const std::string series = ao == AoMethod::Off ? "no AO" : "AO (reference ray-traced)";
            const core::RenderRequest base = request(a, s, ao);
            double ref_ms = 0;
            const Image ref = reference(s, base, ref_ms);
            save_image(ref, a.out + "/" + name + "_" + ao_method_name(ao) + "_reference.png", {});
            for (const Config& c : configs) {
                if (ao == AoMethod::Off && c.ao == AoMethod::Raytraced) continue; // the cone export's twin there
                double ms = 0;
                int frames = 0;
                const Image img = run(s, base, c, a.reps, ms, frames);
                const bench::ImageError e = bench::compare(img, ref);
                std::printf("| %s | %s | %s | %d | %.1f | %.4f | %.4f | %.4f | %.4f |\n", name.c_str(), series.c_str(),
                            c.name.c_str(), frames, ms, e.rmse, e.p99, e.edge_rmse, e.edge_p99);
                std::fflush(stdout);
                csv << name << "," << series << "," << csv_text(c.name) << "," << frames << "," << ms << "," << e.rmse << ","
                    << e.p99 << "," << e.edge_rmse << "," << e.edge_p99 << "," << s.triangles << "\n";
            }
            std::printf("| %s | %s | reference (8x8 stratified, 1 sample each) | 64 | %.1f | 0 | 0 | 0 | 0 |\n",
                        name.c_str(), series.c_str(), ref_ms);
        }
        peers(s, a, csv);
        s.scene.release_gpu();
    }
    csv.close();
    write_plot(csv_path, a.out + "/image_time_error.png");
    return 0;
} catch (const std::exception& e) {
    std::cerr << "image_bench: " << e.what() << "\n";
    return 1;
}
