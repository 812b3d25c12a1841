// The iso slider's latency (docs/gui.md "Surfaces panel"): the time
// from a new slider value to the new surface on screen, as the Surfaces panel
// does it: re-extraction (core::Scene::extract_isosurface), the swap on the
// GUI thread (Scene::replace_surface) and the first frame that shows it
// (Scene::render: upload, AO re-voxelization, draw), with the volume's range
// index cached (what the panel uses) and without it (a fresh index and value
// range scan per value, as Scene::add_isosurfaces did before), and
// vtkFlyingEdges3D extracting the same volume and values in the same run.
//
//   slider_bench [--size 512x512x400] [--reps 3] [--width 800] [--height 600] [--ao on|off] [--steps 8]
//
// Prints a markdown table. Data: datasets/headsq (64x64x93) and the
// CT-like phantom (tests/bench/ct_phantom.hpp, cached in the temporary folder).
#include <cstring>
#include <functional>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <vtkFlyingEdges3D.h>
#include <vtkPolyData.h>

#include "bench_util.hpp"
#include "ct_phantom.hpp"
#include "vtk_volume.hpp"
#include "io/error.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/gl/context.hpp"
#include "renderer/surface/extract.hpp"

using namespace iso;
using namespace iso::bench;

namespace iso::bench {
void set_vtk_threads(int n); // vtk_threads.cpp
}

namespace {

struct Args {
    std::array<std::int64_t, 3> size{512, 512, 400};
    int reps = 3, width = 800, height = 600, steps = 8;
    bool ao = true;
};

struct Case {
    std::string name;
    std::function<Volume()> load;
    double start, delta; // slider values: start + i * delta
};

struct Row {
    std::string name, iso;
    std::vector<double> cached, uncached, index, range, swap, frame, fe;
    std::size_t visited = 0, chunks = 0, tris = 0;
};

void run_case(const Case& c, const Args& a, std::vector<Row>& rows) {
    core::Scene s;
    s.set_volume(c.load(), c.name);
    const Volume& v = s.volume();
    auto img = as_vtk(v);
    RenderOptions ro;
    ro.width = a.width;
    ro.height = a.height;
    ro.look.ao = a.ao ? AoMethod::Cone : AoMethod::Off;
    // The surface the slider starts from, drawn once (uploaded, AO built).
    const auto id = s.add_isosurface(s.extract_isosurface(c.start), c.start);
    const Camera cam = s.camera(PatientView::Anterior, double(a.width) / a.height);
    s.render(cam, ro);
    Row r;
    r.name = c.name;
    std::ostringstream isos;
    isos << c.start + c.delta << " .. " << c.start + c.delta * a.steps;
    r.iso = isos.str();
    for (int rep = 0; rep < a.reps; ++rep)
        for (int i = 1; i <= a.steps; ++i) {
            // Alternate directions across reps so every value is new to the surface shown.
            const double iso = c.start + c.delta * (rep % 2 ? a.steps + 1 - i : i);
            // Without the cached index: a fresh one and the range scan, per value.
            double t0 = now_s();
            ExtractOptions eo;
            const Extractor fresh(v, eo);
            double t1 = now_s();
            Mesh m0 = weld(fresh.extract(iso), fresh.options().threads);
            double t2 = now_s();
            const auto vr = v.value_range();
            double t3 = now_s();
            (void)vr;
            r.index.push_back(t1 - t0);
            r.range.push_back(t3 - t2);
            r.uncached.push_back(t3 - t0);
            // With it (the panel's path).
            t0 = now_s();
            Mesh m = s.extract_isosurface(iso);
            t1 = now_s();
            r.cached.push_back(t1 - t0);
            if (m.triangles.size() != m0.triangles.size())
                throw Error("slider_bench", "cached and fresh extraction differ");
            r.tris = m.triangles.size();
            // Swap and the first frame that shows it.
            t0 = now_s();
            s.replace_surface(id, std::move(m), iso, {});
            t1 = now_s();
            s.render(cam, ro); // reads the image back: the frame is finished
            t2 = now_s();
            r.swap.push_back(t1 - t0);
            r.frame.push_back(t2 - t1);
            // Chunks the cached index lets the extraction visit.
            ExtractStats st;
            (void)fresh.extract(iso, &st);
            r.visited = st.chunks_visited;
            r.chunks = st.chunks_total;
            // The peer.
            t0 = now_s();
            vtkNew<vtkFlyingEdges3D> fe;
            fe->SetInputData(img);
            fe->SetValue(0, iso);
            fe->ComputeNormalsOn();
            fe->ComputeGradientsOff();
            fe->ComputeScalarsOff();
            fe->Update();
            r.fe.push_back(now_s() - t0);
        }
    s.release_gpu();
    rows.push_back(std::move(r));
}

std::array<std::int64_t, 3> parse_size(const std::string& s) {
    std::array<std::int64_t, 3> d{};
    if (std::sscanf(s.c_str(), "%ldx%ldx%ld", &d[0], &d[1], &d[2]) != 3)
        throw Error("--size", "expected WxHxD, got " + s);
    return d;
}

} // namespace

