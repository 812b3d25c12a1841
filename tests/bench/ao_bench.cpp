// Ambient occlusion: run time against error (docs/ao.md).
//
// For each scene (the bundled CT's skin and bone surfaces, the Stanford
// bunny, the thin-structure phantom of thin_phantom.hpp), AO radius and image
// size, against the Embree ray-traced reference (cached by
// input hash, see core::RenderRequest::cache_dir):
//   - cone-traced AO over a sweep of its tunables (AO passes timed with
//     glFinish after each pass, slicemap rebuilt every frame);
//   - the same AO traced through the slicemap (the voxel-grid reference), to
//     split voxelization error from cone error;
//   - VTK 9.1 vtkSSAOPass (ssao_peer under xvfb-run) over a kernel sweep,
//     same meshes, camera and size, in the same run;
//   - disk-based AO (GPU Gems 3 ch. 12; --disk none|default|sweep), its cost
//     split into hierarchy build (CPU), upload, element passes and gather;
//   - no AO at all (AO = 1).
// Prints markdown tables with Pareto flags, writes OUT/ao.csv and, with
// gnuplot, OUT/ao_time_rmse.png (every scene and radius, one panel each) and
// one OUT/ao_time_rmse_<scene>_R<radius>.png per scene and radius.
//
//   ao_bench [--quick] [--out DIR] [--sizes 512,1024] [--scenes ct-skin,ct-bone,bunny,thin]
//            [--radii 10,20] [--rays 1024] [--reps 5] [--ssao PATH|none] [--config C ...] [--voxel-ref]
//            [--disk none|default|sweep]
//   ao_bench --replot DIR/ao.csv [--out DIR2]   (redraw the plot from saved results)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tests/support/ao_metrics.hpp"
#include "bench_util.hpp"
#include "io/image.hpp"
#include "io/mesh.hpp"
#include "renderer/ao/reference.hpp"
#include "renderer/core/api.hpp"
#include "renderer/gl/context.hpp"
#include "tests/support/thin_phantom.hpp"

namespace fs = std::filesystem;
using namespace iso;

namespace {

struct Args {
    std::string out = "bench-results/ao";
    std::vector<int> sizes{512, 1024};
    std::vector<std::string> scenes{"ct-skin", "ct-bone", "bunny", "thin"};
    // AO radii in mm for the CT scenes (10: the issue's target; 20: twice
    // that, where a sphere is widest against a thin wall and the slicemap's z
    // range grows by R, so its voxels are coarsest: the harder case). The
    // bunny, in its own units, gets the same multiples of a tenth of its size.
    std::vector<double> radii{10, 20};
    int rays = 1024;
    int reps = 5;
    bool quick = false;
    std::string ssao = ISOSCOPE_SSAO_PEER;
    std::string data = ISOSCOPE_DATA_DIR;
    std::vector<std::string> configs; // replace the sweep (exploration)
    bool extras = true;               // still frames, voxel reference
    bool voxel_ref_each = false;      // --voxel-ref: voxel-grid reference for every --config
    std::string replot;               // --replot CSV: only redraw OUT/ao_time_rmse.png from saved results
    std::string disk = "sweep";       // --disk none|default|sweep: disk AO rows
};

struct Scene {
    std::string name, input, view;
    std::vector<double> isos;
    double radius = 10;    // mm (CT scenes) or scene units (the bunny)
    double radius_mm = 10; // the --radii entry it came from (names the plot)
    std::vector<Mesh> meshes;
    double size = 1; // bounding-box diagonal
};

struct Row {
    std::string scene, method, params;
    int size = 0;
    double radius = 0; // AO radius (scene units)
    double ao_ms = 0, frame_ms = 0;
    AoError err;
    bool pareto = false;
};

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> v;
    std::stringstream ss(s);
    for (std::string t; std::getline(ss, t, ',');) v.push_back(t);
    return v;
}

Scene make_scene(const std::string& name, const Args& a) {
    Scene s;
    s.name = name;
    if (name == "ct-skin" || name == "ct-bone") {
        s.input = a.data + "/headsq.nhdr";
        s.isos = {name == "ct-skin" ? 500.0 : 1150.0};
        s.view = name == "ct-skin" ? "left" : "anterior";
        core::Scene scene;
        scene.open(s.input);
        for (const auto id : scene.add_isosurfaces(s.isos)) s.meshes.push_back(scene.mesh(id));
    } else if (name == "bunny") {
        s.input = a.data + "/bunny.vtp";
        s.view = "anterior";
        s.meshes.push_back(core::open_mesh(s.input));
    } else if (name == "thin") {
        // The thin-structure phantom: vessels 3.5 .. 0.45 mm in radius and 1-2 mm
        // bone shells (thin_phantom.hpp), written once as NRRD because the
        // reference goes through core::render_input(path). Seen from the front,
        // the tree is in front of the bone.
        s.input = bench::write_thin_phantom(a.out + "/thin_phantom_v2.nrrd");
        s.isos = {150.0};
        s.view = "anterior";
        core::Scene scene;
        scene.open(s.input);
        for (const auto id : scene.add_isosurfaces(s.isos)) s.meshes.push_back(scene.mesh(id));
    } else {
        throw Error("ao_bench", "unknown scene '" + name + "' (ct-skin, ct-bone, bunny, thin)");
    }
    Bounds b;
    for (const auto& m : s.meshes)
        for (const auto& p : m.positions) b.add(glm::dvec3(p));
    s.size = 2.0 * b.radius();
    return s;
}

