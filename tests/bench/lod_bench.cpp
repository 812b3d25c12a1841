// Levels of detail and cluster culling, run time against error
// (docs/lod.md, docs/measuring.md): every surface drawn whole (--lod off)
// against the clusters at several error bounds, with and without culling,
// per scene:
//   G-buffer pass (ms; the frame's pass times, glFinish after each) of the
//     first frame (no last frame: distance batches) and the median of the
//     frames after it (the last frame's visibility), the whole frame,
//     triangles drawn, the levels' build (s, once per surface);
//   error against the full frame of the same settings: image RMSE (sRGB
//     0..1, every pixel), depth error (mm along the view axis, mean and
//     largest over the pixels both cover) and the pixels whose coverage
//     differs.
// VTK's answer beside it (lod_peer under xvfb-run): vtkPolyDataMapper with
// every triangle, and vtkQuadricClustering as ParaView's LOD, against VTK's
// own full image. Moving frames (a drag's, RenderOptions::moving) at
// several moving bounds: the stand-ins (lod::Proxy) where they qualify.
// Scenes: the bundled CT (headsq) resampled 3x per axis,
// skin and bone; and any mesh given with --mesh (the 1024^3 phantom's
// surface: `isoscope mesh ct1024x1024x1024.nii --iso 300.5 -o ct1024.ply`,
// the volume from `scale_bench --sizes 1024 --generate-only`).
//
//   lod_bench [--mesh NAME=PATH ...] [--no-ct] [--size 1920x1080] [--errors 0.5,1,2,4]
//             [--moving-errors 2,4,8] [--frames 4] [--out DIR] [--no-peer] [--divisions 128,256]
// Writes DIR/lod_bench.csv and DIR/lod_bench.png (gnuplot: G-buffer time
// against image RMSE).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "io/mesh.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/surface/analysis.hpp"
#include "tests/bench/bench_util.hpp"
#include "tests/bench/image_error.hpp"

using namespace iso;
namespace fs = std::filesystem;

