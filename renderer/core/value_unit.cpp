#include "renderer/core/value_unit.hpp"

#include <cmath>
#include <cstdio>

#include "renderer/core/scene.hpp"

namespace iso::core {

std::string_view value_unit(const Metadata& meta) {
    return meta.modality == "CT" ? kHounsfieldUnit : std::string_view{};
}

std::string_view value_unit(const Volume& v) { return value_unit(v.meta); }

std::string_view value_unit(const Scene& scene) {
    return scene.has_volume() ? value_unit(scene.volume()) : std::string_view{};
}

std::string value_readout(double value, std::string_view unit, int decimals) {
    if (!std::isfinite(value)) return "value undefined";
    char number[64];
    std::snprintf(number, sizeof number, "%.*f", decimals, value);
    if (unit.empty()) return std::string("value ") + number;
    return std::string(number) + " " + std::string(unit);
}

} // namespace iso::core
