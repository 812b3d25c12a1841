#include "renderer/ao/cone_pattern.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <glm/glm.hpp>

namespace iso {

namespace {
constexpr double kPi = 3.14159265358979323846;
} // namespace

std::vector<glm::vec4> cone_directions(int n) {
    std::vector<glm::vec4> out;
    out.reserve(std::size_t(n));
    // Each cone gets 1/n of the hemisphere's solid angle: 2 pi (1 - cos a) = 2 pi / n.
    const double cos_a = n == 1 ? 0.0 : 1.0 - 1.0 / n;
    const double sin_a = std::sqrt(1.0 - cos_a * cos_a);
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < n; ++k) {
        // Sunflower: equal-area cells of the unit disk; lifted, equal cosine-weighted measure.
        const double r = n == 1 ? 0.0 : std::sqrt((k + 0.5) / n);
        const double phi = k * golden;
        const double x = r * std::cos(phi), y = r * std::sin(phi);
        out.emplace_back(float(x), float(y), float(std::sqrt(std::max(0.0, 1.0 - r * r))), float(sin_a));
    }
    return out;
}

std::vector<glm::vec2> poisson_disk(int n, std::uint32_t seed) {
    // Dart throwing in the unit square with wrap-around distances (so the
    // density is the same everywhere, edges included), then Shirley and
    // Chiu's concentric map, which carries uniform density on the square to
    // uniform density on the disk. Dart throwing straight in the disk would
    // crowd the rim (points there have fewer neighbours to reject them) and
    // bias every volume estimate toward the sphere's outer columns.
    std::mt19937 rng(seed * 2654435761u + 12345u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double d = n > 1 ? 0.9 / std::sqrt(double(n)) : 0.0; // ~0.85 of the hexagonal packing distance
    std::vector<glm::dvec2> pts;
    int fails = 0;
    while (int(pts.size()) < n) {
        const glm::dvec2 c(u(rng), u(rng));
        bool ok = true;
        for (const auto& p : pts) {
            glm::dvec2 e = glm::abs(p - c);
            e = glm::min(e, 1.0 - e);
            if (glm::dot(e, e) < d * d) {
                ok = false;
                break;
            }
        }
        if (ok) {
            pts.push_back(c);
            fails = 0;
        } else if (++fails > 200) {
            d *= 0.95;
            fails = 0;
        }
    }
    std::vector<glm::vec2> out;
    for (const auto& p : pts) {
        const double a = 2 * p.x - 1, b = 2 * p.y - 1;
        double r, phi;
        if (a == 0 && b == 0) {
            r = phi = 0;
        } else if (std::abs(a) > std::abs(b)) {
            r = a;
            phi = kPi / 4 * (b / a);
        } else {
            r = b;
            phi = kPi / 2 - kPi / 4 * (a / b);
        }
        out.emplace_back(float(r * std::cos(phi)), float(r * std::sin(phi)));
    }
    return out;
}

std::vector<glm::vec4> cone_pattern(const ConeAoSettings& s, std::uint32_t frame) {
    std::vector<glm::vec4> out = cone_directions(s.cones);
    std::mt19937 rng(0x9E3779B9u ^ (frame * 0x85EBCA6Bu + 17u));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int J = s.jitter_sets;
    // Rotations about the normal stratified over the sets (a fresh offset each frame).
    // Sphere offsets along the cone stratified too, in shuffled order: with
    // independent offsets, one frame's few sets could all place their spheres
    // near (or far), and that frame's whole image would be darker (or
    // lighter) than the mean the still frames converge to.
    const double base = u(rng);
    std::vector<int> strata(std::size_t(J), 0);
    for (int j = 0; j < J; ++j) strata[std::size_t(j)] = j;
    std::shuffle(strata.begin(), strata.end(), rng);
    std::vector<glm::vec4> sets, samples;
    for (int j = 0; j < J; ++j) {
        const double a = 2.0 * kPi * (j + base) / J;
        const double offset = (strata[std::size_t(j)] + u(rng)) / J - 0.5;
        sets.emplace_back(float(std::cos(a)), float(std::sin(a)), float(offset), 0.0f);
        const auto disk = poisson_disk(s.samples, std::uint32_t(frame * 7919u + std::uint32_t(j) * 104729u + 1u));
        const double b = 2.0 * kPi * u(rng); // the disk pattern also turns
        for (const auto& p : disk)
            samples.emplace_back(float(std::cos(b) * p.x - std::sin(b) * p.y),
                                 float(std::sin(b) * p.x + std::cos(b) * p.y), 0.0f, 0.0f);
    }
    out.insert(out.end(), sets.begin(), sets.end());
    out.insert(out.end(), samples.begin(), samples.end());
    return out;
}

} // namespace iso