void mark_pareto(std::vector<Row>& rows) {
    for (auto& r : rows) {
        r.pareto = true;
        for (const auto& o : rows)
            if (&o != &r && o.ao_ms <= r.ao_ms && o.err.rmse <= r.err.rmse &&
                (o.ao_ms < r.ao_ms || o.err.rmse < r.err.rmse)) {
                r.pareto = false;
                break;
            }
    }
}

std::string no_commas(std::string s) {
    std::replace(s.begin(), s.end(), ',', ';');
    return s;
}

// An AO image as an 8-bit grey PNG (background dark blue-grey), or the
// signed difference of two as a diverging map (red: too dark, blue: too bright).
void save_grey(const Image& ao, const std::string& path) {
    Image o;
    o.width = ao.width;
    o.height = ao.height;
    o.channels = 3;
    o.bytes.resize(std::size_t(o.width) * o.height * 3);
    for (std::size_t i = 0; i < ao.floats.size(); ++i) {
        const float v = ao.floats[i];
        const bool bg = !std::isfinite(v);
        const auto g = std::uint8_t(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f);
        o.bytes[3 * i] = bg ? 40 : g;
        o.bytes[3 * i + 1] = bg ? 44 : g;
        o.bytes[3 * i + 2] = bg ? 60 : g;
    }
    save_image(o, path);
}
void save_diff(const Image& ao, const Image& ref, const std::string& path, float full_scale = 0.25f) {
    Image o;
    o.width = ao.width;
    o.height = ao.height;
    o.channels = 3;
    o.bytes.assign(std::size_t(o.width) * o.height * 3, 40);
    for (std::size_t i = 0; i < ao.floats.size(); ++i) {
        const float a = ao.floats[i], r = ref.floats[i];
        if (!std::isfinite(a) || !std::isfinite(r)) continue;
        const float d = std::clamp((a - r) / full_scale, -1.0f, 1.0f);
        o.bytes[3 * i] = std::uint8_t(255.0f * (d < 0 ? 1.0f : 1.0f - d));
        o.bytes[3 * i + 1] = std::uint8_t(255.0f * (1.0f - std::abs(d)));
        o.bytes[3 * i + 2] = std::uint8_t(255.0f * (d > 0 ? 1.0f : 1.0f + d));
    }
    save_image(o, path);
}

std::string fmt(double v, int prec = 3) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(prec) << v;
    return s.str();
}

struct ConeConfig {
    int cones, spheres, samples;
    double grid;
    int layers;
    double persistence;
    double bias = 1.0;
    int frames = 1;          // still frames accumulated (temporal jitter)
    double resolution = 1.0; // cone pass pixels per image pixel
    double strength = 1.0;
    double ray_weight = 0.5;
    int surface = -1; // ConeAoSettings::surface_voxels: 0 off, 1 on, -1 the renderer's default
    double axis = ConeAoSettings{}.axis_weight; // axis probes (default on)
};

std::string describe(const ConeConfig& c) {
    std::ostringstream s;
    s << c.cones << "c " << c.spheres << "s " << c.samples << "p grid " << c.grid << " L" << c.layers << " pers "
      << c.persistence;
    if (c.bias != 1.0) s << " bias " << c.bias;
    if (c.resolution != 1.0) s << " res " << c.resolution;
    if (c.strength != 1.0) s << " strength " << c.strength;
    s << " rw " << c.ray_weight;
    if (c.frames != 1) s << " x" << c.frames << " frames";
    if (c.surface == 0) s << " solid only";
    if (c.surface == 1) s << " surface voxels";
    s << " axis " << c.axis;
    return s.str();
}