namespace {

struct Args {
    std::vector<std::pair<std::string, std::string>> meshes;
    bool ct = true, peer = true;
    int width = 1920, height = 1080, frames = 4;
    std::vector<double> errors{0.5, 1.0, 2.0, 4.0};
    std::vector<double> moving_errors{2.0, 4.0, 8.0};
    std::string out = "bench-results/lod", divisions = "128,256";
};

struct Frame {
    Image image, depth;
    double gbuffer_first = 0, gbuffer_next = 0, frame_first = 0, frame_next = 0, build_s = 0;
    std::uint64_t drawn_first = 0, drawn_next = 0, full = 0;
};

double pass_ms(const RenderResult& r, const char* name) {
    for (const auto& p : r.stats.passes)
        if (p.name == name) return p.ms;
    return 0;
}
double total_ms(const RenderResult& r) {
    double t = 0;
    for (const auto& p : r.stats.passes) t += p.ms;
    return t;
}

// `frames` frames of one configuration on a fresh renderer, then its depth.
Frame run(core::Scene& scene, const Camera& cam, RenderOptions ro, int frames) {
    scene.release_gpu();
    Frame f;
    std::vector<double> g, t;
    for (int k = 0; k < frames; ++k) {
        const RenderResult r = scene.render(cam, ro);
        if (k == 0) {
            f.gbuffer_first = pass_ms(r, "gbuffer");
            f.frame_first = total_ms(r);
            f.drawn_first = r.lod.used ? r.lod.triangles_drawn : 0;
            f.build_s = r.lod.build_seconds;
            f.image = r.image;
        } else {
            g.push_back(pass_ms(r, "gbuffer"));
            t.push_back(total_ms(r));
            f.drawn_next = r.lod.used ? r.lod.triangles_drawn : 0;
        }
        f.full = r.lod.triangles_full;
    }
    f.gbuffer_next = bench::median(g);
    f.frame_next = bench::median(t);
    ro.aov = Aov::Depth;
    f.depth = scene.render(cam, ro).image;
    return f;
}

struct Errors {
    double rmse = 0, depth_mean = 0, depth_max = 0, coverage = 0;
};

Errors compare(const Frame& a, const Frame& ref) {
    Errors e;
    e.rmse = bench::compare(a.image, ref.image).rmse;
    const std::size_t n = std::size_t(ref.image.width) * std::size_t(ref.image.height);
    std::size_t both = 0, differ = 0;
    for (std::size_t p = 0; p < n; ++p) {
        const float x = a.depth.floats[p], y = ref.depth.floats[p];
        if (std::isinf(x) != std::isinf(y)) {
            ++differ;
        } else if (!std::isinf(x)) {
            ++both;
            e.depth_mean += std::abs(double(x) - y);
            e.depth_max = std::max(e.depth_max, std::abs(double(x) - y));
        }
    }
    e.depth_mean = both ? e.depth_mean / double(both) : 0.0;
    e.coverage = double(differ) / double(n);
    return e;
}

struct Row {
    std::string scene, config;
    Frame f;
    Errors e;
};

void print(const Row& r) {
    std::printf("%-10s %-22s %9.1f %9.1f %9.1f %6.2f %11llu %11llu %8.5f %8.4f %8.4f %7.4f\n", r.scene.c_str(),
                r.config.c_str(), r.f.gbuffer_first, r.f.gbuffer_next, r.f.frame_next, r.f.build_s,
                (unsigned long long)(r.f.drawn_first ? r.f.drawn_first : r.f.full),
                (unsigned long long)(r.f.drawn_next ? r.f.drawn_next : r.f.full), r.e.rmse, r.e.depth_mean,
                r.e.depth_max, 100.0 * r.e.coverage);
}

// The VTK peer on one mesh: its JSON and its images' errors (LOD against full).
void run_peer(const Args& a, const std::string& name, const std::string& mesh, const Camera& cam,
              std::vector<Row>& rows) {
    const fs::path dir = fs::path(a.out) / ("vtk_" + name);
    fs::create_directories(dir);
    std::ostringstream cmd;
    cmd << "xvfb-run -a -s '-screen 0 " << a.width + 64 << "x" << a.height + 64 << "x24' " << ISOSCOPE_LOD_PEER
        << " --mesh '" << mesh << "' --eye " << cam.eye.x << "," << cam.eye.y << "," << cam.eye.z << " --target "
        << cam.target.x << "," << cam.target.y << "," << cam.target.z << " --up " << cam.up.x << "," << cam.up.y << ","
        << cam.up.z << " --fov " << cam.fov_y_degrees << " --near " << cam.near_plane << " --far " << cam.far_plane
        << " --size " << a.width << "x" << a.height << " --background 0.08,0.09,0.11 --out '" << dir.string()
        << "' --divisions " << a.divisions << " --frames 3";
    const std::string line = bench::capture(cmd.str());
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(line);
    } catch (const std::exception&) {
        std::fprintf(stderr, "lod_bench: the VTK peer gave no result: %s\n", line.c_str());
        return;
    }
    const Image full = load_image((dir / "full.png").string());
    Row r{name, "VTK all triangles", {}, {}};
    r.f.gbuffer_next = r.f.frame_next = j["full_ms"].get<double>();
    r.f.full = j["full_triangles"].get<std::uint64_t>();
    rows.push_back(r);
    print(rows.back());
    for (const auto& l : j["lod"]) {
        const int d = l["divisions"].get<int>();
        Row q{name, "VTK quadric " + std::to_string(d), {}, {}};
        q.f.gbuffer_next = q.f.frame_next = l["ms"].get<double>();
        q.f.build_s = l["build_s"].get<double>();
        q.f.drawn_next = q.f.drawn_first = l["triangles"].get<std::uint64_t>();
        const Image img = load_image((dir / ("lod" + std::to_string(d) + ".png")).string());
        q.e.rmse = bench::compare(img, full).rmse;
        rows.push_back(q);
        print(rows.back());
    }
}

void bench_scene(const Args& a, const std::string& name, core::Scene& scene, const std::string& mesh_path,
                 std::vector<Row>& rows) {
    const Camera cam = scene.camera(PatientView::Anterior, double(a.width) / double(a.height));
    RenderOptions ro;
    ro.width = a.width;
    ro.height = a.height;
    ro.time_passes = true;
    ro.look.aa.samples = 1;
    ro.look.lod.enabled = false;
    const Frame ref = run(scene, cam, ro, a.frames);
    rows.push_back({name, "all triangles", ref, {}});
    print(rows.back());
    for (const double e : a.errors)
        for (const bool cull : {true, false}) {
            if (!cull && e != 0.5) continue;
            ro.look.lod.enabled = true;
            ro.look.lod.error_px = e;
            ro.look.lod.culling = cull;
            char cfg[64];
            std::snprintf(cfg, sizeof cfg, "lod %.2g px%s", e, cull ? " + culling" : "");
            Row r{name, cfg, run(scene, cam, ro, a.frames), {}};
            r.e = compare(r.f, ref);
            rows.push_back(r);
            print(rows.back());
        }
    // A drag's frames (RenderOptions::moving): a stand-in where its error
    // projects within the moving bound, else the levels to that bound (the
    // "lod N px + culling" rows above are what a moving frame drew before
    // the stand-ins).
    for (const double e : a.moving_errors) {
        ro.look.lod.enabled = true;
        ro.look.lod.culling = true;
        ro.look.lod.error_px = 0.5;
        ro.look.lod.moving_error_px = e;
        ro.moving = true;
        char cfg[64];
        std::snprintf(cfg, sizeof cfg, "moving %.2g px", e);
        Row r{name, cfg, run(scene, cam, ro, a.frames), {}};
        r.e = compare(r.f, ref);
        rows.push_back(r);
        print(rows.back());
    }
    if (a.peer && !mesh_path.empty()) run_peer(a, name, mesh_path, cam, rows);
}

