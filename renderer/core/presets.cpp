#include "renderer/core/presets.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "renderer/core/value_unit.hpp"

namespace iso::core {

namespace {

// Values that look like HU: the lowest is air (about -1000 HU; -1024 where
// the scanner pads), the highest below 5000 (dense bone and contrast reach
// about 3000; metal is clipped by most scanners near 3071).
bool hu_like(const ValueRange& r) { return r.min >= -1100 && r.min <= -900 && r.max <= 5000; }

std::string number(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

} // namespace

bool ct_in_hu(const Scene& scene) {
    if (!scene.has_volume()) return false;
    const Metadata& m = scene.volume().meta;
    if (!value_unit(scene).empty()) return true; // the modality says CT: its values are HU
    return m.modality.empty() && hu_like(scene.value_range());
}

std::vector<double> value_histogram(const Volume& v, double lo, double hi, int bins, std::int64_t samples) {
    std::vector<double> counts(std::size_t(std::max(bins, 1)), 0.0);
    const double n = double(std::max<std::int64_t>(1, v.voxel_count()));
    const auto stride =
        std::max<std::int64_t>(1, std::int64_t(std::ceil(std::cbrt(n / double(std::max<std::int64_t>(1, samples))))));
    const double width = hi > lo ? hi - lo : 1.0;
    const int last = int(counts.size()) - 1;
    for (std::int64_t k = 0; k < v.dims[2]; k += stride)
        for (std::int64_t j = 0; j < v.dims[1]; j += stride)
            for (std::int64_t i = 0; i < v.dims[0]; i += stride) {
                const double x = v.value(i, j, k);
                if (!std::isfinite(x)) continue;
                counts[std::size_t(std::clamp(int((x - lo) / width * double(counts.size())), 0, last))] += 1;
            }
    return counts;
}

// Exhaustive over the bin edges (two classes: O(bins), three: O(bins^2)),
// with prefix sums of the counts and the first moments.
std::vector<double> otsu_thresholds(const std::vector<double>& counts, double lo, double hi, int classes) {
    const std::size_t n = counts.size();
    if (n < 2 || classes < 2 || classes > 3) return {};
    std::vector<double> w(n + 1, 0.0), mu(n + 1, 0.0); // prefix sums
    for (std::size_t i = 0; i < n; ++i) {
        w[i + 1] = w[i] + counts[i];
        mu[i + 1] = mu[i] + counts[i] * (double(i) + 0.5);
    }
    if (w[n] <= 0) return {};
    // A class [a, b) of bins: its share of the between-class variance, sum of w * mean^2.
    const auto term = [&](std::size_t a, std::size_t b) {
        const double wc = w[b] - w[a];
        return wc > 0 ? (mu[b] - mu[a]) * (mu[b] - mu[a]) / wc : 0.0;
    };
    const auto value = [&](std::size_t edge) { return lo + (hi - lo) * double(edge) / double(n); };
    double best = -1;
    std::vector<double> out;
    if (classes == 2) {
        for (std::size_t t = 1; t < n; ++t)
            if (const double s = term(0, t) + term(t, n); s > best) best = s, out = {value(t)};
        return out;
    }
    for (std::size_t t1 = 1; t1 + 1 < n; ++t1)
        for (std::size_t t2 = t1 + 1; t2 < n; ++t2)
            if (const double s = term(0, t1) + term(t1, t2) + term(t2, n); s > best)
                best = s, out = {value(t1), value(t2)};
    return out;
}

std::vector<IsoPreset> iso_presets(const Scene& scene) {
    std::vector<IsoPreset> out;
    if (!scene.has_volume()) return out;
    const bool ct = ct_in_hu(scene);
    const ValueRange r = scene.value_range();
    // Rules of thumb for calibrated CT (docs/gui.md), not tuned on a dataset here.
    std::vector<IsoPreset> hu = {
        {"bone", 300, true}, {"skin", -500, true}, {"soft tissue", 20, true}, {"contrast-filled vessels", 200, true}};
    for (auto& p : hu) {
        if (!ct) {
            p.enabled = false;
            p.why_not = "For CT in Hounsfield units; this volume's values are not HU";
        } else if (p.value < r.min || p.value > r.max) {
            p.enabled = false;
            p.why_not = "Outside this volume's values (" + number(r.min) + " to " + number(r.max) + ")";
        }
    }
    if (!ct && r.max > r.min) {
        constexpr int kBins = 256;
        const auto counts = value_histogram(scene.volume(), r.min, r.max, kBins);
        const auto two = otsu_thresholds(counts, r.min, r.max, 2);
        const auto three = otsu_thresholds(counts, r.min, r.max, 3);
        // Rounded to the volume's precision for the eye: a bin is (max - min) / 256 wide.
        const double step = std::pow(10.0, std::floor(std::log10((r.max - r.min) / kBins)));
        const auto round = [step](double v) { return std::round(v / step) * step; };
        if (!two.empty()) out.push_back({"foreground (Otsu)", round(two[0])});
        if (three.size() == 2) out.push_back({"bright structures (3-class Otsu)", round(three[1])});
    }
    out.insert(out.end(), hu.begin(), hu.end());
    return out;
}

TransferFunction default_transfer_function(double lo, double hi) {
    if (!(hi > lo)) hi = lo + 1;
    const auto at = [&](double f) { return lo + f * (hi - lo); };
    return TransferFunction({{at(0.0), 0.0, "#000000"},
                             {at(0.3), 0.0, "#c08060"},
                             {at(0.5), 0.02, "#e0b090"},
                             {at(0.8), 0.2, "#f0e0c8"},
                             {at(1.0), 0.5, "#ffffff"}});
}

TransferFunction initial_transfer_function(const Scene& scene) {
    if (!scene.has_volume() || ct_in_hu(scene)) return transfer_function_from("bone");
    const ValueRange r = scene.value_range();
    return default_transfer_function(r.min, r.max);
}

} // namespace iso::core
