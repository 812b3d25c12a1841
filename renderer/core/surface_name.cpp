#include "renderer/core/surface_name.hpp"

#include <cstdio>

namespace iso::core {

std::string value_text(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return text;
}

std::string surface_name(bool label, double value) { return (label ? "label " : "iso ") + value_text(value); }

std::string surface_file_suffix(bool label, double value) { return (label ? "-label" : "-iso") + value_text(value); }

} // namespace iso::core
