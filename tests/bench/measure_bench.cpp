// Measurement benchmark (docs/measure.md): area and volume of analytic ball
// phantoms on an oblique, anisotropic grid (tests/unit/measure_phantoms.hpp)
// at several voxel sizes, ours (chunked marching cubes + measure_isosurface)
// against VTK 9.1 (vtkFlyingEdges3D + vtkMassProperties) on the same volume
// and iso value: relative error against the analytic answer, the
// uncertainty we report next to it, and time. Then how often the true error
// lies within the reported uncertainty over random balls, and a ball cut by
// the volume border (open surface).
//
//   measure_bench [--out DIR] [--balls N] [--threads T] [--reps R] [--no-large]
//
// Last, the time of each on the 512 x 512 x 400 CT phantom of the isosurface
// benchmark (millions of triangles; cached in the temporary folder, made in
// about 20 s when absent; --no-large skips it). Prints markdown tables,
// writes DIR/measure_bench.csv and, when gnuplot is installed,
// DIR/measure_convergence.png and DIR/measure_coverage.png.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <unistd.h>

#include <tbb/global_control.h>

#include <vtkFlyingEdges3D.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkMassProperties.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkShortArray.h>

#include "tests/support/measure_phantoms.hpp"
#include "bench_util.hpp"
#include "ct_phantom.hpp"
#include "vtk_volume.hpp"
#include "renderer/surface/extract.hpp"
#include "renderer/surface/analysis.hpp"

using namespace iso;
using namespace iso::bench;
using namespace iso::test;
namespace fs = std::filesystem;

namespace iso::bench {
void set_vtk_threads(int n); // vtk_threads.cpp
}

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Peer {
    double area = 0, volume_ml = 0, ms = 0, measure_ms = 0;
    std::size_t tris = 0;
};