int main(int argc, char** argv) {
    try {
        Args a;
        for (int i = 1; i < argc; ++i) {
            const std::string k = argv[i];
            auto next = [&]() -> std::string {
                if (i + 1 >= argc) throw Error(k, "needs a value");
                return argv[++i];
            };
            if (k == "--size")
                a.size = parse_size(next());
            else if (k == "--reps")
                a.reps = std::stoi(next());
            else if (k == "--width")
                a.width = std::stoi(next());
            else if (k == "--height")
                a.height = std::stoi(next());
            else if (k == "--steps")
                a.steps = std::stoi(next());
            else if (k == "--ao")
                a.ao = next() != "off";
            else
                throw Error(k, "unknown option (--size, --reps, --width, --height, --steps, --ao)");
        }
        const int threads = tbb::info::default_concurrency();
        set_vtk_threads(threads);
        gl::HeadlessContext ctx(false);
        const auto headsq = [] { return load_volume(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr"); };
        const auto phantom = [&a] { return cached_ct_phantom(a.size); };
        std::ostringstream dims;
        dims << a.size[0] << "x" << a.size[1] << "x" << a.size[2];
        const std::vector<Case> cases = {
            {"headsq (64x64x93) skin", headsq, 500, 10},
            {"headsq (64x64x93) bone", headsq, 1150, 10},
            {"phantom (" + dims.str() + ") skin", phantom, -500, 10},
            {"phantom (" + dims.str() + ") bone", phantom, 700, 10},
        };
        std::vector<Row> rows;
        for (const auto& c : cases) {
            std::cerr << c.name << "...\n";
            run_case(c, a, rows);
        }
        std::cout
            << "## Slider change to new surface on screen (" << threads << " threads, " << a.width << "x" << a.height
            << ", AO " << (a.ao ? "on" : "off") << ", GL: " << ctx.info().renderer << "; median over " << a.reps
            << " x " << a.steps << " values, ms)\n\n"
            << "| data | iso values | tris | chunks visited | extract, cached index | extract, no cached index "
               "(index + range scan) | swap | first frame | total, cached | total, not cached | vtkFlyingEdges3D |\n"
            << "|---|---|---|---|---|---|---|---|---|---|---|\n";
        std::cout << std::fixed << std::setprecision(1);
        for (const auto& r : rows) {
            const double cached = 1e3 * median(r.cached), uncached = 1e3 * median(r.uncached),
                         swap = 1e3 * median(r.swap), frame = 1e3 * median(r.frame);
            std::cout << "| " << r.name << " | " << r.iso << " | " << r.tris << " | " << r.visited << " / " << r.chunks
                      << " | " << cached << " | " << uncached << " (" << 1e3 * median(r.index) << " + "
                      << 1e3 * median(r.range) << ") | " << std::setprecision(2) << swap << std::setprecision(1)
                      << " | " << frame << " | " << cached + swap + frame << " | " << uncached + swap + frame << " | "
                      << 1e3 * median(r.fe) << " |\n";
        }
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "slider_bench: " << e.what() << "\n";
        return 1;
    }
}
