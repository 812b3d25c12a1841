// A CT-like synthetic volume for benchmarks: air, an elliptic body of soft
// tissue with noise, a bone shell (skull-like) and contrast-filled vessels,
// int16 Hounsfield units. Deterministic for a given size and seed.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <unistd.h>

#include <glm/glm.hpp>
#include <tbb/parallel_for.h>

#include "io/volume.hpp"

namespace iso::bench {

inline Volume ct_phantom(std::array<std::int64_t, 3> dims, glm::dvec3 spacing = {0.7, 0.7, 1.0}, unsigned seed = 1) {
    auto v = Volume::dense(dims, VoxelType::I16, make_affine(spacing, {0, 0, 0}));
    v.meta.modality = "CT";
    v.meta.source = "synthetic CT phantom";
    const glm::dvec3 ext = glm::dvec3(dims[0], dims[1], dims[2]) * spacing;
    const glm::dvec3 c = ext * 0.5;
    const glm::dvec3 body = ext * glm::dvec3(0.42, 0.36, 0.46); // semi-axes
    // Vessels: a few tubes wandering along z.
    struct Tube {
        double x0, y0, ax, ay, fx, fy, r;
    };
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Tube> tubes;
    for (int i = 0; i < 12; ++i)
        tubes.push_back({c.x + (u(rng) - 0.5) * body.x, c.y + (u(rng) - 0.5) * body.y, 5 + 15 * u(rng), 5 + 15 * u(rng),
                         0.01 + 0.03 * u(rng), 0.01 + 0.03 * u(rng), 1.5 + 4 * u(rng)});
    auto s = v.as<std::int16_t>();
    tbb::parallel_for(std::int64_t(0), dims[2], [&](std::int64_t k) {
        std::mt19937 r(seed * 7919u + unsigned(k));
        std::normal_distribution<double> noise(0.0, 12.0);
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const glm::dvec3 p = glm::dvec3(i, j, k) * spacing;
                const glm::dvec3 q = (p - c) / body;
                const double rho = glm::length(q); // 1 on the body surface
                double hu = -1000.0 + noise(r) * 0.3;
                if (rho < 1.0) {
                    hu = 40.0 + noise(r);
                    // bone shell between rho 0.78 and 0.86, thickness varying with angle
                    const double shell = 0.82 + 0.02 * std::sin(6 * std::atan2(q.y, q.x)) * std::cos(4 * q.z);
                    if (std::abs(rho - shell) < 0.035) hu = 1100.0 + 300.0 * std::cos(9 * q.x) + noise(r);
                    for (const auto& t : tubes) {
                        const double tx = t.x0 + t.ax * std::sin(t.fx * p.z), ty = t.y0 + t.ay * std::cos(t.fy * p.z);
                        const double d = std::hypot(p.x - tx, p.y - ty);
                        if (d < t.r) hu = std::max(hu, 300.0 + noise(r));
                    }
                }
                s[v.linear_index(i, j, k)] = std::int16_t(std::lround(std::clamp(hu, -1024.0, 3071.0)));
            }
    });
    return v;
}

// ct_phantom(size) cached as raw int16 in the temporary folder (it takes
// seconds to make; benchmark children share the copy).
inline Volume cached_ct_phantom(std::array<std::int64_t, 3> size) {
    namespace fs = std::filesystem;
    const std::string cache =
        (fs::temp_directory_path() / ("isoscope-phantom-" + std::to_string(size[0]) + "x" + std::to_string(size[1]) +
                                      "x" + std::to_string(size[2]) + ".raw"))
            .string();
    auto v = Volume::dense(size, VoxelType::I16, make_affine({0.7, 0.7, 1.0}, {0, 0, 0}));
    std::ifstream in(cache, std::ios::binary);
    if (in && fs::file_size(cache) == v.bytes().size()) {
        in.read(reinterpret_cast<char*>(v.bytes().data()), std::streamsize(v.bytes().size()));
        return v;
    }
    v = ct_phantom(size);
    const std::string tmp = cache + ".tmp" + std::to_string(::getpid());
    std::ofstream(tmp, std::ios::binary)
        .write(reinterpret_cast<const char*>(v.bytes().data()), std::streamsize(v.bytes().size()));
    fs::rename(tmp, cache);
    return v;
}

} // namespace iso::bench
