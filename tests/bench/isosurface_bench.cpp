// Isosurface benchmark: our chunked marching cubes against
// vtkFlyingEdges3D and OpenVDB's volumeToMesh on the same volume, iso value
// and thread count, each measurement in its own child process.
//
//   isosurface_bench [--out DIR] [--size 512x512x400] [--reps 3] [--quick]
//
// Prints tables (markdown) and writes DIR/isosurface.csv and, when gnuplot is
// installed, DIR/isosurface_chunks.png and DIR/isosurface_methods.png.
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <tbb/global_control.h>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkShortArray.h>

#include "bench_util.hpp"
#include "ct_phantom.hpp"
#include "vtk_volume.hpp"
#include "io/volume_io.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/gpu/gpu_extract.hpp"

using namespace iso;
using namespace iso::bench;
namespace fs = std::filesystem;

namespace iso::bench {
void set_vtk_threads(int n); // vtk_threads.cpp
}

namespace {

struct Args {
    std::string out = "bench-results";
    std::array<std::int64_t, 3> size{512, 512, 400};
    int reps = 3;
    bool quick = false;
    // child mode
    std::string one, data;
    double iso = 0;
    int threads = 1, chunk = 32;
};

// The phantom takes seconds to make: children share a cached raw copy.
Volume load_data(const std::string& data, const std::array<std::int64_t, 3>& size) {
    if (data != "phantom") return load_volume(data);
    return cached_ct_phantom(size);
}

// Child: one method, several repetitions, one RESULT line.
int run_one(const Args& a) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(a.threads));
    set_vtk_threads(a.threads);
    openvdb::initialize();
    Volume v = load_data(a.data, a.size);
    if (v.type != VoxelType::I16 && a.one == "fe") throw Error(a.data, "benchmark expects int16 data");
    const std::size_t base = current_rss();
    reset_peak_rss();
    std::vector<double> times, t_index, t_extract, t_weld;
    std::size_t tris = 0, verts = 0, visited = 0, total = 0, scratch = 0;
    for (int r = 0; r < a.reps; ++r) {
        const double t0 = now_s();
        if (a.one == "ours" || a.one == "ours-warm") {
            ExtractOptions opt;
            opt.chunk_size = a.chunk;
            opt.threads = a.threads;
            opt.memory_budget = std::size_t(1) << 30;
            const double ti = now_s();
            Extractor x(v, opt);
            const double te = now_s();
            ExtractStats st;
            auto s = x.extract(a.iso, &st);
            const double tw = now_s();
            Mesh m = weld(s, a.threads);
            const double tend = now_s();
            t_index.push_back(te - ti);
            t_extract.push_back(tw - te);
            t_weld.push_back(tend - tw);
            tris = m.triangles.size();
            verts = m.positions.size();
            visited = st.chunks_visited;
            total = st.chunks_total;
            scratch = st.peak_scratch_bytes;
            times.push_back(a.one == "ours" ? tend - t0 : tend - te);
        } else if (a.one == "gpu") {
            static gl::HeadlessContext ctx(false);
            if (r == 0) std::cerr << "GL renderer: " << ctx.info().renderer << "\n";
            ExtractOptions opt;
            opt.chunk_size = a.chunk;
            opt.threads = a.threads;
            opt.memory_budget = std::size_t(1) << 30;
            GpuExtractor x(v, opt); // builds the chunk index on the CPU
            const double te = now_s();
            auto s = x.extract(a.iso);
            glFinish();
            const double tw = now_s();
            Mesh m = weld(s, a.threads);
            const double tend = now_s();
            t_index.push_back(te - t0);
            t_extract.push_back(tw - te);
            t_weld.push_back(tend - tw);
            times.push_back(tend - t0);
            tris = m.triangles.size();
            verts = m.positions.size();
        } else if (a.one == "fe") {
            auto img = as_vtk(v);
            vtkNew<vtkFlyingEdges3D> fe;
            fe->SetInputData(img);
            fe->SetValue(0, a.iso);
            fe->ComputeNormalsOn();
            fe->ComputeGradientsOff();
            fe->ComputeScalarsOff();
            fe->Update();
            times.push_back(now_s() - t0);
            tris = std::size_t(fe->GetOutput()->GetNumberOfCells());
            verts = std::size_t(fe->GetOutput()->GetNumberOfPoints());
        } else if (a.one == "vdb") {
            openvdb::tools::Dense<const std::int16_t, openvdb::tools::LayoutXYZ> dense(
                openvdb::CoordBBox(openvdb::Coord(0),
                                   openvdb::Coord(int(v.dims[0]) - 1, int(v.dims[1]) - 1, int(v.dims[2]) - 1)),
                v.as<std::int16_t>().data());
            auto grid = openvdb::FloatGrid::create(-1024.0f);
            openvdb::tools::copyFromDense(dense, *grid, 0.0f);
            std::vector<openvdb::Vec3s> pts;
            std::vector<openvdb::Vec3I> trisv;
            std::vector<openvdb::Vec4I> quads;
            openvdb::tools::volumeToMesh(*grid, pts, trisv, quads, a.iso, 0.0);
            times.push_back(now_s() - t0);
            tris = trisv.size() + 2 * quads.size();
            verts = pts.size();
        } else {
            throw Error("isosurface_bench", "unknown method " + a.one);
        }
    }
    std::cout << std::setprecision(6) << "RESULT ms=" << 1e3 * median(times) << " tris=" << tris << " verts=" << verts
              << " extra_mb=" << double(peak_rss() > base ? peak_rss() - base : 0) / (1 << 20);
    if (a.one == "gpu")
        std::cout << " index_ms=" << 1e3 * median(t_index) << " extract_ms=" << 1e3 * median(t_extract)
                  << " weld_ms=" << 1e3 * median(t_weld);
    else if (!t_index.empty())
        std::cout << " index_ms=" << 1e3 * median(t_index) << " extract_ms=" << 1e3 * median(t_extract)
                  << " weld_ms=" << 1e3 * median(t_weld) << " visited=" << visited << " chunks=" << total
                  << " scratch_mb=" << double(scratch) / (1 << 20);
    std::cout << "\n";
    return 0;
}