// Time-vs-RMSE plots of an ao.csv, one panel per scene and AO radius: all
// panels in one picture (png_path) and each in its own file
// (<png_path stem>_<scene>_R<radius>.png). Filled marks for the first image
// size, open marks for the others; each method's frontier (the rows no faster
// row of that method beats) as a line; "no AO" as a dashed level. Every
// method with timed rows is drawn (cone, vtkSSAOPass, and whatever else a
// branch adds), the references and still-frame rows are not. Reads the CSV
// back, so `--replot` can redraw saved results; a CSV from before the radius
// column (13 fields) plots one panel per scene. Returns the files written.
std::vector<std::string> write_plot(const std::string& csv_path, const std::string& png_path) {
    struct P {
        std::string group, method;
        int size;
        double ms, rmse;
    };
    std::ifstream in(csv_path);
    if (!in) throw Error(csv_path, "cannot open the results to plot");
    std::string line;
    std::getline(in, line);
    if (line.rfind("scene,size,method,params,ao_ms,frame_ms,bias,mae,rmse", 0) != 0)
        throw Error(csv_path, "not an ao_bench CSV (header '" + line + "')");
    std::vector<P> pts;
    std::vector<std::string> groups, methods;
    std::map<std::string, double> none_rmse;
    std::map<std::string, std::string> group_file; // group -> file-name part
    std::vector<int> sizes;
    std::string renderer_name; // the optional 13th column
    for (int ln = 2; std::getline(in, line); ++ln) {
        if (line.empty()) continue;
        const std::vector<std::string> f = split(line);
        if (f.size() < 12)
            throw Error(csv_path,
                        "line " + std::to_string(ln) + ": expected 12 fields, got " + std::to_string(f.size()));
        std::string group = f[0], file = f[0];
        if (f.size() > 13 && !f[13].empty()) {
            const double r = std::stod(f[13]);
            group += ", R = " + fmt(r, r < 1 ? 4 : 0);
            file += "_R" + fmt(r, r < 1 ? 4 : 0);
        }
        P q{group, f[2], std::stoi(f[1]), std::stod(f[4]), std::stod(f[8])};
        if (!std::isfinite(q.ms) || !std::isfinite(q.rmse))
            throw Error(csv_path, "line " + std::to_string(ln) + ": non-finite time or RMSE");
        if (std::find(groups.begin(), groups.end(), group) == groups.end()) groups.push_back(group);
        group_file[group] = file;
        if (std::find(sizes.begin(), sizes.end(), q.size) == sizes.end()) sizes.push_back(q.size);
        if (f.size() > 12 && renderer_name.empty()) renderer_name = f[12];
        if (q.method == "none" && (!none_rmse.count(group) || q.size == sizes.front())) none_rmse[group] = q.rmse;
        const bool drawn = q.ms > 0 && q.method != "none" && q.method != "voxel-ref" && q.method != "cone-vs-voxel" &&
                           q.method != "cone-still";
        if (drawn && std::find(methods.begin(), methods.end(), q.method) == methods.end()) methods.push_back(q.method);
        pts.push_back(q);
    }
    if (pts.empty()) throw Error(csv_path, "no rows to plot");
    const std::string dat = fs::path(png_path).replace_extension(".dat").string();
    // One gnuplot data block per (group, size, method, points|front), addressed by index.
    std::ofstream d(dat);
    std::map<std::string, int> block;
    int nblock = 0;
    for (const auto& g : groups)
        for (int S : sizes)
            for (const auto& m : methods) {
                std::vector<P> v;
                for (const auto& q : pts)
                    if (q.group == g && q.size == S && q.method == m && q.ms > 0) v.push_back(q);
                std::sort(v.begin(), v.end(), [](const P& x, const P& y) { return x.ms < y.ms; });
                const std::string key = g + "|" + std::to_string(S) + "|" + m;
                d << "# " << key << " points\n";
                for (const auto& q : v) d << q.ms << " " << q.rmse << "\n";
                if (v.empty()) d << "nan nan\n";
                d << "\n\n# " << key << " front\n";
                double best = 1e30;
                bool any = false;
                for (const auto& q : v)
                    if (q.rmse < best) {
                        best = q.rmse;
                        d << q.ms << " " << q.rmse << "\n";
                        any = true;
                    }
                if (!any) d << "nan nan\n";
                d << "\n\n";
                block[key] = nblock;
                nblock += 2;
            }
    d.close();
    if (!d) throw Error(dat, "could not write the plot data");
    // colours: dark for the first size, light for the others; marks: filled / open
    const char* dark[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"};
    const char* light[] = {"#6baed6", "#fc9272", "#98df8a", "#c5b0d5", "#ffbb78"};
    const int filled[] = {7, 5, 9, 13, 11}, open[] = {6, 4, 8, 12, 10};
    auto panel = [&](std::ostream& gp, const std::string& g) {
        gp << "set title '" << g << "'\nplot ";
        bool first = true;
        for (size_t si = 0; si < sizes.size(); ++si)
            for (size_t mi = 0; mi < methods.size(); ++mi) {
                const int b = block[g + "|" + std::to_string(sizes[si]) + "|" + methods[mi]];
                const size_t c = mi % 5;
                const int pt = si == 0 ? filled[c] : open[c];
                const std::string lc = std::string("'") + (si == 0 ? dark[c] : light[c]) + "'";
                const std::string label = methods[mi] == "vtkSSAOPass" ? "SSAO" : methods[mi];
                gp << (first ? "" : ", ") << "'" << dat << "' index " << b << " with points pt " << pt
                   << " ps 1.2 lc rgb " << lc << " title '" << label << " " << sizes[si] << "', '" << dat << "' index "
                   << b + 1 << " with lines lc rgb " << lc << " notitle";
                first = false;
            }
        if (none_rmse.count(g))
            gp << (first ? "" : ", ") << none_rmse.at(g) << " with lines dt 2 lc rgb 'gray40' title 'no AO'";
        gp << "\n";
    };
    const std::string common = "set logscale x\nset grid\nset key bottom left\nset xlabel 'AO time per frame, ms'\nset "
                               "ylabel 'RMSE'\nset yrange [0:*]\n";
    const std::string title = "Ambient occlusion: run time against RMSE (Embree reference), " +
                              (renderer_name.empty() ? std::string("renderer not recorded") : renderer_name);
    std::vector<std::string> written;
    auto run_gnuplot = [&](const std::string& png, auto&& body) {
        const std::string gpp = fs::path(png).replace_extension(".gp").string();
        std::ofstream gp(gpp);
        body(gp);
        gp.close();
        if (!gp) throw Error(gpp, "could not write the gnuplot script");
        if (std::system(("gnuplot '" + gpp + "'").c_str()) != 0) throw Error(gpp, "gnuplot failed");
        written.push_back(png);
    };
    // All panels: up to 4 per row.
    const int cols = int(std::min<size_t>(groups.size(), 4)), rows_n = int((groups.size() + 3) / 4);
    run_gnuplot(png_path, [&](std::ostream& gp) {
        gp << "set terminal pngcairo size " << 520 * cols + 80 << "," << 620 * rows_n << " font ',10'\nset output '"
           << png_path << "'\n"
           << "set multiplot layout " << rows_n << "," << cols << " title '" << title << "'\n"
           << common;
        for (const auto& g : groups) panel(gp, g);
        gp << "unset multiplot\n";
    });
    // One file per scene and radius.
    for (const auto& g : groups) {
        const std::string png =
            (fs::path(png_path).parent_path() / (fs::path(png_path).stem().string() + "_" + group_file[g] + ".png"))
                .string();
        run_gnuplot(png, [&](std::ostream& gp) {
            gp << "set terminal pngcairo size 640,560 font ',10'\nset output '" << png << "'\n"
               << common << "set label 1 '" << renderer_name << "' at graph 0.02, graph 0.97 font ',8'\n";
            panel(gp, g);
        });
    }
    return written;
}
} // namespace

