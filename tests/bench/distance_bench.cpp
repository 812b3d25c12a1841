// Surface-to-surface distance benchmark (docs/measure.md, "Structures"): the
// shortest distance between two surfaces, ours (an exact minimum over every
// triangle pair through a BVH of each surface: renderer/surface/closest.hpp)
// against the ways a user of VTK or Slicer gets one, in the same run:
//   - vtkDistancePolyDataFilter: the distance from every vertex of each
//     surface to the other surface (exact point-to-surface through
//     vtkImplicitPolyDataDistance), its minimum taken both ways;
//   - the nearest pair of vertices (vtkKdTreePointLocator over one
//     surface's vertices, each vertex of the other queried);
//   - brute force over every triangle pair (ours, the reference) where it
//     takes under a minute.
// The error of each is against the exact minimum (brute force, or the
// closed form where the closest points are the poles of two UV spheres);
// the time is the median of --reps runs, hierarchy building included.
//
//   distance_bench [--out DIR] [--reps R]
//
// Cases: two UV spheres (poles facing: the closed form d - r1 - r2; along an
// oblique axis: closest points inside faces), and the bundled head's skin
// (iso 500) to its bone (iso 1150), the whole surfaces and one bone
// component to another. Prints a markdown table and writes DIR/distance_bench.csv.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <vtkCellArray.h>
#include <vtkDistancePolyDataFilter.h>
#include <vtkDoubleArray.h>
#include <vtkKdTreePointLocator.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "bench_util.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/closest.hpp"
#include "tests/support/meshes.hpp"

using namespace iso;