// Child: incremental re-extraction of a 32^3 edit against a full extraction.
int run_incremental(const Args& a) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(a.threads));
    Volume v = load_data(a.data, a.size);
    ExtractOptions opt;
    opt.chunk_size = a.chunk;
    opt.threads = a.threads;
    Extractor x(v, opt);
    std::vector<double> full, full_weld, inc;
    auto surf = x.extract(a.iso);
    std::size_t redone = 0;
    for (int r = 0; r < std::max(a.reps, 5); ++r) {
        double t0 = now_s();
        auto s = x.extract(a.iso);
        full.push_back(now_s() - t0);
        t0 = now_s();
        Mesh m = weld(s, a.threads);
        full_weld.push_back(full.back() + now_s() - t0);
        // The edit: a 32^3 box on the body surface set to bone (a "paint" stroke), different each rep.
        IndexBox box;
        const std::int64_t off = 8 * r;
        box.lo = {v.dims[0] / 2 - 16 + off, std::int64_t(v.dims[1] * 0.14) - 16, v.dims[2] / 2 - 16};
        for (int k = 0; k < 3; ++k) box.hi[k] = box.lo[k] + 31;
        for (auto kk = box.lo[2]; kk <= box.hi[2]; ++kk)
            for (auto jj = box.lo[1]; jj <= box.hi[1]; ++jj)
                for (auto ii = box.lo[0]; ii <= box.hi[0]; ++ii)
                    v.as<std::int16_t>()[v.linear_index(ii, jj, kk)] = std::int16_t(1200 + 10 * r);
        t0 = now_s();
        std::span<ChunkedSurface> one(&surf, 1);
        redone = x.update(box, one).size();
        inc.push_back(now_s() - t0);
    }
    std::cout << std::setprecision(6) << "RESULT full_ms=" << 1e3 * median(full)
              << " full_weld_ms=" << 1e3 * median(full_weld) << " inc_ms=" << 1e3 * median(inc) << " redone=" << redone
              << " chunks=" << x.index().chunk_count() << "\n";
    return 0;
}

std::map<std::string, double> parse(const std::string& out) {
    std::map<std::string, double> r;
    const auto pos = out.find("RESULT ");
    if (pos == std::string::npos) return r;
    std::istringstream is(out.substr(pos + 7));
    std::string kv;
    while (is >> kv) {
        const auto eq = kv.find('=');
        if (eq != std::string::npos) r[kv.substr(0, eq)] = std::stod(kv.substr(eq + 1));
    }
    return r;
}

} // namespace

