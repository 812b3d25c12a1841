// Disk-based AO on the CPU (renderer/ao/disk_hierarchy.hpp: the model of the
// compute shaders) against the Embree reference, per vertex, to choose the
// defaults of DiskAoSettings (docs/ao.md, "Disk AO: hierarchy and CPU
// evaluation"). For each scene (the bundled CT's skin and bone surfaces, the
// Stanford bunny, as in ao_bench): hierarchy build time, then for each
// setting the element passes over every vertex disk and the final gather at
// a fixed random sample of vertices (their vertex normals), against
// AoReference::at at the same points (same rays for every setting).
//
//   disk_ao_cpu_bench [--scenes ct-skin,ct-bone,bunny] [--samples 2000] [--rays 1024]
//                     [--configs "passes=2,t=1,k=0,min=0.7;..."] [--radius-scale F] [--verbose]
// R: 10 mm on the CT, a tenth of the bunny's size (as ao_bench), times F.
// --surface-points: receivers at uniform random points of the surface with
// the interpolated vertex normal (a pixel's receiver) instead of vertices.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "bench_util.hpp"
#include "io/error.hpp"
#include "io/mesh.hpp"
#include "renderer/ao/disk_hierarchy.hpp"
#include "renderer/ao/reference.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/frame/camera.hpp"

using namespace iso;

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> v;
    std::stringstream ss(s);
    for (std::string t; std::getline(ss, t, sep);)
        if (!t.empty()) v.push_back(t);
    return v;
}

struct Config {
    std::string text;
    DiskAoSettings s;
    bool sided = false; // disk_occlusion_sided with the receiver's geometric normal
};

// "passes=2,t=1,k=0,min=0.7,eps=8,off=0.001,sided=1": k relative to 1 / R^2
// (k=1: halved at d = R); sided=1: disk_occlusion_sided.
Config parse(const std::string& text, double R) {
    Config c{text, {}};
    for (const auto& kv : split(text, ',')) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos) throw Error("disk_ao_cpu_bench", "bad setting '" + kv + "'");
        const std::string k = kv.substr(0, eq);
        const double v = std::stod(kv.substr(eq + 1));
        if (k == "passes")
            c.s.passes = static_cast<int>(v);
        else if (k == "t")
            c.s.triangle_attenuation = v;
        else if (k == "k")
            c.s.distance_attenuation = v / (R * R);
        else if (k == "min") {
            c.s.min_scale = v;
            c.s.max_scale = 1.0 - v;
        } else if (k == "eps")
            c.s.traversal_epsilon = v;
        else if (k == "off")
            c.s.receiver_offset = v;
        else if (k == "sided")
            c.sided = v != 0;
        else
            throw Error("disk_ao_cpu_bench", "unknown setting '" + k + "'");
    }
    return c;
}

} // namespace

