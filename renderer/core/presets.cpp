#include "renderer/core/presets.hpp"

#include "renderer/core/value_unit.hpp"

namespace iso::core {

bool ct_in_hu(const Scene& scene) {
    if (!scene.has_volume() || value_unit(scene).empty()) return false;
    const ValueRange r = scene.value_range();
    return r.min >= -1100 && r.max <= 5000;
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
