// The rule for what fits a volume, shared by the Surfaces and Volume
// panels, the workspace and the CLI: a volume is CT in Hounsfield units
// when its unit is HU (core::value_unit: the modality says CT, or the
// values were rescaled to HU) and its values lie in CT's range; the CT
// presets (window/level, iso values, transfer functions) fit only such a
// volume, and the others get defaults made from their value range.
#pragma once

#include "renderer/core/scene.hpp"
#include "renderer/volume/transfer_function.hpp"

namespace iso::core {

// The scene's volume is CT in HU with HU-like values (-1100 .. 5000).
bool ct_in_hu(const Scene& scene);

// For values [lo, hi] that are not CT: transparent below a third of the
// range, rising to a faint warm colour and to opaque white at the top.
TransferFunction default_transfer_function(double lo, double hi);

// The transfer function a volume starts with: the "bone" preset for CT in
// HU, else default_transfer_function over its value range (a scene
// without a volume: "bone").
TransferFunction initial_transfer_function(const Scene& scene);

} // namespace iso::core