int main(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        std::string s = argv[i];
        auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
        if (s == "--out")
            a.out = next();
        else if (s == "--quick")
            a.quick = true;
        else if (s == "--sizes") {
            a.sizes.clear();
            for (auto& t : split(next())) a.sizes.push_back(std::stoi(t));
        } else if (s == "--scenes")
            a.scenes = split(next());
        else if (s == "--radii") {
            a.radii.clear();
            for (auto& t : split(next())) a.radii.push_back(std::stod(t));
        } else if (s == "--rays")
            a.rays = std::stoi(next());
        else if (s == "--reps")
            a.reps = std::stoi(next());
        else if (s == "--ssao")
            a.ssao = next();
        else if (s == "--data")
            a.data = next();
        else if (s == "--voxel-ref")
            a.voxel_ref_each = true;
        else if (s == "--disk")
            a.disk = next();
        else if (s == "--replot")
            a.replot = next();
        else if (s == "--config")
            a.configs.push_back(
                next()); // cones,spheres,samples,grid,layers,persistence[,bias[,frames[,resolution[,strength[,ray_weight[,surface_voxels[,axis_weight]]]]]]]
        else {
            std::cerr << "usage: ao_bench [--quick] [--out DIR] [--sizes 512,1024] [--scenes "
                         "ct-skin,ct-bone,bunny,thin] [--radii 10,20] [--rays N] "
                         "[--reps N] [--ssao PATH|none] [--config C ...] [--voxel-ref] [--replot CSV]\n";
            return 2;
        }
    }
    if (a.quick) {
        a.sizes = {256};
        a.rays = 256;
        a.reps = 2;
    }
    try {
        fs::create_directories(a.out);
        if (!a.replot.empty()) {
            for (const auto& f : write_plot(a.replot, a.out + "/ao_time_rmse.png")) std::cout << "wrote " << f << "\n";
            return 0;
        }
        gl::HeadlessContext ctx;
        ctx.make_current();
        // cones, spheres, samples, grid, layers, persistence, bias, frames, resolution, strength, ray weight
        std::vector<ConeConfig> configs = {
            // the defaults' estimator (ray weight 0.5, persistence 1), coarse cone pass
            {4, 2, 4, 0.25, 1, 1.0, 1, 1, 0.25, 1, 0.5},
            {3, 1, 4, 0.25, 1, 1.0, 1, 1, 0.5, 1, 0.5},
            {4, 3, 4, 0.5, 1, 1.0, 1, 1, 0.5, 1, 0.5},
            {6, 4, 6, 1.0, 2, 1.0, 1, 1, 0.5, 1, 0.5},
            {8, 5, 8, 1.0, 2, 1.0, 1, 1, 0.5, 1, 0.5}, // the defaults
            {16, 8, 16, 1.0, 4, 1.0, 1, 1, 0.5, 1, 0.5},
            // every pixel traced
            {3, 2, 3, 0.5, 1, 1.0, 1, 1, 1, 1, 0.5},
            {8, 5, 8, 1.0, 2, 1.0, 1, 1, 1, 1, 0.5},
            {16, 8, 16, 1.0, 4, 1.0, 1, 1, 1, 1, 0.5},
            // the thesis's volume fraction, and other combinations
            {8, 5, 8, 1.0, 2, 0.5, 1, 1, 1, 1, 0.0},
            {8, 5, 8, 1.0, 2, 0.5, 1, 1, 0.5, 1, 0.0},
            {8, 5, 8, 1.0, 2, 0.5, 1, 1, 0.5, 1, 0.5},
            {8, 5, 8, 1.0, 2, 1.0, 1, 1, 0.5, 1, 1.0},
            {8, 5, 8, 1.0, 2, 0.0, 1, 1, 0.5, 1, 0.5},
            // cheap settings with ray weight 1 (the thin bone walls lost by the
            // voxelization favour it; the bulky bunny does not)
            {3, 1, 4, 0.25, 1, 1.0, 1, 1, 0.5, 1, 1.0},
            {4, 2, 4, 0.25, 1, 1.0, 1, 1, 0.35, 1, 1.0},
            {4, 3, 4, 0.5, 1, 1.0, 1, 1, 0.5, 1, 1.0},
            // thin structures (docs/ao.md "Thin structures"): every
            // row above has the default axis probes; here surface voxels, and
            // the defaults and a cheap setting without the probes
            {8, 5, 8, 1.0, 2, 1.0, 1, 1, 0.5, 1, 0.5, 1},
            {8, 5, 8, 1.0, 2, 1.0, 1, 1, 0.5, 1, 0.5, -1, 0.0},
            {4, 3, 4, 0.5, 1, 1.0, 1, 1, 0.5, 1, 0.5, -1, 0.0},
        };
        std::vector<int> kernels = {8, 16, 32, 64, 128};
        if (a.quick) {
            configs = {{4, 3, 4, 0.5, 1, 1.0, 1, 1, 0.5, 1, 0.5}, {8, 5, 8, 1.0, 2, 1.0, 1, 1, 0.5, 1, 0.5}};
            kernels = {16, 64};
        }
        if (!a.configs.empty()) {
            configs.clear();
            for (const auto& c : a.configs) {
                ConeConfig k{};
                k.bias = 1.0;
                k.frames = 1;
                k.resolution = 1.0;
                k.strength = 1.0;
                k.ray_weight = 0.5;
                k.surface = -1;
                k.axis = ConeAoSettings{}.axis_weight;
                const int got = std::sscanf(c.c_str(), "%d,%d,%d,%lf,%d,%lf,%lf,%d,%lf,%lf,%lf,%d,%lf", &k.cones,
                                            &k.spheres, &k.samples, &k.grid, &k.layers, &k.persistence, &k.bias,
                                            &k.frames, &k.resolution, &k.strength, &k.ray_weight, &k.surface, &k.axis);
                if (got < 6 || k.frames < 1)
                    throw Error("--config", "expected "
                                            "cones,spheres,samples,grid,layers,persistence[,bias[,frames[,resolution[,"
                                            "strength[,ray_weight[,surface_voxels[,axis_weight]]]]]]], got '" +
                                                c + "'");
                configs.push_back(k);
            }
        }
        std::vector<Row> all;
        std::string renderer_name;
        for (const auto& scene_name : a.scenes) {
            Scene sc = make_scene(scene_name, a);
            for (const double radius_mm : a.radii)
                for (int S : a.sizes) {
                    sc.radius_mm = radius_mm;
                    // CT scenes: mm; the bunny (units of ~metres/10): a tenth of its size per 10 mm.
                    sc.radius = sc.name == "bunny" ? 0.1 * sc.size * radius_mm / 10.0 : radius_mm;
                    // picture names: the radius appears only when it is not the target's 10
                    const std::string stem_r = radius_mm == 10.0 ? "" : "_R" + fmt(radius_mm, 0);
                    std::cerr << "[ao_bench] " << sc.name << " R " << sc.radius << " " << S << "x" << S
                              << ": reference (" << a.rays << " rays)\n";
                    // The reference through the core API: same camera as the CLI, cached.
                    core::RenderRequest rq;
                    rq.isos = sc.isos;
                    rq.view = sc.view;
                    rq.width = rq.height = S;
                    rq.aov = Aov::Ao;
                    rq.look.ao = AoMethod::Raytraced;
                    rq.look.cone.radius_mm = sc.radius;
                    rq.look.ao_rays = a.rays;
                    const auto ref = core::render_input(sc.input, rq);
                    const Camera cam = ref.camera;
                    renderer_name = ref.gl_renderer;

                    Renderer ren;
                    for (const auto& m : sc.meshes) ren.add(m, {});
                    std::vector<Row> rows;
                    auto add_row = [&](const std::string& method, const std::string& params, double ao_ms,
                                       double frame_ms, const Image& img) {
                        Row r{sc.name, method, params, S, sc.radius, ao_ms, frame_ms, ao_error(img, ref.image, a.rays)};
                        rows.push_back(r);
                    };
                    {
                        Image ones = ref.image;
                        for (auto& v : ones.floats)
                            if (std::isfinite(v)) v = 1.0f;
                        add_row("none", "AO = 1", 0, 0, ones);
                    }
                    // Cone AO sweep.
                    for (const auto& c : configs) {
                        RenderOptions ro;
                        RenderHooks hooks;
                        ro.width = ro.height = S;
                        ro.aov = Aov::Ao;
                        ro.look.ao = AoMethod::Cone;
                        ro.look.cone.radius_mm = sc.radius;
                        ro.look.cone.cones = c.cones;
                        ro.look.cone.spheres = c.spheres;
                        ro.look.cone.samples = c.samples;
                        ro.look.cone.grid_scale = c.grid;
                        ro.look.cone.layers = c.layers;
                        ro.look.cone.persistence = c.persistence;
                        ro.look.cone.bias = c.bias;
                        ro.look.cone.resolution = c.resolution;
                        ro.look.cone.strength = c.strength;
                        ro.look.cone.ray_weight = c.ray_weight;
                        if (c.surface >= 0) ro.look.cone.surface_voxels = c.surface != 0;
                        ro.look.cone.axis_weight = c.axis;
                        ro.look.cone.temporal = c.frames > 1;
                        ro.time_passes = true;
                        Image img;
                        std::vector<double> ao_ms, frame_ms;
                        std::map<std::string, std::vector<double>> pass_ms;
                        for (int rep = 0; rep < a.reps + 1; ++rep) {
                            hooks.ao_force_voxelize = true;
                            for (int f = 1; f < c.frames; ++f) { // earlier still frames (not timed)
                                ren.render(cam, ro, hooks);
                                hooks.ao_force_voxelize = false;
                            }
                            auto r = ren.render(cam, ro, hooks);
                            double ao = 0, total = 0;
                            for (const auto& p : r.stats.passes) {
                                if (!p.ran) continue;
                                total += p.ms;
                                if (p.name == "zrange" || p.name == "voxelize" || p.name == "cone_ao" ||
                                    p.name == "ao_upsample") {
                                    ao += p.ms;
                                    if (rep > 0) pass_ms[p.name].push_back(p.ms);
                                }
                            }
                            if (rep > 0) { // the first frame compiles shaders
                                ao_ms.push_back(ao);
                                frame_ms.push_back(total);
                            }
                            img = std::move(r.image);
                        }
                        std::cerr << "[ao_bench]   " << describe(c) << ":";
                        for (auto& [name, v] : pass_ms)
                            std::cerr << " " << name << " " << fmt(bench::median(v), 1) << " ms";
                        std::cerr << "\n";
                        add_row("cone", describe(c), bench::median(ao_ms), bench::median(frame_ms), img);
                    }
                    // Default settings, still camera, temporal accumulation of 8 frames.
                    if (a.configs.empty()) {
                        RenderOptions ro;
                        RenderHooks hooks;
                        ro.width = ro.height = S;
                        ro.aov = Aov::Ao;
                        ro.look.ao = AoMethod::Cone;
                        ro.look.cone.radius_mm = sc.radius;
                        ro.time_passes = true;
                        Image img;
                        double ao_sum = 0;
                        const int frames = 8;
                        ren.render(cam, ro, hooks); // warm-up; then a new view starts the accumulation
                        hooks.ao_force_voxelize = true;
                        for (int f = 0; f < frames; ++f) {
                            auto r = ren.render(cam, ro, hooks);
                            hooks.ao_force_voxelize = false;
                            for (const auto& p : r.stats.passes)
                                if (p.ran && (p.name == "zrange" || p.name == "voxelize" || p.name == "cone_ao" ||
                                              p.name == "ao_upsample"))
                                    ao_sum += p.ms;
                            img = std::move(r.image);
                        }
                        add_row("cone-still", "default; 8 still frames accumulated (time: all 8)", ao_sum, 0, img);
                        const std::string stem = a.out + "/" + sc.name + "_" + std::to_string(S) + stem_r;
                        save_grey(ref.image, stem + "_reference.png");
                        save_grey(img, stem + "_cone.png");
                        save_diff(img, ref.image, stem + "_cone_minus_reference.png");
                    }
                    // ---- Disk AO (docs/ao.md, "Disk AO on the GPU") ----
                    // Default settings, then a small sweep of the element passes and
                    // the traversal epsilon. Each timed frame starts from scratch
                    // (the meshes replaced, so the hierarchy is rebuilt): AO ms =
                    // disk_build (CPU build + upload) + disk_elements + disk_gather;
                    // the split goes into the parameters column. A new view of the
                    // same scene costs the gather alone.
                    if (a.disk != "none") {
                        struct DiskConfig {
                            int passes;
                            double epsilon, t = 1.0, min_scale = 0.7;
                        };
                        // Default (no element passes, epsilon 16); epsilon 8 (the
                        // chapter's) and 32; two element passes as the CPU
                        // benchmark measured best (t = 0.1, min 1) and as the
                        // chapter gives them (t = 1, 0.7 / 0.3).
                        const DiskAoSettings defaults;
                        std::vector<DiskConfig> dcs{{defaults.passes, defaults.traversal_epsilon}};
                        if (a.disk == "sweep")
                            dcs.insert(dcs.end(), {{0, 8.0}, {0, 32.0}, {2, 16.0, 0.1, 1.0}, {2, 8.0}});
                        for (const auto& dc : dcs) {
                            RenderOptions ro;
                            ro.width = ro.height = S;
                            ro.aov = Aov::Ao;
                            ro.look.ao = AoMethod::Disk;
                            ro.look.cone.radius_mm = sc.radius;
                            ro.look.disk.passes = dc.passes;
                            ro.look.disk.traversal_epsilon = dc.epsilon;
                            ro.look.disk.triangle_attenuation = dc.t;
                            ro.look.disk.min_scale = dc.min_scale;
                            ro.look.disk.max_scale = 1.0 - dc.min_scale;
                            ro.time_passes = true;
                            Image img;
                            std::map<std::string, std::vector<double>> ms;
                            for (int rep = 0; rep < a.reps + 1; ++rep) {
                                for (std::size_t m = 0; m < sc.meshes.size(); ++m)
                                    ren.replace(std::uint32_t(m + 1), sc.meshes[m]);
                                auto r = ren.render(cam, ro);
                                if (rep > 0) { // the first frame compiles shaders
                                    double total = 0;
                                    for (const auto& p : r.stats.passes)
                                        if (p.ran && p.name.rfind("disk_", 0) == 0) {
                                            ms[p.name].push_back(p.ms);
                                            total += p.ms;
                                        }
                                    ms["build"].push_back(r.disk_build_ms);
                                    ms["total"].push_back(total);
                                }
                                img = std::move(r.image);
                            }
                            const double build = bench::median(ms["build"]);
                            const double upload = std::max(0.0, bench::median(ms["disk_build"]) - build);
                            std::ostringstream params;
                            params << "passes " << dc.passes << " eps " << dc.epsilon;
                            if (dc.passes > 0) params << " t " << dc.t << " min " << dc.min_scale;
                            params << " (build " << fmt(build, 1) << " + upload " << fmt(upload, 1) << " + elements "
                                   << fmt(bench::median(ms["disk_elements"]), 1) << " + gather "
                                   << fmt(bench::median(ms["disk_gather"]), 1) << " ms)";
                            std::cerr << "[ao_bench]   disk " << params.str() << "\n";
                            add_row("disk", params.str(), bench::median(ms["total"]), 0, img);
                            if (dc.passes == defaults.passes && dc.epsilon == defaults.traversal_epsilon) {
                                const std::string stem = a.out + "/" + sc.name + "_" + std::to_string(S) + stem_r;
                                save_grey(img, stem + "_disk.png");
                                save_diff(img, ref.image, stem + "_disk_minus_reference.png");
                            }
                        }
                    }
                    // The voxel-grid reference (default grid, or each --config's
                    // grid, layers and bias with --voxel-ref), on every 4th pixel.
                    {
                        std::vector<ConeConfig> vcs;
                        if (a.configs.empty())
                            vcs.push_back(ConeConfig{8, 5, 8, 1.0, 2, 1.0, 1, 1, 0.5, 1, 0.5});
                        else if (a.voxel_ref_each)
                            vcs = configs;
                        for (const auto& vc : vcs) {
                            RenderOptions ro;
                            RenderHooks hooks;
                            ro.width = ro.height = S;
                            ro.aov = Aov::Ao;
                            ro.look.ao = AoMethod::Cone;
                            ro.look.cone.radius_mm = sc.radius;
                            ro.look.cone.grid_scale = vc.grid;
                            ro.look.cone.layers = vc.layers;
                            ro.look.cone.bias = vc.bias;
                            if (vc.surface >= 0) ro.look.cone.surface_voxels = vc.surface != 0;
                            hooks.ao_force_voxelize = true;
                            hooks.read_slicemap = true;
                            auto r = ren.render(cam, ro, hooks);
                            RenderOptions d;
                            d.width = d.height = S;
                            d.aov = Aov::Depth;
                            const Image depth = ren.render(cam, d).image;
                            d.aov = Aov::Normal;
                            const Image normal = ren.render(cam, d).image;
                            AoReferenceOptions vo;
                            vo.radius_mm = sc.radius;
                            vo.rays = std::min(a.rays, 256);
                            const double t0 = bench::now_s();
                            const Image vox =
                                voxel_ao_image(r.slicemap, cam, depth, normal, vo, vc.bias, a.quick ? 2 : 4);
                            const double t1 = bench::now_s();
                            if (a.configs.empty()) {
                                add_row("voxel-ref", "rays through the default slicemap (every 4th px, CPU)", 0,
                                        (t1 - t0) * 1e3, vox);
                                // Cone error alone: cone (default) against the voxel reference.
                                Row cr{sc.name,
                                       "cone-vs-voxel",
                                       "default cone AO against the voxel reference",
                                       S,
                                       sc.radius,
                                       0,
                                       0,
                                       ao_error(r.image, vox, vo.rays)};
                                rows.push_back(cr);
                            } else {
                                std::ostringstream pr;
                                pr << "grid " << vc.grid << " L" << vc.layers << " bias " << vc.bias
                                   << " (every 4th px, CPU)";
                                add_row("voxel-ref", pr.str(), 0, (t1 - t0) * 1e3, vox);
                            }
                        }
                    }
                    // VTK's SSAO, same meshes and camera, under Xvfb.
                    if (a.ssao != "none" && fs::exists(a.ssao)) {
                        std::vector<std::string> files;
                        for (std::size_t m = 0; m < sc.meshes.size(); ++m) {
                            files.push_back(a.out + "/" + sc.name + "_" + std::to_string(m) + ".ply");
                            if (!fs::exists(files.back())) save_mesh(sc.meshes[m], files.back());
                        }
                        auto v3 = [](const glm::dvec3& v) {
                            std::ostringstream s;
                            s.precision(17);
                            s << v.x << "," << v.y << "," << v.z;
                            return s.str();
                        };
                        struct SsaoRun {
                            double radius, bias;
                            int kernel;
                            std::string label;
                        };
                        std::vector<SsaoRun> runs;
                        for (int k : kernels) runs.push_back({sc.radius, 0.001 * sc.size, k, "radius R"});
                        runs.push_back({0.1 * sc.size, 0.001 * sc.size, 32, "radius 0.1 x scene (Kitware's advice)"});
                        for (const auto& run : runs) {
                            std::ostringstream cmd;
                            cmd.precision(17);
                            const std::string out_exr = a.out + "/ssao_" + sc.name + stem_r + ".exr";
                            cmd << "xvfb-run -a -s '-screen 0 " << std::max(S + 64, 1280) << "x"
                                << std::max(S + 64, 1024) << "x24' " << a.ssao;
                            for (const auto& f : files) cmd << " --mesh " << f;
                            cmd << " --eye " << v3(cam.eye) << " --target " << v3(cam.target) << " --up " << v3(cam.up)
                                << " --fov " << cam.fov_y_degrees << " --near " << cam.near_plane << " --far "
                                << cam.far_plane << " --size " << S << "x" << S << " --radius " << run.radius
                                << " --bias " << run.bias << " --kernel " << run.kernel << " --frames "
                                << std::max(5, a.reps * 2) << " --out " << out_exr << " 2>/dev/null";
                            const std::string line = bench::capture(cmd.str());
                            try {
                                const auto j = nlohmann::json::parse(line.substr(line.find('{')));
                                const Image img = load_image(out_exr);
                                if (run.kernel == 32 && run.label == "radius R") {
                                    const std::string stem = a.out + "/" + sc.name + "_" + std::to_string(S) + stem_r;
                                    save_grey(img, stem + "_ssao.png");
                                    save_diff(img, ref.image, stem + "_ssao_minus_reference.png");
                                }
                                const double ms = j.at("ms_median").get<double>(),
                                             plain = j.at("ms_plain_median").get<double>();
                                add_row("vtkSSAOPass",
                                        "kernel " + std::to_string(run.kernel) + ", " + run.label + " " +
                                            fmt(run.radius, 4) + ", bias " + fmt(run.bias, 5),
                                        std::max(0.0, ms - plain), ms, img);
                            } catch (const std::exception& e) {
                                std::cerr << "[ao_bench] ssao_peer failed (" << e.what() << "): " << line << "\n";
                            }
                        }
                    } else if (a.ssao != "none") {
                        std::cerr << "[ao_bench] no ssao_peer at " << a.ssao << ": VTK's SSAO not measured\n";
                    }
                    // Pareto over the methods that give a per-frame AO (not the references, not the CPU voxel tracer).
                    std::vector<Row> contenders;
                    for (const auto& r : rows)
                        if (r.method == "cone" || r.method == "vtkSSAOPass" || r.method == "none")
                            contenders.push_back(r);
                    mark_pareto(contenders);
                    for (auto& r : rows)
                        for (const auto& c : contenders)
                            if (c.method == r.method && c.params == r.params) r.pareto = c.pareto;
                    std::cout << "\n### " << sc.name << ", " << S << "x" << S << ", R = " << fmt(sc.radius, 4)
                              << " (reference: " << a.rays << " rays/px, own noise RMS "
                              << fmt(rows[0].err.reference_noise_rms, 4) << "; " << rows[0].err.pixels
                              << " foreground px)\n\n";
                    std::cout << "| method | parameters | AO ms | frame ms | bias | MAE | RMSE | p95 | p99 | Pareto |\n"
                              << "|---|---|---:|---:|---:|---:|---:|---:|---:|:-:|\n";
                    for (const auto& r : rows)
                        std::cout << "| " << r.method << " | " << r.params << " | " << fmt(r.ao_ms, 1) << " | "
                                  << fmt(r.frame_ms, 1) << " | " << fmt(r.err.bias) << " | " << fmt(r.err.mae) << " | "
                                  << fmt(r.err.rmse) << " | " << fmt(r.err.p95) << " | " << fmt(r.err.p99) << " | "
                                  << (r.pareto ? "*" : "") << " |\n";
                    std::cout.flush();
                    all.insert(all.end(), rows.begin(), rows.end());
                }
        }
        std::cout << "\nrenderer: " << renderer_name
                  << "; AO ms: zrange + voxelize + cone_ao (+ ao_upsample) passes (cone), frame with SSAO minus "
                     "frame without (vtkSSAOPass); glFinish after each pass; median of "
                  << a.reps << " frames\n";
        std::ofstream csv(a.out + "/ao.csv");
        csv << "scene,size,method,params,ao_ms,frame_ms,bias,mae,rmse,p95,p99,pareto,renderer,radius\n";
        for (const auto& r : all)
            csv << r.scene << "," << r.size << "," << r.method << "," << no_commas(r.params) << "," << r.ao_ms << ","
                << r.frame_ms << "," << r.err.bias << "," << r.err.mae << "," << r.err.rmse << "," << r.err.p95 << ","
                << r.err.p99 << "," << r.pareto << "," << no_commas(renderer_name) << "," << r.radius << "\n";
        // Closed before gnuplot reads it: an open stream holds the last rows in its buffer
        // (a small run plotted nothing, a large one lost its last rows).
        csv.close();
        if (!csv) throw Error(a.out + "/ao.csv", "could not write the results");
        if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
            for (const auto& f : write_plot(a.out + "/ao.csv", a.out + "/ao_time_rmse.png"))
                std::cerr << "[ao_bench] wrote " << f << "\n";
        } else
            std::cerr << "[ao_bench] gnuplot not found: no plot\n";
    } catch (const std::exception& e) {
        std::cerr << "ao_bench: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
