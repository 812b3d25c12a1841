// What DSRAA costs the live view: the steady frame time of each scene with
// 1, 2 and 4 visibility sub-samples per pixel (the live view's frame: one
// frame, no accumulation; without AO and with cone AO), the ratio to one
// sample, and the passes that make the difference (time_passes: glFinish
// after each pass, a separate run). Error against exact coverage is
// image_bench's; this program measures the cost. Prints a Markdown table
// and writes OUT/dsraa_bench.csv.
//
//   dsraa_bench [--out DIR] [--size WxH] [--frames N] [--ao off|cone] [--scenes head,bunny,thin,dense] [--quick]
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "bench_scenes.hpp"
#include "bench_util.hpp"
#include "renderer/core/api.hpp"
#include "renderer/gl/context.hpp"

using namespace iso;
namespace fs = std::filesystem;

namespace {

struct Args {
    std::string out = "bench-results/dsraa";
    int width = 640, height = 480, frames = 9;
    std::vector<std::string> scenes{"head", "bunny", "thin"};
    std::vector<AoMethod> ao{AoMethod::Off, AoMethod::Cone};
    bool quick = false;
};

struct Timing {
    double ms = 0;                      // median steady frame
    std::map<std::string, double> pass; // median per pass, with glFinish after each
};

Timing measure(bench::BenchScene& s, const Args& a, AoMethod ao, int samples) {
    core::RenderRequest req;
    req.width = a.width;
    req.height = a.height;
    req.view = s.view;
    req.look.ao = ao;
    req.look.aa.samples = samples;
    req.look.aa.frames = 1;
    req.look.ao_frames = 1;
    RenderOptions ro = core::frame_options(req);
    const Camera cam = core::frame_camera(s.scene, req);
    for (int i = 0; i < 2; ++i) s.scene.render(cam, ro); // shaders, uploads, pool
    Timing t;
    std::vector<double> frame;
    for (int i = 0; i < a.frames; ++i) {
        const double t0 = bench::now_s();
        const RenderResult r = s.scene.render(cam, ro);
        frame.push_back((bench::now_s() - t0) * 1e3);
        if (r.aa_samples != samples)
            throw Error("dsraa_bench", "asked " + std::to_string(samples) + " sub-samples, the frame drew " +
                                           std::to_string(r.aa_samples));
    }
    t.ms = bench::median(frame);
    ro.time_passes = true;
    std::map<std::string, std::vector<double>> passes;
    for (int i = 0; i < a.frames; ++i)
        for (const auto& p : s.scene.render(cam, ro).stats.passes)
            if (p.ran) passes[p.name].push_back(p.ms);
    for (auto& [name, v] : passes) t.pass[name] = bench::median(v);
    return t;
}

Args parse(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("dsraa_bench", arg + " needs a value");
            return argv[++i];
        };
        if (arg == "--out")
            a.out = next();
        else if (arg == "--size") {
            if (!bench::parse_size(next(), a.width, a.height)) throw Error("dsraa_bench", "--size WxH");
        } else if (arg == "--frames")
            a.frames = std::max(1, std::stoi(next()));
        else if (arg == "--quick") {
            a.quick = true;
            a.frames = 2;
        } else if (arg == "--ao") {
            a.ao = {ao_method_from_name(next())};
        } else if (arg == "--scenes") {
            a.scenes = bench::split_list(next());
        } else {
            throw Error("dsraa_bench", "unknown argument " + arg +
                                           " (usage: dsraa_bench [--out DIR] [--size WxH] [--frames N] [--ao off|cone] "
                                           "[--scenes head,bunny,thin,dense] [--quick])");
        }
    }
    return a;
}

} // namespace

int main(int argc, char** argv) try {
    const Args a = parse(argc, argv);
    fs::create_directories(a.out);
    std::ofstream csv(a.out + "/dsraa_bench.csv");
    csv << "scene,ao,samples,frame_ms,ratio,gbuffer_ms,dsraa_ms,lighting_ms,triangles\n";
    const gl::ScopedCurrent context;
    std::printf("%d x %d, median of %d frames\n\n", a.width, a.height, a.frames);
    std::printf("| scene | AO | sub-samples | frame ms | x 1 sample | gbuffer ms | dsraa ms | lighting ms |\n"
                "|---|---|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& name : a.scenes) {
        bench::BenchScene s;
        s.name = name;
        bench::make_scene(s, ISOSCOPE_DATA_DIR, a.quick);
        for (const AoMethod ao : a.ao) {
            double base = 0;
            for (const int samples : {1, 2, 4}) {
                const Timing t = measure(s, a, ao, samples);
                if (samples == 1) base = t.ms;
                const auto pass = [&](const char* p) { return t.pass.count(p) ? t.pass.at(p) : 0.0; };
                std::printf("| %s | %s | %d | %.1f | %.2f | %.1f | %.1f | %.1f |\n", name.c_str(), ao_method_name(ao),
                            samples, t.ms, t.ms / base, pass("gbuffer"), pass("dsraa"), pass("lighting"));
                std::fflush(stdout);
                csv << name << "," << ao_method_name(ao) << "," << samples << "," << t.ms << "," << t.ms / base << ","
                    << pass("gbuffer") << "," << pass("dsraa") << "," << pass("lighting") << "," << s.triangles << "\n";
            }
        }
        s.scene.release_gpu();
    }
    return 0;
} catch (const std::exception& e) {
    std::cerr << "dsraa_bench: " << e.what() << "\n";
    return 1;
}
