// The legend of an annotated frame (Annotations::legend): what the scene's
// visible surfaces are, for `isoscope render`, File > Export image and the
// desktop app's 3D view alike.
#pragma once

#include <vector>

#include "renderer/frame/annotations.hpp"
#include "renderer/frame/frame.hpp"

namespace iso::core {

class Scene;

// One entry per visible surface, in the scene's order: its name, colour
// (linear RGB) and opacity (1 when `look` draws every surface opaque), and
// for an isosurface its iso value with the volume's unit (value_unit: "500
// HU" for CT; "500" when the volume does not say, shown only when the name
// is not already "iso 500"). Label and mesh surfaces have no value.
std::vector<Annotations::LegendEntry> legend_entries(const Scene& scene, const FrameLook& look);

} // namespace iso::core
