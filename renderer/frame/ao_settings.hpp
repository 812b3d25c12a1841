// Disk-based ambient occlusion on the GPU (docs/ao.md, "Disk AO on the
// GPU"): the settings' checks and comparison.
// The hierarchy and the CPU evaluation are renderer/ao/disk_hierarchy.hpp,
// the kernels renderer/ao/disk_geometry.hpp, the passes
// renderer/passes/disk_*.cpp with shaders/ao/disk_*.
#pragma once

#include "renderer/ao/disk_geometry.hpp"

namespace iso {

// Checks ranges; throws iso::Error naming the offending setting.
void validate(const DiskAoSettings& s);

// Every member equal (the element terms depend on all of them).
bool same_settings(const DiskAoSettings& a, const DiskAoSettings& b);

} // namespace iso
