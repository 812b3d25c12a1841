// A smoke run of the anti-aliasing peers (aa_peer.hpp): VTK's camera against
// ours (a sphere and a thin rod drawn flat by both in a 4:3 image, coverage
// compared), then two small
// scenes, an opaque sphere with a thin rod across it and the same with a
// translucent slab in front, drawn by VTK without anti-aliasing, with FXAA,
// 4x and 8x multisampling and its 8x8 supersampled reference, each
// configuration's time and error against the reference printed
// (image_error.hpp). VTK runs under xvfb-run.
//
//   aa_peer_smoke [--size 128] [--reps 3] [--factor 8] [--out DIR]
// Prints "camera check: ... PASS" (or FAIL, exit status 1) and the tables.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "aa_peer.hpp"
#include "image_error.hpp"
#include "io/mesh.hpp"

using namespace iso;

namespace {

Mesh uv_sphere(glm::dvec3 c, double r, int stacks, int slices) {
    constexpr double kPi = 3.14159265358979323846;
    Mesh m;
    for (int i = 0; i <= stacks; ++i)
        for (int j = 0; j < slices; ++j) {
            const double th = kPi * i / stacks, ph = 2 * kPi * j / slices;
            const glm::dvec3 n(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            m.positions.push_back(glm::vec3(c + r * n));
            m.normals.push_back(glm::vec3(n));
        }
    const auto v = [&](int i, int j) { return std::uint32_t(i * slices + (j % slices)); };
    for (int i = 0; i < stacks; ++i)
        for (int j = 0; j < slices; ++j) {
            m.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
            m.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
        }
    return m;
}

Mesh box(glm::vec3 lo, glm::vec3 hi) {
    Mesh m;
    for (int k = 0; k < 8; ++k) m.positions.push_back({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
    const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : q) {
        m.triangles.push_back({f[0], f[1], f[2]});
        m.triangles.push_back({f[0], f[2], f[3]});
    }
    return m;
}

// One scene through every configuration: the table of time and error against VTK's reference.
bool run_scene(const std::string& title, const std::vector<bench::PeerMesh>& meshes, const Camera& cam, int size,
               int reps, const bench::AaPeerOptions& opt) {
    std::vector<std::string> failed;
    const auto images = bench::render_vtk_aa(meshes, cam, size, size, reps, opt, &failed);
    for (const auto& f : failed) std::printf("failed: %s\n", f.c_str());
    const bench::PeerImage* ref = nullptr;
    for (const auto& p : images)
        if (p.name == "reference") ref = &p;
    std::printf("\n### %s, %dx%d, %s, reference %dx%d supersampled\n\n", title.c_str(), size, size,
                images.empty() ? "?" : images[0].renderer.c_str(), opt.reference_factor, opt.reference_factor);
    std::printf("| config | ms median (p25-p75) | samples asked/window | peeled | px differing from none "
                "| RMSE | p99 | edge RMSE | edge p99 |\n|---|---:|---:|---|---:|---:|---:|---:|---:|\n");
    for (const auto& p : images) {
        const bench::ImageError e = ref ? bench::compare(p.image, ref->image) : bench::ImageError{};
        std::printf("| %s | %.1f (%.1f-%.1f) | %d/%d | %s | %ld | %.4f | %.4f | %.4f | %.4f |\n", p.name.c_str(), p.ms,
                    p.ms_p25, p.ms_p75, p.samples_asked, p.samples_window, p.peeled ? "yes" : "no", p.differ_from_none,
                    e.rmse, e.p99, e.edge_rmse, e.edge_p99);
    }
    if (ref)
        std::printf("\nedge pixels: %zu of %zu\n", bench::compare(ref->image, ref->image).edge_pixels,
                    ref->image.bytes.size() / 4);
    return ref != nullptr;
}

} // namespace

int main(int argc, char** argv) {
    int size = 128, reps = 3, factor = 8;
    std::string out;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--size")) size = std::stoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--reps")) reps = std::stoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--factor")) factor = std::stoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--out")) out = argv[i + 1];
    }
    try {
        const Mesh sphere = uv_sphere({0, 0, 0}, 40, 48, 96);
        const Mesh rod = box({-60, -45, -1}, {60, -43, 1}); // 2 mm thick, in front of the sphere
        const Mesh slab = box({-20, -70, -55}, {20, -60, 55});
        Bounds b;
        for (const Mesh* m : {&sphere, &rod, &slab})
            for (const auto& p : m->positions) b.add(glm::dvec3(p));
        Camera cam;
        cam.set_view(PatientView::Anterior, b);
        cam.fit(b, 1.0);
        cam.orbit(20, 15);
        cam.fit_planes(b);
        if (!out.empty()) std::filesystem::create_directories(out);
        // The sphere and the rod as one mesh, in a 4:3 image: silhouettes, a thin part and the aspect.
        Mesh both = sphere;
        for (const auto& t : rod.triangles)
            both.triangles.push_back({t[0] + std::uint32_t(sphere.positions.size()),
                                      t[1] + std::uint32_t(sphere.positions.size()),
                                      t[2] + std::uint32_t(sphere.positions.size())});
        both.positions.insert(both.positions.end(), rod.positions.begin(), rod.positions.end());
        both.normals.clear();
        Camera wide = cam;
        wide.fit(b, 4.0 / 3.0);
        const bench::CameraCheck c =
            bench::check_camera(both, wide, size * 4 / 3, size, out.empty() ? "" : out + "/camera");
        std::printf("camera check: %zu px, ours covers %zu, VTK %zu, %zu disagree: agreement %.4f, IoU %.4f: %s\n",
                    c.pixels, c.ours, c.vtk, c.disagree, c.agreement, c.iou, c.ok ? "PASS" : "FAIL");
        bench::AaPeerOptions opt;
        opt.reference_factor = factor;
        const bench::PeerMesh ball{&sphere, {0.8f, 0.55f, 0.45f}, 1.0f, ""}, bar{&rod, {0.9f, 0.1f, 0.1f}, 1.0f, ""},
            glass{&slab, {0.3f, 0.5f, 0.9f}, 0.4f, ""};
        opt.work_dir = out.empty() ? "" : out + "/opaque";
        bool ok = run_scene("opaque: a sphere and a 2 mm rod", {ball, bar}, cam, size, reps, opt);
        opt.work_dir = out.empty() ? "" : out + "/translucent";
        ok = run_scene("with a slab at 40 % (dual depth peeling)", {ball, bar, glass}, cam, size, reps, opt) && ok;
        return c.ok && ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::cerr << "aa_peer_smoke: " << e.what() << "\n";
        return 1;
    }
}