// vtkFlyingEdges3D in index space (VTK 9.1's filter ignores the direction
// matrix), its points mapped through the volume's affine, then
// vtkMassProperties: what a VTK pipeline (Slicer's Segment Statistics) reports.
Peer vtk_peer(const Volume& v, double iso, int reps) {
    Peer r;
    std::vector<double> total, mp;
    for (int rep = 0; rep < reps; ++rep) {
        const double t0 = now_s();
        vtkNew<vtkImageData> img;
        img->SetDimensions(int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
        vtkNew<vtkFloatArray> arr;
        const auto s = v.as<float>();
        arr->SetArray(const_cast<float*>(s.data()), vtkIdType(s.size()), /*save=*/1);
        img->GetPointData()->SetScalars(arr);
        vtkNew<vtkFlyingEdges3D> fe;
        fe->SetInputData(img);
        fe->SetValue(0, iso);
        fe->ComputeNormalsOff();
        fe->ComputeGradientsOff();
        fe->ComputeScalarsOff();
        fe->Update();
        vtkPolyData* pd = fe->GetOutput();
        vtkPoints* pts = pd->GetPoints();
        for (vtkIdType i = 0; i < pd->GetNumberOfPoints(); ++i) {
            double p[3];
            pts->GetPoint(i, p);
            const glm::dvec3 w(v.index_to_lps * glm::dvec4(p[0], p[1], p[2], 1.0));
            pts->SetPoint(i, w.x, w.y, w.z);
        }
        const double t1 = now_s();
        vtkNew<vtkMassProperties> mass;
        mass->SetInputData(pd);
        mass->Update();
        r.area = mass->GetSurfaceArea();
        r.volume_ml = mass->GetVolume() / 1000.0;
        r.tris = std::size_t(pd->GetNumberOfCells());
        const double t2 = now_s();
        total.push_back(t2 - t0);
        mp.push_back(t2 - t1);
    }
    r.ms = 1e3 * median(total);
    r.measure_ms = 1e3 * median(mp);
    return r;
}

struct Ours {
    SurfaceMeasures m;
    double ms = 0;             // extraction + measure_isosurface (with the uncertainty)
    double measure_ms = 0;     // measure_surface alone
    double uncertainty_ms = 0; // measure_isosurface beyond measure_surface (coarsening + coarse extraction + matching)
};

Ours ours(const Volume& v, double iso, int threads, int reps) {
    Ours r;
    std::vector<double> total, meas, unc;
    for (int rep = 0; rep < reps; ++rep) {
        const double t0 = now_s();
        ExtractOptions eo;
        eo.normals = false;
        eo.threads = threads;
        const Mesh mesh = extract_isosurface(v, iso, eo);
        const double t1 = now_s();
        r.m = measure_isosurface(v, iso, mesh, {.threads = threads});
        const double t2 = now_s();
        (void)measure_surface(mesh, {.threads = threads});
        const double t3 = now_s();
        total.push_back(t2 - t0);
        meas.push_back(t3 - t2);
        unc.push_back((t2 - t1) - (t3 - t2));
    }
    r.ms = 1e3 * median(total);
    r.measure_ms = 1e3 * median(meas);
    r.uncertainty_ms = 1e3 * median(unc);
    return r;
}

double rel(double x, double truth) { return (x - truth) / truth; }

struct Ball {
    Volume v;
    double r = 0;
    glm::dvec3 c{0.0};
};

// A ball of radius r, its centre moved off the grid centre by `offset`
// voxels (so phases differ), PSF sigma = 0.6 x the mean voxel step.
Ball make_ball(double scale, double r, const glm::dvec3& offset) {
    Ball b;
    b.r = r;
    const auto dims = dims_for(r, 3.0 * scale + 2.0, scale);
    const glm::dvec3 centre(-30.0, 45.0, 120.0); // LPS, away from the origin as in a scan
    const glm::dmat4 aff = oblique_affine(dims, scale, centre);
    b.c = centre + glm::dmat3(aff) * offset;
    const glm::dvec3 sp = phantom_spacing(scale);
    const double sigma = 0.6 * (sp.x + sp.y + sp.z) / 3.0;
    b.v = ct_ball(dims, aff, b.c, r, sigma);
    return b;
}

// Edge profiles of the coverage table: sigma of the Gaussian blur in voxels
// (mean step), 0 for a binary mask, < 0 for a linear ramp (distance field).
struct Profile {
    std::string name;
    double sigma_voxels;
};

Volume ball_with_profile(double scale, double r, const glm::dvec3& offset, const Profile& pr) {
    const auto dims = dims_for(r, 3.0 * scale + 2.0, scale);
    const glm::dvec3 centre(-30.0, 45.0, 120.0);
    const glm::dmat4 aff = oblique_affine(dims, scale, centre);
    const glm::dvec3 c = centre + glm::dmat3(aff) * offset;
    const glm::dvec3 sp = phantom_spacing(scale);
    const double sigma = pr.sigma_voxels * (sp.x + sp.y + sp.z) / 3.0;
    return sample_field(dims, aff, [&](const glm::dvec3& p) {
        const double d = r - glm::length(p - c);
        if (pr.sigma_voxels < 0) return kBallIso + 100.0 * d;
        if (pr.sigma_voxels == 0) return d >= 0 ? 1000.0 : 0.0;
        return ct_edge(d, sigma);
    });
}

std::string pct(double x, int digits = 3) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << 100.0 * x << " %";
    return o.str();
}
std::string num(double x, int digits = 1) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << x;
    return o.str();
}

} // namespace