void write_outputs(const Args& a, const std::vector<Row>& rows) {
    const fs::path csv = fs::path(a.out) / "lod_bench.csv";
    std::ofstream f(csv);
    f << "scene,config,gbuffer_first_ms,gbuffer_ms,frame_ms,build_s,triangles_first,triangles,image_rmse,"
         "depth_mean_mm,depth_max_mm,coverage_pct\n";
    for (const auto& r : rows)
        f << r.scene << "," << r.config << "," << r.f.gbuffer_first << "," << r.f.gbuffer_next << "," << r.f.frame_next
          << "," << r.f.build_s << "," << (r.f.drawn_first ? r.f.drawn_first : r.f.full) << ","
          << (r.f.drawn_next ? r.f.drawn_next : r.f.full) << "," << r.e.rmse << "," << r.e.depth_mean << ","
          << r.e.depth_max << "," << 100.0 * r.e.coverage << "\n";
    std::ofstream gp(fs::path(a.out) / "lod_bench.gp");
    gp << "set datafile separator ','\nset terminal pngcairo size 900,600\nset output '" << a.out
       << "/lod_bench.png'\nset logscale x\nset xlabel 'G-buffer pass, ms (llvmpipe; log)'\n"
          "set ylabel 'image RMSE against every triangle'\nset key outside\n"
          "plot '"
       << csv.string()
       << "' every ::1 using 4:9:(stringcolumn(1).' '.stringcolumn(2)) with labels point pt 7 offset 1,0.5 "
          "font ',7' notitle\n";
    gp.close();
    if (std::system(("gnuplot " + (fs::path(a.out) / "lod_bench.gp").string() + " 2>/dev/null").c_str()) == 0)
        std::printf("wrote %s/lod_bench.png\n", a.out.c_str());
    std::printf("wrote %s\n", csv.c_str());
}

Args parse(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string s = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("lod_bench", s + " needs a value");
            return argv[++i];
        };
        if (s == "--mesh") {
            const std::string v = value();
            const auto eq = v.find('=');
            if (eq == std::string::npos) throw Error("--mesh", "expected NAME=PATH, got '" + v + "'");
            a.meshes.emplace_back(v.substr(0, eq), v.substr(eq + 1));
        } else if (s == "--no-ct") {
            a.ct = false;
        } else if (s == "--no-peer") {
            a.peer = false;
        } else if (s == "--size") {
            if (!bench::parse_size(value(), a.width, a.height)) throw Error("--size", "expected WxH");
        } else if (s == "--errors") {
            a.errors.clear();
            for (const auto& e : bench::split_list(value())) a.errors.push_back(std::stod(e));
        } else if (s == "--moving-errors") {
            a.moving_errors.clear();
            for (const auto& e : bench::split_list(value())) a.moving_errors.push_back(std::stod(e));
        } else if (s == "--frames") {
            a.frames = std::max(2, std::stoi(value()));
        } else if (s == "--out") {
            a.out = value();
        } else if (s == "--divisions") {
            a.divisions = value();
        } else {
            throw Error("lod_bench", "unknown option " + s);
        }
    }
    return a;
}

} // namespace

int main(int argc, char** argv) {
    try {
        const Args a = parse(argc, argv);
        fs::create_directories(a.out);
        const gl::ScopedCurrent context;
        std::vector<Row> rows;
        std::printf("%-10s %-22s %9s %9s %9s %6s %11s %11s %8s %8s %8s %7s\n", "scene", "config", "gb1st ms", "gb ms",
                    "frame ms", "build", "tris 1st", "tris", "RMSE", "dz mean", "dz max", "cov %");
        if (a.ct) {
            // The bundled CT resampled 3x per axis (trilinear): a real CT's
            // surfaces at micro-CT triangle counts.
            const Volume v0 = load_volume(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr");
            Volume v = resample_extent(v0, {3 * v0.dims[0] - 2, 3 * v0.dims[1] - 2, 3 * v0.dims[2] - 2});
            core::Scene scene;
            scene.set_volume(std::move(v), "headsq x3");
            const auto ids = scene.add_isosurfaces({500, 1150});
            const std::string path = (fs::path(a.out) / "headsq_x3_bone.ply").string();
            save_mesh(scene.mesh(ids[1]), path);
            scene.remove_surface(ids[0]); // the peer draws one mesh: the bone
            bench_scene(a, "headsq x3", scene, path, rows);
        }
        for (const auto& [name, path] : a.meshes) {
            core::Scene scene;
            scene.open(path);
            bench_scene(a, name, scene, path, rows);
        }
        write_outputs(a, rows);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "lod_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