int main(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        std::string s = argv[i];
        auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
        if (s == "--out")
            a.out = next();
        else if (s == "--reps")
            a.reps = std::stoi(next());
        else if (s == "--quick")
            a.quick = true;
        else if (s == "--size") {
            const std::string v = next();
            std::sscanf(v.c_str(), "%ldx%ldx%ld", &a.size[0], &a.size[1], &a.size[2]);
        } else if (s == "--one")
            a.one = next();
        else if (s == "--data")
            a.data = next();
        else if (s == "--iso")
            a.iso = std::stod(next());
        else if (s == "--threads")
            a.threads = std::stoi(next());
        else if (s == "--chunk")
            a.chunk = std::stoi(next());
        else {
            std::cerr << "usage: isosurface_bench [--out DIR] [--size WxHxD] [--reps N] [--quick]\n";
            return 2;
        }
    }
    try {
        if (a.one == "incremental") return run_incremental(a);
        if (!a.one.empty()) return run_one(a);
    } catch (const std::exception& e) {
        std::cerr << "isosurface_bench: " << e.what() << "\n";
        return 1;
    }

    // Driver.
    fs::create_directories(a.out);
    const std::string self = fs::canonical("/proc/self/exe").string();
    const std::string size =
        std::to_string(a.size[0]) + "x" + std::to_string(a.size[1]) + "x" + std::to_string(a.size[2]);
    auto child = [&](const std::string& method, const std::string& data, double iso, int threads, int chunk) {
        std::ostringstream cmd;
        cmd << self << " --one " << method << " --data '" << data << "' --iso " << iso << " --threads " << threads
            << " --chunk " << chunk << " --size " << size << " --reps " << a.reps;
        return parse(capture(cmd.str()));
    };
    std::ofstream csv(a.out + "/isosurface.csv");
    std::ofstream dat(a.out + "/isosurface_methods.dat"); // for the clustered bar plot
    dat << "case ours FlyingEdges OpenVDB\n";
    csv << "table,data,iso,method,threads,chunk,ms,tris,extra_mb\n";

    const std::string bundled = std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr";
    struct Case {
        std::string name, data;
        double iso;
    };
    std::vector<Case> cases = {{"headsq skin (64x64x93)", bundled, 500.0},
                               {"headsq bone (64x64x93)", bundled, 1150.0},
                               {"phantom skin (" + size + ")", "phantom", -500.0},
                               {"phantom bone (" + size + ")", "phantom", 400.0}};
    // Warm the phantom cache once.
    child("ours", "phantom", 0.0, 2, 32);

    std::cout << "## Extraction: ours vs vtkFlyingEdges3D vs OpenVDB volumeToMesh (normals on; median of " << a.reps
              << " runs; extra = peak RSS beyond the loaded volume)\n\n";
    std::cout << "| data | threads | ours ms | FE ms | VDB ms | FE/ours | ours tris | FE tris | VDB tris | ours extra "
                 "MiB | FE extra MiB | VDB extra MiB |\n";
    std::cout << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : cases) {
        for (int t : {1, 2}) {
            const auto o = child("ours", c.data, c.iso, t, 32);
            const auto f = child("fe", c.data, c.iso, t, 32);
            const auto d = a.quick ? std::map<std::string, double>{} : child("vdb", c.data, c.iso, t, 32);
            std::cout << std::fixed << std::setprecision(1) << "| " << c.name << " | " << t << " | " << o.at("ms")
                      << " | " << f.at("ms") << " | " << (d.count("ms") ? d.at("ms") : 0.0) << " | "
                      << std::setprecision(2) << f.at("ms") / o.at("ms") << "x | " << std::setprecision(0)
                      << o.at("tris") << " | " << f.at("tris") << " | " << (d.count("tris") ? d.at("tris") : 0.0)
                      << " | " << std::setprecision(1) << o.at("extra_mb") << " | " << f.at("extra_mb") << " | "
                      << (d.count("extra_mb") ? d.at("extra_mb") : 0.0) << " |\n";
            const std::string label =
                c.name.substr(0, c.name.find(' ', c.name.find(' ') + 1)) + ", " + std::to_string(t) + " thr";
            dat << '"' << label << "\" " << o.at("ms") << ' ' << f.at("ms") << ' ' << (d.count("ms") ? d.at("ms") : 0.0)
                << "\n";
            for (auto& [m, r] :
                 std::vector<std::pair<std::string, std::map<std::string, double>>>{{"ours", o}, {"fe", f}, {"vdb", d}})
                if (r.count("ms"))
                    csv << "methods," << c.name << "," << c.iso << "," << m << "," << t << ",32," << r.at("ms") << ","
                        << r.at("tris") << "," << r.at("extra_mb") << "\n";
            std::cout.flush();
        }
    }

    std::cout << "\n## Where our time goes (2 threads, chunk 32)\n\n| data | index ms | extract ms | weld ms | chunks "
                 "visited |\n|---|---|---|---|---|\n";
    for (const auto& c : cases) {
        const auto o = child("ours", c.data, c.iso, 2, 32);
        std::cout << std::fixed << std::setprecision(1) << "| " << c.name << " | " << o.at("index_ms") << " | "
                  << o.at("extract_ms") << " | " << o.at("weld_ms") << " | " << std::setprecision(0) << o.at("visited")
                  << " / " << o.at("chunks") << " |\n";
    }

    std::cout << "\n## GPU compute path (same chunks; GL renderer printed on stderr)\n\n| data | total ms | index ms | "
                 "GPU passes + read-back ms | weld ms | tris |\n|---|---|---|---|---|---|\n";
    for (const auto& c : cases) {
        const auto o = child("gpu", c.data, c.iso, 2, 32);
        if (!o.count("ms")) {
            std::cout << "| " << c.name << " | (no GL context) | | | | |\n";
            continue;
        }
        std::cout << std::fixed << std::setprecision(1) << "| " << c.name << " | " << o.at("ms") << " | "
                  << o.at("index_ms") << " | " << o.at("extract_ms") << " | " << o.at("weld_ms") << " | "
                  << std::setprecision(0) << o.at("tris") << " |\n";
        csv << "gpu," << c.name << "," << c.iso << ",gpu,2,32," << o.at("ms") << "," << o.at("tris") << ",0\n";
        std::cout.flush();
    }

    std::cout << "\n## Chunk size sweep (phantom skin, 2 threads)\n\n| chunk | ms | extract-only ms | scratch MiB | "
                 "extra MiB |\n|---|---|---|---|---|\n";
    for (int cs : {8, 16, 24, 32, 48, 64, 96, 128}) {
        const auto o = child("ours", "phantom", -500.0, 2, cs);
        std::cout << std::fixed << std::setprecision(1) << "| " << cs << " | " << o.at("ms") << " | "
                  << o.at("extract_ms") << " | " << o.at("scratch_mb") << " | " << o.at("extra_mb") << " |\n";
        csv << "chunks,phantom,-500,ours,2," << cs << "," << o.at("ms") << "," << o.at("tris") << ","
            << o.at("extra_mb") << "\n";
        std::cout.flush();
    }

    std::cout
        << "\n## Incremental re-extraction after a 32^3 edit (phantom skin)\n\n| threads | full (chunks) ms | full + "
           "weld ms | incremental ms | speed-up vs full + weld | chunks redone |\n|---|---|---|---|---|---|\n";
    for (int t : {1, 2}) {
        std::ostringstream cmd;
        cmd << self << " --one incremental --data phantom --iso -500 --threads " << t << " --chunk 32 --size " << size
            << " --reps " << a.reps;
        const auto r = parse(capture(cmd.str()));
        std::cout << std::fixed << std::setprecision(1) << "| " << t << " | " << r.at("full_ms") << " | "
                  << r.at("full_weld_ms") << " | " << std::setprecision(2) << r.at("inc_ms") << " | "
                  << std::setprecision(0) << r.at("full_weld_ms") / r.at("inc_ms") << "x | " << r.at("redone") << " / "
                  << r.at("chunks") << " |\n";
        csv << "incremental,phantom,-500,ours," << t << ",32," << r.at("inc_ms") << ",0,0\n";
    }
    csv.close();
    dat.close();

    // Plots through gnuplot when it is installed.
    if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
        std::ofstream gp(a.out + "/isosurface.gp");
        gp << "set datafile separator ','\nset terminal pngcairo size 900,500 noenhanced\nset key left top\n"
           << "set output '" << a.out
           << "/isosurface_chunks.png'\nset title 'Chunk size sweep (phantom skin, 2 threads)'\n"
           << "set xlabel 'chunk size (cells per side)'\nset ylabel 'ms'\nset logscale x 2\n"
           << "plot '< grep ^chunks " << a.out << "/isosurface.csv' using 6:7 with linespoints title 'ours'\n";
        gp << "set output '" << a.out
           << "/isosurface_methods.png'\nunset logscale x\nset title 'Isosurface extraction time, normals on (lower is "
              "better)'\n"
           << "set style data histograms\nset style histogram clustered gap 1\nset style fill solid 0.8 border -1\n"
           << "set xtics rotate by -25 font ',9'\nset xlabel ''\nset ylabel 'ms'\nset datafile separator "
              "whitespace\nset key left top\n"
           << "plot '" << a.out
           << "/isosurface_methods.dat' using 2:xtic(1) title 'ours (chunked MC)', '' using 3 title "
              "'vtkFlyingEdges3D', "
           << "'' using 4 title 'OpenVDB volumeToMesh'\n";
        gp.close();
        if (std::system(("gnuplot " + a.out + "/isosurface.gp").c_str()) != 0) std::cerr << "gnuplot failed\n";
    }
    std::cout << "\nwrote " << a.out << "/isosurface.csv\n";
    return 0;
}