namespace {

vtkSmartPointer<vtkPolyData> to_vtk(const Mesh& m) {
    auto pd = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToDouble();
    for (const auto& p : m.positions) pts->InsertNextPoint(p.x, p.y, p.z);
    vtkNew<vtkCellArray> cells;
    for (const auto& t : m.triangles) {
        const vtkIdType ids[3] = {t[0], t[1], t[2]};
        cells->InsertNextCell(3, ids);
    }
    pd->SetPoints(pts);
    pd->SetPolys(cells);
    return pd;
}

double median_ms(int reps, const std::function<double()>& run, double& value) {
    std::vector<double> t;
    for (int i = 0; i < reps; ++i) {
        const double t0 = bench::now_s();
        value = run();
        t.push_back(1000.0 * (bench::now_s() - t0));
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

// vtkDistancePolyDataFilter's minimum over the vertices of `a` to `b` and of `b` to `a`.
double vtk_vertex_to_surface(const Mesh& a, const Mesh& b) {
    const auto pa = to_vtk(a), pb = to_vtk(b);
    vtkNew<vtkDistancePolyDataFilter> f;
    f->SetInputData(0, pa);
    f->SetInputData(1, pb);
    f->SignedDistanceOff();
    f->ComputeSecondDistanceOn();
    f->Update();
    double best = 1e300;
    for (int k = 0; k < 2; ++k) {
        auto* d = vtkDoubleArray::SafeDownCast(f->GetOutput(k)->GetPointData()->GetArray("Distance"));
        for (vtkIdType i = 0; d && i < d->GetNumberOfTuples(); ++i) best = std::min(best, d->GetValue(i));
    }
    return best;
}

// The nearest pair of vertices, through a k-d tree over b's vertices.
double vtk_vertex_to_vertex(const Mesh& a, const Mesh& b) {
    const auto pb = to_vtk(b);
    vtkNew<vtkKdTreePointLocator> loc;
    loc->SetDataSet(pb);
    loc->BuildLocator();
    double best = 1e300;
    for (const auto& p : a.positions) {
        double dist2 = 0;
        const double q[3] = {p.x, p.y, p.z};
        loc->FindClosestPointWithinRadius(1e30, q, dist2);
        best = std::min(best, std::sqrt(dist2));
    }
    return best;
}

struct Case {
    std::string name;
    Mesh a, b;
    double exact = std::nan(""); // closed form, when there is one
};

std::vector<Case> cases() {
    std::vector<Case> out;
    for (int n : {20, 80, 320}) {
        Case c{"UV spheres, poles facing, " + std::to_string(2 * n * n) + " triangles each",
               test::uv_sphere({0, 0, 0}, 10.0, n, 2 * n), test::uv_sphere({0, 0, 35}, 15.0, n, 2 * n), 10.0};
        out.push_back(std::move(c));
    }
    const glm::dvec3 dir = glm::normalize(glm::dvec3(1, 2, 2));
    for (int n : {20, 80, 320})
        out.push_back({"UV spheres, oblique axis, " + std::to_string(2 * n * n) + " triangles each",
                       test::uv_sphere({0, 0, 0}, 10.0, n, 2 * n), test::uv_sphere(40.0 * dir, 15.0, n, 2 * n)});
    core::Scene scene;
    scene.open(std::string(ISOSCOPE_DATA_DIR) + "/headsq.nhdr");
    const auto ids = scene.add_isosurfaces({500, 1150});
    out.push_back({"head: skin (iso 500) to bone (iso 1150)", scene.mesh(ids[0]), scene.mesh(ids[1])});
    const auto comps = triangle_components(scene.mesh(ids[1]));
    out.push_back({"head: bone component 1 to component 2", component_mesh(scene.mesh(ids[1]), comps, 0),
                   component_mesh(scene.mesh(ids[1]), comps, 1)});
    return out;
}

} // namespace

int main(int argc, char** argv) {
    std::string out_dir = ".";
    int reps = 3;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--out" && i + 1 < argc)
            out_dir = argv[++i];
        else if (a == "--reps" && i + 1 < argc)
            reps = std::max(1, std::atoi(argv[++i]));
        else {
            std::cerr << "usage: distance_bench [--out DIR] [--reps R]\n";
            return 2;
        }
    }
    std::filesystem::create_directories(out_dir);
    std::ofstream csv(out_dir + "/distance_bench.csv");
    csv << "case,triangles_a,triangles_b,method,ms,distance_mm,error_mm\n";
    std::cout << "| case | method | ms (median of " << reps
              << ") | distance mm | error mm |\n|---|---|---:|---:|---:|\n";
    for (const Case& c : cases()) {
        struct Row {
            std::string method;
            double ms = 0, d = 0;
        };
        std::vector<Row> rows;
        double d = 0;
        double ms = median_ms(
            reps, [&] { return surface_distance(TriangleBvh(c.a), TriangleBvh(c.b)).pair.distance_mm; }, d);
        rows.push_back({"ours: BVH, exact triangle pairs", ms, d});
        const double pairs = double(c.a.triangles.size()) * double(c.b.triangles.size());
        double exact = c.exact;
        if (pairs < 4e7) {
            ms = median_ms(
                1, [&] { return surface_distance_brute_force(c.a, c.b).pair.distance_mm; }, d);
            rows.push_back({"brute force, every triangle pair", ms, d});
            if (std::isnan(exact)) exact = d;
        }
        if (std::isnan(exact))
            exact = rows[0].d; // no closed form, brute force too slow: ours (equal wherever both ran)
        ms = median_ms(
            reps, [&] { return vtk_vertex_to_surface(c.a, c.b); }, d);
        rows.push_back({"VTK vtkDistancePolyDataFilter (vertices to surface, both ways)", ms, d});
        ms = median_ms(
            reps, [&] { return vtk_vertex_to_vertex(c.a, c.b); }, d);
        rows.push_back({"VTK k-d tree: nearest vertex pair", ms, d});
        for (const Row& r : rows) {
            std::cout << "| " << c.name << " | " << r.method << " | " << std::fixed << std::setprecision(1) << r.ms
                      << " | " << std::setprecision(6) << r.d << " | " << std::scientific << std::setprecision(2)
                      << r.d - exact << std::defaultfloat << " |\n";
            csv << '"' << c.name << "\"," << c.a.triangles.size() << ',' << c.b.triangles.size() << ",\"" << r.method
                << "\"," << r.ms << ',' << std::setprecision(12) << r.d << ',' << r.d - exact << "\n";
        }
    }
    std::cout << "wrote " << out_dir << "/distance_bench.csv\n";
    return 0;
}
