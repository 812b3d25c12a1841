// What fits a volume, one rule for the Surfaces and Volume panels, the
// workspace and the CLI (docs/gui.md "Presets"): CT's presets (window/level,
// iso values and transfer functions in Hounsfield units) fit a volume that
// is CT (its modality says so: its values are HU), or one whose file names
// no modality but whose values look like HU (the lowest near air, -1100 to
// -900 HU, the highest below 5000: a CT saved as NIfTI or NRRD). Other volumes (MR, and values that are not HU) get
// presets made from their own values: thresholds that split the histogram
// (Otsu), and a transfer function over their range. No preset is named
// after a dataset.
#pragma once

#include <string>
#include <vector>

#include "renderer/core/scene.hpp"
#include "renderer/volume/transfer_function.hpp"

namespace iso::core {

// CT's presets fit the scene's volume (the rule above); false without a volume.
bool ct_in_hu(const Scene& scene);

// Counts per equal bin over [lo, hi] of a regular subsample of at most
// `samples` voxels (finite values only): cheap enough for the GUI thread.
std::vector<double> value_histogram(const Volume& v, double lo, double hi, int bins, std::int64_t samples = 2'000'000);

// Otsu's thresholds of a histogram over [lo, hi]: the value that best splits
// it in two classes (one threshold), or in three (two thresholds, ascending:
// the multi-level method), maximising the between-class variance.
std::vector<double> otsu_thresholds(const std::vector<double>& counts, double lo, double hi, int classes);

struct IsoPreset {
    std::string name; // "bone", "foreground (Otsu)"
    double value = 0;
    bool hu = false;     // a CT preset, in HU
    bool enabled = true; // fits this volume
    std::string why_not; // when not: why (a tooltip)
};
// The iso presets for the scene's volume, the one to start with first: for
// CT in HU bone (300), then skin (-500), soft tissue (20), contrast-filled
// vessels (200); for other volumes the two-class Otsu threshold
// ("foreground") and the upper one of three classes ("bright structures"),
// then the CT presets disabled, saying why. Empty without a volume.
std::vector<IsoPreset> iso_presets(const Scene& scene);

// For values [lo, hi] that are not CT: transparent below a third of the
// range, rising to a faint warm colour and to opaque white at the top.
TransferFunction default_transfer_function(double lo, double hi);

// The transfer function a volume starts with: the "bone" preset when CT's
// presets fit, else default_transfer_function over its value range (a
// scene without a volume: "bone").
TransferFunction initial_transfer_function(const Scene& scene);

} // namespace iso::core