int main(int argc, char** argv) {
    std::string out = "bench-results";
    int balls = 16, threads = 2, reps = 5;
    bool large = true;
    for (int i = 1; i < argc; ++i) {
        std::string s = argv[i];
        auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
        if (s == "--out")
            out = next();
        else if (s == "--balls")
            balls = std::stoi(next());
        else if (s == "--threads")
            threads = std::stoi(next());
        else if (s == "--reps")
            reps = std::stoi(next());
        else if (s == "--no-large")
            large = false;
        else {
            std::cerr << "usage: measure_bench [--out DIR] [--balls N] [--threads T] [--reps R] [--no-large]\n";
            return 2;
        }
    }
    try {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
        set_vtk_threads(threads);
        fs::create_directories(out);
        std::ofstream csv(out + "/measure_bench.csv");
        csv << "table,case,voxel_mm,radius_mm,tris,area_err_ours,area_unc_ours,area_err_vtk,vol_err_ours,vol_unc_ours,"
               "vol_err_vtk,"
               "spread,ours_ms,ours_measure_ms,ours_uncertainty_ms,vtk_ms,vtk_measure_ms\n";
        const double start = now_s();

        // 1. One ball, several voxel sizes.
        const double R = 10.0;
        std::cout
            << "## Ball of radius " << R
            << " mm: relative error against 4/3 pi r^3 and 4 pi r^2, and our uncertainty U\n\n"
            << "Grid (0.7, 1.0, 1.3) x s mm rotated 25 degrees about (1, 2, 3); CT-like edge (erf, sigma = 0.6 mean "
               "voxel); "
            << "iso 500 is the sphere exactly. " << threads << " threads, median of " << reps
            << " runs. Ours: extract_isosurface + measure_isosurface (U included); VTK: vtkFlyingEdges3D + "
               "vtkMassProperties.\n\n"
            << "| voxel s mm | tris | area err ours | area U | area err VTK | volume err ours | volume U | volume err "
               "VTK | "
               "ours ms (MC + measure + U) | measure_surface ms | U ms | VTK ms (FE + mass) | vtkMassProperties ms |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        std::array<double, 2> err_at_1{0, 0}; // |area|, |volume| relative error at s = 1, for the plot's s^2 guide
        for (double s : {2.0, 1.4, 1.0, 0.7, 0.5}) {
            const Ball b = make_ball(s, R, {0.31, 0.17, 0.43});
            const double area = 4 * kPi * R * R, vol = 4.0 / 3.0 * kPi * R * R * R / 1000.0;
            const Ours o = ours(b.v, kBallIso, threads, reps);
            if (s == 1.0) err_at_1 = {std::abs(rel(o.m.area_mm2, area)), std::abs(rel(o.m.volume_ml, vol))};
            const Peer p = vtk_peer(b.v, kBallIso, reps);
            std::cout << "| " << s << " | " << o.m.triangles << " | " << pct(rel(o.m.area_mm2, area)) << " | "
                      << pct(o.m.area_uncertainty_mm2 / area) << " | " << pct(rel(p.area, area)) << " | "
                      << pct(rel(o.m.volume_ml, vol)) << " | " << pct(o.m.volume_uncertainty_ml / vol) << " | "
                      << pct(rel(p.volume_ml, vol)) << " | " << num(o.ms, 2) << " | " << num(o.measure_ms, 2) << " | "
                      << num(o.uncertainty_ms, 2) << " | " << num(p.ms, 2) << " | " << num(p.measure_ms, 2) << " |\n";
            csv << std::setprecision(8) << "convergence,ball sigma 0.6," << s << "," << R << "," << o.m.triangles << ","
                << rel(o.m.area_mm2, area) << "," << o.m.area_uncertainty_mm2 / area << "," << rel(p.area, area) << ","
                << rel(o.m.volume_ml, vol) << "," << o.m.volume_uncertainty_ml / vol << "," << rel(p.volume_ml, vol)
                << "," << o.m.edge_fraction_spread << "," << o.ms << "," << o.measure_ms << "," << o.uncertainty_ms
                << "," << p.ms << "," << p.measure_ms << "\n";
            std::cout.flush();
        }

        // 2. A ball cut by the volume border: what each side reports.
        {
            const double r = 12.0, d = 5.0, s = 1.0;
            const auto dims = dims_for(r, 4.0, s);
            const glm::dvec3 centre(-30.0, 45.0, 120.0);
            const glm::dmat4 aff = oblique_affine(dims, s, centre);
            const glm::dvec3 n_i = glm::normalize(glm::dvec3(aff[0])), plane(aff[3]);
            const glm::dvec3 c = centre - glm::dot(centre - plane, n_i) * n_i + d * n_i;
            const glm::dvec3 sp = phantom_spacing(s);
            const Volume v = ct_ball(dims, aff, c, r, 0.6 * (sp.x + sp.y + sp.z) / 3.0);
            const Ours o = ours(v, kBallIso, threads, 1);
            const Peer p = vtk_peer(v, kBallIso, 1);
            const double full = 4.0 / 3.0 * kPi * r * r * r / 1000.0, hc = r - d;
            const double inside = full - kPi * hc * hc * (3 * r - hc) / 3.0 / 1000.0;
            std::cout
                << "\n## Ball of radius " << r << " mm cut by the volume border " << d
                << " mm from its centre (s = 1; the part inside the field: " << num(inside, 4) << " mL, whole ball "
                << num(full, 4) << " mL, cut circle " << num(2 * kPi * std::sqrt(r * r - d * d), 3) << " mm)\n\n"
                << "| | volume mL | kind | U mL | boundary loops | boundary length mm |\n|---|---|---|---|---|---|\n"
                << "| ours (measure_isosurface) | " << num(o.m.volume_ml, 4) << " | "
                << volume_kind_name(o.m.volume_kind) << " | " << num(o.m.volume_uncertainty_ml, 4) << " | "
                << o.m.boundary_loops << " | " << num(o.m.boundary_length_mm, 3) << " |\n"
                << "| VTK (vtkMassProperties) | " << num(p.volume_ml, 4) << " | (not reported) | | | |\n";
            csv << "cut,ball cut by the border," << s << "," << r << "," << o.m.triangles << ",,,,"
                << rel(o.m.volume_ml, inside) << "," << o.m.volume_uncertainty_ml / inside << ","
                << rel(p.volume_ml, inside) << "," << o.m.edge_fraction_spread << ",,,,,\n";
        }

        // 3. Coverage: random balls (radius 4..20 mm, random sub-voxel centre) per edge profile and voxel size.
        std::cout << "\n## Is the true error within U? " << balls
                  << " random balls per row (radius 4-20 mm, random centre), by edge profile and voxel size\n\n"
                  << "covered: |error| <= U; U/|err|: smallest and median ratio; spread: mean edge fraction spread "
                     "(flagged below "
                  << kResolvedEdgeSpread << ").\n\n"
                  << "| edge | voxel s mm | spread | area covered | area U/err min | area U/err median | max area err "
                     "| volume covered | "
                     "volume U/err min | volume U/err median | max volume err "
                     "|\n|---|---|---|---|---|---|---|---|---|---|---|\n";
        const std::vector<Profile> profiles = {{"ramp (distance)", -1.0}, {"blur 1.0 voxel", 1.0},
                                               {"blur 0.5 voxel", 0.5},   {"blur 0.35 voxel", 0.35},
                                               {"blur 0.25 voxel", 0.25}, {"binary mask", 0.0}};
        for (const auto& pr : profiles) {
            std::mt19937 rng(12345);
            std::uniform_real_distribution<double> radius(4.0, 20.0), frac(-0.5, 0.5);
            for (double s : {2.0, 1.0, 0.5}) {
                int cov_a = 0, cov_v = 0;
                std::vector<double> ratio_a, ratio_v;
                double max_a = 0, max_v = 0, spread = 0;
                for (int n = 0; n < balls; ++n) {
                    const double r = radius(rng);
                    const Volume v = ball_with_profile(s, r, {frac(rng), frac(rng), frac(rng)}, pr);
                    const auto m = measure_isosurface(v, kBallIso, MeasureOptions{.threads = threads});
                    const double area = 4 * kPi * r * r, vol = 4.0 / 3.0 * kPi * r * r * r / 1000.0;
                    const double ea = std::abs(rel(m.area_mm2, area)), ev = std::abs(rel(m.volume_ml, vol));
                    const double ua = m.area_uncertainty_mm2 / area, uv = m.volume_uncertainty_ml / vol;
                    cov_a += ea <= ua;
                    cov_v += ev <= uv;
                    ratio_a.push_back(ua / ea);
                    ratio_v.push_back(uv / ev);
                    max_a = std::max(max_a, ea);
                    max_v = std::max(max_v, ev);
                    spread += m.edge_fraction_spread / balls;
                    csv << std::setprecision(8) << "coverage," << pr.name << "," << s << "," << r << "," << m.triangles
                        << "," << rel(m.area_mm2, area) << "," << ua << ",," << rel(m.volume_ml, vol) << "," << uv
                        << ",," << m.edge_fraction_spread << ",,,,,\n";
                }
                std::cout << "| " << pr.name << " | " << s << " | " << num(spread, 2) << " | " << cov_a << " / "
                          << balls << " | " << num(*std::min_element(ratio_a.begin(), ratio_a.end()), 2) << " | "
                          << num(median(ratio_a), 2) << " | " << pct(max_a, 2) << " | " << cov_v << " / " << balls
                          << " | " << num(*std::min_element(ratio_v.begin(), ratio_v.end()), 2) << " | "
                          << num(median(ratio_v), 2) << " | " << pct(max_v, 2) << " |\n";
                std::cout.flush();
            }
        }

        // 4. Millions of triangles: the CT phantom of the isosurface benchmark.
        if (large) {
            const std::array<std::int64_t, 3> size{512, 512, 400};
            const Volume v = cached_ct_phantom(size);
            std::cout << "\n## Large surfaces: CT phantom 512 x 512 x 400 (int16, 0.7 x 0.7 x 1 mm), " << threads
                      << " threads, median of " << reps << " (ours and VTK alternating)\n\n"
                      << "| surface | tris | components | closed | area ours mm2 | volume ours mL | ours / VTK - 1 "
                         "(area, volume) | "
                         "U area | U volume | spread | MC ms | measure_surface ms | measure_surface 1 thread ms | "
                         "measure_isosurface ms | FE ms | vtkMassProperties ms |\n"
                         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
            for (const auto& [name, iso] :
                 std::vector<std::pair<std::string, double>>{{"skin (iso -500)", -500.0}, {"bone (iso 400)", 400.0}}) {
                std::vector<double> t_mc, t_meas, t_meas1, t_iso, t_fe, t_mass;
                SurfaceMeasures m, mi;
                Peer p;
                Mesh mesh;
                for (int rep = 0; rep < reps; ++rep) {
                    double t0 = now_s();
                    mesh = extract_isosurface(v, iso, {.normals = false, .threads = threads});
                    double t1 = now_s();
                    m = measure_surface(mesh, {.threads = threads});
                    double t2 = now_s();
                    (void)measure_surface(mesh, {.threads = 1});
                    double t3 = now_s();
                    mi = measure_isosurface(v, iso, mesh, {.threads = threads});
                    double t4 = now_s();
                    t_mc.push_back(t1 - t0);
                    t_meas.push_back(t2 - t1);
                    t_meas1.push_back(t3 - t2);
                    t_iso.push_back(t4 - t3);
                    // VTK: Flying Edges on the same samples (axis-aligned grid, so VTK's spacing and origin suffice).
                    auto img = as_vtk(v);
                    vtkNew<vtkFlyingEdges3D> fe;
                    fe->SetInputData(img);
                    fe->SetValue(0, iso);
                    fe->ComputeNormalsOff();
                    fe->ComputeGradientsOff();
                    fe->ComputeScalarsOff();
                    t0 = now_s();
                    fe->Update();
                    t1 = now_s();
                    vtkNew<vtkMassProperties> mass;
                    mass->SetInputData(fe->GetOutput());
                    mass->Update();
                    p.area = mass->GetSurfaceArea();
                    p.volume_ml = mass->GetVolume() / 1000.0;
                    t2 = now_s();
                    t_fe.push_back(t1 - t0);
                    t_mass.push_back(t2 - t1);
                }
                std::cout << "| " << name << " | " << m.triangles << " | " << m.components.size() << " | "
                          << (m.closed ? "yes" : "no") << " | " << num(m.area_mm2, 1) << " | " << num(m.volume_ml, 3)
                          << " | " << std::scientific << std::setprecision(1) << rel(m.area_mm2, p.area) << ", "
                          << rel(m.volume_ml, p.volume_ml) << std::defaultfloat << " | "
                          << pct(mi.area_uncertainty_mm2 / m.area_mm2, 2) << " | "
                          << pct(mi.volume_uncertainty_ml / std::abs(m.volume_ml), 2) << " | "
                          << num(mi.edge_fraction_spread, 2) << " | " << num(1e3 * median(t_mc)) << " | "
                          << num(1e3 * median(t_meas)) << " | " << num(1e3 * median(t_meas1)) << " | "
                          << num(1e3 * median(t_iso)) << " | " << num(1e3 * median(t_fe)) << " | "
                          << num(1e3 * median(t_mass)) << " |\n";
                csv << std::setprecision(8) << "large," << name << ",0.7," << 0 << "," << m.triangles << ",,"
                    << mi.area_uncertainty_mm2 / m.area_mm2 << ",,," << mi.volume_uncertainty_ml / std::abs(m.volume_ml)
                    << ",," << mi.edge_fraction_spread << "," << 1e3 * median(t_mc) << "," << 1e3 * median(t_meas)
                    << "," << 1e3 * (median(t_iso) - median(t_meas)) << "," << 1e3 * median(t_fe) << ","
                    << 1e3 * median(t_mass) << "\n";
                std::cout.flush();
            }
        }
        csv.close();

        // Plots through gnuplot when it is installed: error and U against voxel
        // size, and U against the true error over all random balls.
        if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
            std::ofstream gp(out + "/measure.gp");
            gp << "set datafile separator ','\nset terminal pngcairo size 1100,480 noenhanced\n"
               << "set output '" << out << "/measure_convergence.png'\nset multiplot layout 1,2\n"
               << "set logscale xy\nset xrange [0.45:2.2]\nset xtics (0.5, 0.7, 1, 1.4, 2)\nset key right bottom\nset "
                  "xlabel 'voxel scale s (mm; spacing 0.7 x 1.0 x 1.3 s)'\n"
               << "set ylabel '|relative error|, U (%)'\nset format y '%g'\n";
            for (const auto& [title, err, unc, vtk] : std::vector<std::tuple<std::string, int, int, int>>{
                     {"Ball r = 10 mm: area", 6, 7, 8}, {"Ball r = 10 mm: volume", 9, 10, 11}}) {
                gp << "set title '" << title << "'\n"
                   << "plot '< grep ^convergence " << out << "/measure_bench.csv' using 3:(100*abs($" << err
                   << ")) with linespoints pt 7 title 'ours |error|', '' using 3:(100*abs($" << vtk
                   << ")) with points pt 6 ps 2 title 'VTK |error|', '' using 3:(100*$" << unc
                   << ") with linespoints dt 2 pt 5 title 'ours U', " << 100.0 * (err == 6 ? err_at_1[0] : err_at_1[1])
                   << "*x**2 with lines dt 3 lc rgb 'black' title 'error at s = 1 times s^2'\n";
            }
            gp << "unset multiplot\nset terminal pngcairo size 1100,480 noenhanced\nset output '" << out
               << "/measure_coverage.png'\n"
               << "set multiplot layout 1,2\nunset xrange\nset xtics auto\nset xlabel '|true relative error| (%)'\nset "
                  "ylabel 'reported U (%)'\nset key right bottom\n";
            for (const auto& [title, err, unc] : std::vector<std::tuple<std::string, int, int>>{
                     {"Random balls: area", 6, 7}, {"Random balls: volume", 9, 10}}) {
                gp << "set title '" << title << " (above the line: covered)'\nplot ";
                bool first = true;
                for (const auto& pr : profiles) {
                    gp << (first ? "" : ", ") << "'< grep \"^coverage," << pr.name << ",\" " << out
                       << "/measure_bench.csv' using (100*abs($" << err << ")):(100*$" << unc
                       << ") with points pt 7 ps 0.6 title '" << pr.name << "'";
                    first = false;
                }
                gp << ", x with lines lc rgb 'black' title 'U = |error|'\n";
            }
            gp << "unset multiplot\n";
            gp.close();
            if (std::system(("gnuplot " + out + "/measure.gp").c_str()) != 0) std::cerr << "gnuplot failed\n";
        }
        std::cout << "\ntotal " << num(now_s() - start, 1) << " s; wrote " << out << "/measure_bench.csv\n";
    } catch (const std::exception& e) {
        std::cerr << "measure_bench: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