int main(int argc, char** argv) try {
    std::vector<std::string> scenes{"ct-skin", "ct-bone", "bunny"};
    int samples = 2000, rays = 1024;
    bool verbose = false;
    double radius_scale = 1.0;
    bool surface_points = false;
    std::string configs = "passes=1;passes=2;passes=3;passes=4;passes=2,t=0.5;passes=2,t=2;passes=2,k=1;passes=2,k=4;"
                          "passes=2,min=1;passes=2,min=0.5";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw Error("disk_ao_cpu_bench", a + " needs a value");
            return argv[++i];
        };
        if (a == "--scenes")
            scenes = split(next(), ',');
        else if (a == "--samples")
            samples = std::stoi(next());
        else if (a == "--rays")
            rays = std::stoi(next());
        else if (a == "--configs")
            configs = next();
        else if (a == "--verbose")
            verbose = true;
        else if (a == "--radius-scale")
            radius_scale = std::stod(next());
        else if (a == "--surface-points")
            surface_points = true;
        else
            throw Error("disk_ao_cpu_bench", "unknown option '" + a + "'");
    }
    const std::string data = ISOSCOPE_DATA_DIR;
    std::printf(
        "| scene | setting | RMSE | RMSE, normal with winding | bias | max abs | element passes s | gather us/point |\n"
        "|---|---|---|---|---|---|---|---|\n");
    for (const auto& name : scenes) {
        std::vector<Mesh> meshes;
        if (name == "ct-skin" || name == "ct-bone") {
            core::Scene scene;
            scene.open(data + "/headsq.nhdr");
            for (const auto id : scene.add_isosurfaces({name == "ct-skin" ? 500.0 : 1150.0}))
                meshes.push_back(scene.mesh(id));
        } else if (name == "bunny") {
            meshes.push_back(core::open_mesh(data + "/bunny.vtp"));
        } else {
            throw Error("disk_ao_cpu_bench", "unknown scene '" + name + "'");
        }
        Bounds b;
        std::size_t tris = 0, verts = 0;
        for (const auto& m : meshes) {
            for (const auto& p : m.positions) b.add(glm::dvec3(p));
            tris += m.triangles.size();
            verts += m.positions.size();
        }
        const double R = radius_scale * (name == "bunny" ? 0.1 * 2.0 * b.radius() : 10.0);
        if (verbose)
            for (const auto& m : meshes) {
                // Do the vertex normals agree with the triangles' winding?
                std::vector<glm::dvec3> fn(m.positions.size(), glm::dvec3(0.0));
                for (const auto& t : m.triangles) {
                    const glm::dvec3 a(m.positions[t[0]]), b2(m.positions[t[1]]), c(m.positions[t[2]]);
                    for (auto v : t) fn[v] += glm::cross(b2 - a, c - a);
                }
                std::size_t against = 0;
                for (std::size_t v = 0; v < m.normals.size(); ++v)
                    if (glm::dot(fn[v], glm::dvec3(m.normals[v])) < 0) ++against;
                const MeshStats st = mesh_stats(m);
                std::fprintf(
                    stderr, "[disk_ao_cpu_bench] %s: %zu of %zu vertex normals against the winding; signed volume %g\n",
                    name.c_str(), against, m.normals.size(), st.volume);
            }

        double t0 = bench::now_s();
        std::vector<DiskHierarchy> parts;
        for (const auto& m : meshes) parts.push_back(build_disk_hierarchy(m));
        std::vector<const DiskHierarchy*> ptrs;
        for (const auto& p : parts) ptrs.push_back(&p);
        const DiskHierarchy h = parts.size() == 1 ? parts[0] : concatenate(ptrs);
        const double build_s = bench::now_s() - t0;
        std::fprintf(
            stderr, "[disk_ao_cpu_bench] %s: %zu triangles, %zu vertices, %zu nodes, %d levels, build %.3f s, R %.4g\n",
            name.c_str(), tris, verts, h.nodes.size(), h.levels, build_s, R);

        // Sample of vertices (all meshes' vertices in concatenation order).
        std::vector<glm::dvec3> ps, ns;
        std::vector<char> consistent; // vertex normal on the side of its triangles' winding
        std::vector<glm::dvec3> fns;  // the receiver's geometric normal (triangle / area-weighted triangles)
        std::vector<glm::dvec3> face_sum;
        for (const auto& m : meshes) {
            const std::size_t base = face_sum.size();
            face_sum.resize(base + m.positions.size(), glm::dvec3(0.0));
            for (const auto& t : m.triangles) {
                const glm::dvec3 a(m.positions[t[0]]), b2(m.positions[t[1]]), c(m.positions[t[2]]);
                for (auto v : t) face_sum[base + v] += glm::cross(b2 - a, c - a);
            }
        }
        std::mt19937 rng(12345);
        std::uniform_int_distribution<std::size_t> pick(0, verts - 1);
        std::vector<glm::vec3> all_pos;
        for (const auto& m : meshes) all_pos.insert(all_pos.end(), m.positions.begin(), m.positions.end());
        if (surface_points) {
            // Uniform points on the surface (triangles by area, uniform
            // barycentrics) with the interpolated vertex normal: what a
            // pixel's receiver is.
            struct Tri {
                glm::dvec3 a, b, c, na, nb, nc;
                std::size_t v0;
            };
            std::vector<Tri> tris_all;
            std::vector<double> cdf;
            double total = 0;
            std::size_t base = 0;
            for (const auto& m : meshes) {
                for (const auto& t : m.triangles) {
                    Tri q{glm::dvec3(m.positions[t[0]]),
                          glm::dvec3(m.positions[t[1]]),
                          glm::dvec3(m.positions[t[2]]),
                          {},
                          {},
                          {},
                          base + t[0]};
                    const auto nrm = [&](std::uint32_t v) {
                        const std::int32_t leaf = h.vertex_node[base + v];
                        return glm::dvec3(glm::vec3(h.nodes[static_cast<std::size_t>(leaf)].normal_bound));
                    };
                    q.na = nrm(t[0]);
                    q.nb = nrm(t[1]);
                    q.nc = nrm(t[2]);
                    total += 0.5 * glm::length(glm::cross(q.b - q.a, q.c - q.a));
                    cdf.push_back(total);
                    tris_all.push_back(q);
                }
                base += m.positions.size();
            }
            std::uniform_real_distribution<double> u01(0.0, 1.0);
            while (static_cast<int>(ps.size()) < samples) {
                const auto k =
                    static_cast<std::size_t>(std::lower_bound(cdf.begin(), cdf.end(), u01(rng) * total) - cdf.begin());
                const Tri& q = tris_all[std::min(k, tris_all.size() - 1)];
                double r1 = u01(rng), r2 = u01(rng);
                if (r1 + r2 > 1) {
                    r1 = 1 - r1;
                    r2 = 1 - r2;
                }
                const glm::dvec3 nn = (1 - r1 - r2) * q.na + r1 * q.nb + r2 * q.nc;
                if (glm::length(nn) < 1e-6) continue;
                const glm::dvec3 n = glm::normalize(nn);
                ps.push_back((1 - r1 - r2) * q.a + r1 * q.b + r2 * q.c);
                ns.push_back(n);
                consistent.push_back(glm::dot(glm::cross(q.b - q.a, q.c - q.a), n) > 0.0);
                fns.push_back(glm::cross(q.b - q.a, q.c - q.a));
            }
        }
        while (static_cast<int>(ps.size()) < samples) {
            const std::size_t v = pick(rng);
            const std::int32_t leaf = h.vertex_node[v];
            if (leaf < 0) continue;
            const glm::dvec3 n(glm::vec3(h.nodes[static_cast<std::size_t>(leaf)].normal_bound));
            if (glm::length(n) < 0.5) continue;
            ps.emplace_back(all_pos[v]);
            ns.push_back(n);
            consistent.push_back(glm::dot(face_sum[v], n) > 0.0);
            fns.push_back(face_sum[v]);
        }
        std::vector<const Mesh*> mp;
        for (const auto& m : meshes) mp.push_back(&m);
        t0 = bench::now_s();
        const AoReference reference(mp);
        AoReferenceOptions opt;
        opt.radius_mm = R;
        opt.rays = rays;
        std::vector<double> ref(ps.size());
        for (std::size_t i = 0; i < ps.size(); ++i) ref[i] = reference.at(ps[i], ns[i], opt, static_cast<unsigned>(i));
        std::fprintf(stderr, "[disk_ao_cpu_bench] %s: reference at %zu points, %.1f s\n", name.c_str(), ps.size(),
                     bench::now_s() - t0);

        for (const auto& text : split(configs, ';')) {
            const Config c = parse(text, R);
            t0 = bench::now_s();
            const auto terms = disk_element_terms(h, c.s, R);
            const double pass_s = bench::now_s() - t0;
            std::vector<double> ao(ps.size());
            t0 = bench::now_s();
            for (std::size_t i = 0; i < ps.size(); ++i)
                ao[i] = 1.0 - (c.sided ? disk_occlusion_sided(h, ps[i], ns[i], fns[i], terms, c.s, R)
                                       : disk_occlusion(h, ps[i], ns[i], terms, c.s, R));
            const double gather_us = 1e6 * (bench::now_s() - t0) / static_cast<double>(ps.size());
            double se = 0, bias = 0, worst = 0, se_c = 0;
            std::size_t worst_i = 0, n_c = 0;
            for (std::size_t i = 0; i < ps.size(); ++i) {
                const double d = ao[i] - ref[i];
                if (consistent[i]) {
                    se_c += d * d;
                    ++n_c;
                }
                se += d * d;
                bias += d;
                if (std::abs(d) > worst) worst_i = i;
                worst = std::max(worst, std::abs(d));
            }
            if (verbose) {
                double front = 0, back = 0;
                for (const auto& m : meshes)
                    for (const auto& t : m.triangles) {
                        const glm::dvec3 a(m.positions[t[0]]), b2(m.positions[t[1]]), c2(m.positions[t[2]]);
                        if (glm::length((a + b2 + c2) / 3.0 - ps[worst_i]) > R) continue;
                        const double f =
                            clipped_triangle_form_factor(ps[worst_i] + 1e-3 * R * ns[worst_i], ns[worst_i], a, b2, c2);
                        (f > 0 ? front : back) += f;
                    }
                DiskAoSettings tri = c.s;
                tri.traversal_epsilon = 1e30;
                std::fprintf(stderr,
                             "[disk_ao_cpu_bench]   worst: front-facing form factors within R %.3f, back-facing %.3f; "
                             "all-triangle traversal %.3f, first pass %.3f\n",
                             front, back, disk_occlusion(h, ps[worst_i], ns[worst_i], {}, tri, R),
                             disk_occlusion(h, ps[worst_i], ns[worst_i], {}, c.s, R));
            }
            if (verbose)
                std::fprintf(stderr,
                             "[disk_ao_cpu_bench]   worst at (%g %g %g) n (%.3f %.3f %.3f), geometric normal with it: "
                             "%d: disk %.3f, Embree %.3f\n",
                             ps[worst_i].x, ps[worst_i].y, ps[worst_i].z, ns[worst_i].x, ns[worst_i].y, ns[worst_i].z,
                             int(consistent[worst_i]), ao[worst_i], ref[worst_i]);
            std::printf("| %s | %s | %.4f | %.4f | %+.4f | %.3f | %.2f | %.0f |\n", name.c_str(), text.c_str(),
                        std::sqrt(se / ps.size()), std::sqrt(se_c / std::max<std::size_t>(n_c, 1)), bias / ps.size(),
                        worst, pass_s, gather_us);
            std::fflush(stdout);
        }
    }
    return 0;
} catch (const std::exception& e) {
    std::cerr << "disk_ao_cpu_bench: " << e.what() << "\n";
    return 1;
}
