// Error of an AO image against a reference over the pixels where both are
// finite (the foreground): bias, MAE, RMSE, p95 and p99 of |error|
// (the figures docs/ao.md reports). Used by the AO benchmark and the AO tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "io/image.hpp"

namespace iso {

struct AoError {
    double bias = 0, mae = 0, rmse = 0, p95 = 0, p99 = 0, max = 0;
    double reference_noise_rms = 0; // expected RMS noise of the reference itself
    std::size_t pixels = 0;
};

// `rays`: the reference's rays per pixel, to estimate its own noise
// (binomial: sqrt(mean of a(1-a)/N)); 0: not estimated.
inline AoError ao_error(const Image& ao, const Image& ref, int rays = 0) {
    AoError e;
    std::vector<double> abs_err;
    double sum = 0, sum_abs = 0, sum_sq = 0, var = 0;
    const std::size_t n = std::min(ao.floats.size(), ref.floats.size());
    for (std::size_t i = 0; i < n; ++i) {
        const double a = ao.floats[i], r = ref.floats[i];
        if (!std::isfinite(a) || !std::isfinite(r)) continue;
        const double d = a - r;
        sum += d;
        sum_abs += std::abs(d);
        sum_sq += d * d;
        abs_err.push_back(std::abs(d));
        if (rays > 0) var += r * (1.0 - r) / rays;
    }
    e.pixels = abs_err.size();
    if (e.pixels == 0) return e;
    const double m = double(e.pixels);
    e.bias = sum / m;
    e.mae = sum_abs / m;
    e.rmse = std::sqrt(sum_sq / m);
    e.reference_noise_rms = std::sqrt(var / m);
    std::sort(abs_err.begin(), abs_err.end());
    auto q = [&](double p) { return abs_err[std::min(abs_err.size() - 1, std::size_t(p * double(abs_err.size())))]; };
    e.p95 = q(0.95);
    e.p99 = q(0.99);
    e.max = abs_err.back();
    return e;
}

// Cosine-weighted visibility at the foot of an infinite wall at distance d,
// rays limited to R: directions project uniformly onto the unit disk, and
// the wall blocks the segment x >= d/R of it.
inline double wall_ao(double d, double R) {
    const double a = std::min(d / R, 1.0);
    return 1.0 - (std::acos(a) - a * std::sqrt(1.0 - a * a)) / M_PI;
}

} // namespace iso
