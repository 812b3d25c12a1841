// What a volume's values are measured in, and how a readout writes a value at
// a point: one rule for the CLI's pick and measure (text and JSON), the
// desktop app's 3D and slice readouts and its iso value fields, so they
// cannot disagree about when a number is in Hounsfield units.
#pragma once

#include <string>
#include <string_view>

#include "io/volume.hpp"

namespace iso::core {

class Scene;

// The Hounsfield unit: the stored values of a CT volume (after the DICOM
// rescale) are in it.
inline constexpr std::string_view kHounsfieldUnit = "HU";

// "HU" when the volume is CT (its modality, from DICOM or a MetaImage header,
// is "CT"); otherwise none (empty): MR, and every volume whose format does not
// say (NRRD, NIfTI, VTI, OpenVDB, a MetaImage file without a modality).
std::string_view value_unit(const Metadata& meta);
std::string_view value_unit(const Volume& v);
// The unit of the scene's volume; none when the scene has no volume.
std::string_view value_unit(const Scene& scene);

// The readout of a value at a point: "1234.50 HU" with a unit, "value 1234.50"
// without (`decimals` digits after the point); "value undefined" for NaN or
// an infinity (a NaN sample).
std::string value_readout(double value, std::string_view unit, int decimals = 2);

} // namespace iso::core
