// Transparency benchmark: our VOIT against VTK 9.1's
// weighted-blended OIT (its default) and dual depth peeling (4 peels, VTK's
// default, and until converged), same meshes, colours, opacities, camera and
// image size, in the same run (VTK under xvfb-run through oit_peer). Errors
// against the exact CPU reference (Embree, every hit, double precision),
// flat shading, over foreground pixels. Each method is measured in the
// space it composites in: ours composites in linear light and writes sRGB,
// so its error is in sRGB units against the encoded reference; VTK blends
// the (linear) colours it is given in framebuffer space and writes them as
// they are, so its error is in those units against the linear reference.
//
//   voit_bench [--out DIR] [--size N] [--frames N] [--scenes ct,shells] [--peer PATH]
// Prints a table per scene, writes voit.csv and a time-vs-RMSE plot.
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

#include "bench_util.hpp"
#include "io/error.hpp"
#include "tests/support/transparency_reference.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/surface/extract.hpp"

using namespace iso;

namespace {

struct Args {
    std::string out = "bench-results", peer = ISOSCOPE_OIT_PEER;
    int size = 512, frames = 10;
    std::vector<std::string> scenes{"ct", "shells"};
};

struct BenchScene {
    std::string name, description;
    std::vector<Mesh> meshes;
    std::vector<glm::vec3> colors;
    std::vector<float> opacity;
};

// A sphere from a 60^3 distance field: about 20k triangles whatever its radius.
Mesh sphere(double r) {
    const int n = 60;
    const glm::dvec3 origin(-1.2 * r);
    const double step = 2.4 * r / (n - 1);
    auto v = Volume::dense({n, n, n}, VoxelType::F32, make_affine(glm::dvec3(step), origin));
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                v.as<float>()[v.linear_index(i, j, k)] = float(r - glm::length(origin + step * glm::dvec3(i, j, k)));
    return extract_isosurface(v, 0.0, {});
}

BenchScene make_scene(const std::string& name) {
    BenchScene s;
    s.name = name;
    if (name == "ct") {
        core::Scene scene;
        scene.open(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr");
        const auto ids = scene.add_isosurfaces({500, 1150});
        s.description = "bundled CT, skin (iso 500) 0.3 over bone (iso 1150) 0.5, anterior";
        for (std::size_t i = 0; i < ids.size(); ++i) {
            s.meshes.push_back(scene.mesh(ids[i]));
            s.colors.push_back(scene.info(ids[i]).color);
            s.opacity.push_back(i == 0 ? 0.3f : 0.5f);
        }
    } else if (name == "shells") {
        s.description = "20 nested translucent spheres (opacity 0.2), anterior";
        for (int i = 0; i < 20; ++i) {
            const float t = float(i) / 19.0f;
            s.meshes.push_back(sphere(10.0 + 5.0 * i));
            s.colors.push_back({0.2f + 0.7f * t, 0.8f - 0.6f * t, 0.5f});
            s.opacity.push_back(0.2f);
        }
    } else {
        throw Error("voit_bench", "unknown scene '" + name + "' (ct, shells)");
    }
    return s;
}

struct Row {
    std::string method;
    double ms = 0, mib = -1, rmse = 0, max = 0;
    double off = 0; // fraction of foreground pixels off by more than 0.01 in some channel
};

double srgb_byte_error(std::uint8_t v, double linear_ref) { return std::abs(v / 255.0 - srgb_encode(linear_ref)); }

template <class F> void errors(const Image& img, const TransparencyImage& ref, F err, Row& row) {
    double sum = 0;
    std::size_t n = 0, off = 0;
    for (std::size_t p = 0; p < ref.linear.size(); ++p) {
        if (!ref.foreground[p]) continue;
        ++n;
        double worst = 0;
        for (int c = 0; c < 3; ++c) {
            const double e = err(img.bytes[p * std::size_t(img.channels) + std::size_t(c)], ref.linear[p][c]);
            sum += e * e;
            worst = std::max(worst, e);
        }
        row.max = std::max(row.max, worst);
        off += worst > 0.01;
    }
    row.rmse = n ? std::sqrt(sum / double(3 * n)) : 0.0;
    row.off = n ? double(off) / double(n) : 0.0;
}

std::string v3(const glm::dvec3& v) {
    std::ostringstream s;
    s.precision(17);
    s << v.x << "," << v.y << "," << v.z;
    return s.str();
}

} // namespace

int main(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string s = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("voit_bench", s + " needs a value");
            return argv[++i];
        };
        try {
            if (s == "--out")
                a.out = next();
            else if (s == "--size")
                a.size = std::stoi(next());
            else if (s == "--frames")
                a.frames = std::stoi(next());
            else if (s == "--peer")
                a.peer = next();
            else if (s == "--scenes") {
                a.scenes.clear();
                std::stringstream ss(next());
                for (std::string t; std::getline(ss, t, ',');) a.scenes.push_back(t);
            } else {
                std::cerr
                    << "usage: voit_bench [--out DIR] [--size N] [--frames N] [--scenes ct,shells] [--peer PATH]\n";
                return 2;
            }
        } catch (const std::exception& e) {
            std::cerr << "voit_bench: " << e.what() << "\n";
            return 2;
        }
    }
    try {
        std::filesystem::create_directories(a.out);
        gl::HeadlessContext ctx;
        ctx.make_current();
        const int S = a.size;
        std::ofstream csv(a.out + "/voit.csv");
        csv << "scene,method,ms,mib,rmse,max,off_fraction\n";
        std::vector<std::pair<std::string, std::vector<Row>>> all;
        for (const auto& name : a.scenes) {
            const BenchScene sc = make_scene(name);
            Renderer ren;
            std::vector<ReferenceSurface> ref_surfaces;
            std::size_t triangles = 0;
            for (std::size_t i = 0; i < sc.meshes.size(); ++i) {
                SceneObject o;
                o.color = sc.colors[i];
                o.opacity = sc.opacity[i];
                ren.add(sc.meshes[i], o);
                ref_surfaces.push_back({&sc.meshes[i], sc.colors[i], sc.opacity[i]});
                triangles += sc.meshes[i].triangles.size();
            }
            Camera cam;
            cam.set_view(PatientView::Anterior, ren.bounds());
            cam.fit(ren.bounds(), 1.0);
            RenderOptions o;
            o.width = o.height = S;
            o.look.flat_shading = true;
            const glm::dvec3 bg(o.look.background);
            std::cerr << "[voit_bench] " << name << ": reference (Embree, every hit)\n";
            const TransparencyImage ref = transparency_reference(ref_surfaces, cam, S, S, bg);
            std::size_t fg = 0, hits = 0, deepest = 0;
            for (std::size_t p = 0; p < ref.hits.size(); ++p)
                if (ref.foreground[p]) ++fg, hits += ref.hits[p], deepest = std::max<std::size_t>(deepest, ref.hits[p]);
            std::vector<Row> rows;
            // Ours: frames presented into an offscreen framebuffer (no read-back), the GPU finished each time.
            auto target = gl::Texture::create_2d(GL_RGBA8, S, S);
            auto fb = gl::Framebuffer::create();
            fb.attach(GL_COLOR_ATTACHMENT0, target);
            RenderOptions timed = o;
            timed.present = true;
            timed.target_framebuffer = fb.id();
            std::vector<double> ms;
            for (int f = 0; f < a.frames + 2; ++f) {
                const double t0 = bench::now_s();
                ren.render(cam, timed);
                glFinish();
                if (f >= 2) ms.push_back(1000.0 * (bench::now_s() - t0));
            }
            const auto r = ren.render(cam, o);
            Row ours{"VOIT (ours)", bench::median(ms)};
            ours.mib = double(r.oit.capacity * 20 + std::size_t(S) * S * 4) / 1048576.0;
            errors(r.image, ref, srgb_byte_error, ours);
            save_image(r.image, a.out + "/voit_" + name + "_ours.png");
            rows.push_back(ours);
            // VTK through oit_peer.
            std::vector<std::string> files;
            for (std::size_t i = 0; i < sc.meshes.size(); ++i) {
                files.push_back(a.out + "/voit_" + name + "_" + std::to_string(i) + ".ply");
                save_mesh(sc.meshes[i], files.back());
            }
            struct Peer {
                std::string label, mode;
                int peels;
            };
            for (const Peer& p :
                 {Peer{"VTK weighted blended OIT", "wboit", 0}, Peer{"VTK dual depth peeling, 4 peels", "peel", 4},
                  Peer{"VTK dual depth peeling, 100 peels (converged)", "peel", 100}}) {
                std::ostringstream cmd;
                cmd.precision(17);
                const std::string png = a.out + "/voit_" + name + "_" + p.mode + std::to_string(p.peels) + ".png";
                cmd << "xvfb-run -a -s '-screen 0 " << std::max(S + 64, 1280) << "x" << std::max(S + 64, 1024)
                    << "x24' " << a.peer;
                for (std::size_t i = 0; i < files.size(); ++i)
                    cmd << " --mesh " << files[i] << " --color " << v3(glm::dvec3(sc.colors[i])) << " --opacity "
                        << sc.opacity[i];
                cmd << " --eye " << v3(cam.eye) << " --target " << v3(cam.target) << " --up " << v3(cam.up) << " --fov "
                    << cam.fov_y_degrees << " --near " << cam.near_plane << " --far " << cam.far_plane << " --size "
                    << S << "x" << S << " --background " << v3(bg) << " --mode " << p.mode << " --peels " << p.peels
                    << " --frames " << std::max(3, a.frames / 2) << " --out " << png << " 2>/dev/null";
                const std::string line = bench::capture(cmd.str());
                try {
                    const auto j = nlohmann::json::parse(line.substr(line.find('{')));
                    Row row{p.label, j.at("ms_median").get<double>()};
                    errors(
                        load_image(png), ref, [](std::uint8_t v, double lin) { return std::abs(v / 255.0 - lin); },
                        row);
                    rows.push_back(row);
                } catch (const std::exception& e) {
                    std::cerr << "[voit_bench] oit_peer failed (" << e.what() << "): " << line << "\n";
                }
            }
            std::printf("\n### %s, %dx%d: %zu triangles, %zu foreground px, mean depth complexity %.1f, max %zu\n\n",
                        sc.description.c_str(), S, S, triangles, fg, fg ? double(hits) / double(fg) : 0.0, deepest);
            std::printf("| method | ms/frame | OIT memory MiB | RGB RMSE | max error | px off > 0.01 "
                        "|\n|---|---:|---:|---:|---:|---:|\n");
            for (const auto& row : rows) {
                char mib[32] = "-";
                if (row.mib >= 0) std::snprintf(mib, sizeof mib, "%.1f", row.mib);
                std::printf("| %s | %.1f | %s | %.4f | %.4f | %.3f %% |\n", row.method.c_str(), row.ms, mib, row.rmse,
                            row.max, 100 * row.off);
                csv << name << ",\"" << row.method << "\"," << row.ms << "," << row.mib << "," << row.rmse << ","
                    << row.max << "," << row.off << "\n";
            }
            std::printf("\nours: %llu fragments, %llu shaded, longest list %u, pool %llu nodes\n",
                        (unsigned long long)r.oit.fragments, (unsigned long long)r.oit.shaded, r.oit.max_list,
                        (unsigned long long)r.oit.capacity);
            all.emplace_back(name, rows);
        }
        csv.close();
        // Time against error, one panel per scene (log-log).
        std::ofstream gp(a.out + "/voit.gp");
        gp << "set terminal pngcairo size " << 520 * int(all.size()) << ",440\nset output '" << a.out
           << "/voit_time_rmse.png'\n"
           << "set multiplot layout 1," << all.size()
           << "\nset logscale xy\nset xlabel 'ms per frame (llvmpipe)'\nset ylabel 'RGB RMSE vs exact'\n"
           << "set key bottom left\nset grid\n";
        for (const auto& [name, rows] : all) {
            gp << "set title '" << name << "'\nplot";
            for (std::size_t i = 0; i < rows.size(); ++i)
                gp << (i ? "," : "") << " '-' with points pt 7 ps 1.5 title '" << rows[i].method << "'";
            gp << "\n";
            for (const auto& row : rows) gp << row.ms << " " << std::max(row.rmse, 1e-5) << "\ne\n";
        }
        gp << "unset multiplot\n";
        gp.close();
        if (std::system(("gnuplot " + a.out + "/voit.gp").c_str()) == 0)
            std::printf("\nwrote %s/voit_time_rmse.png\n", a.out.c_str());
    } catch (const std::exception& e) {
        std::cerr << "voit_bench: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
