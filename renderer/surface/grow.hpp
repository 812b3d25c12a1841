// Growing a region from a seed (3D Slicer's threshold-limited flood fill,
// ITK's ConnectedThresholdImageFilter): the voxels joined to the seed
// through faces (6-connectivity) whose values lie within [lo, hi], and, with
// a box, whose centres lie inside it. What separates a structure from one
// it only touches: a nidus grown within its value range stops where the
// draining vein's values leave it, or at the box (docs/measure.md, "Grown
// regions").
#pragma once

#include <array>
#include <cstddef>
#include <optional>

#include <glm/vec3.hpp>

#include "io/progress.hpp"
#include "io/volume.hpp"
#include "renderer/surface/box_clip.hpp"

namespace iso {

struct GrowOptions {
    double lo = 0, hi = 0;        // the values grown through, inclusive
    std::optional<LpsBox> within; // voxel centres outside are never grown into
    bool operator==(const GrowOptions&) const = default;
};

// How a grown region was made (kept with its surface: a session grows it again).
struct GrownFrom {
    glm::dvec3 seed{0.0}; // LPS mm
    GrowOptions options;
    bool operator==(const GrownFrom&) const = default;
};

struct GrownRegion {
    Volume mask;                        // uint8 on the volume's grid: 1 in the region, 0 elsewhere
    std::array<std::int64_t, 3> seed{}; // the seed's voxel (the one nearest the seed point)
    std::size_t voxels = 0;
    // Region voxels with a face neighbour outside the region: where the
    // boundary runs through partly filled voxels.
    std::size_t boundary_voxels = 0;
    double voxel_mm3 = 0; // one voxel's volume
    double volume_ml = 0; // voxels x voxel_mm3
    // The partial-volume uncertainty: half the boundary voxels' volume (a
    // boundary voxel is anywhere from empty to full; counted whole, the
    // region is within this of the structure it samples).
    double partial_volume_ml = 0;
    bool reached_box = false;    // stopped at the box somewhere
    bool reached_border = false; // stopped at the volume's edge somewhere
};

// Throws iso::Error: a sparse volume, a seed outside the volume (or the
// box), a range that is empty or not finite, or a seed voxel whose value is
// outside the range (the message gives it).
GrownRegion grow_region(const Volume& v, const glm::dvec3& seed_lps, const GrowOptions& o,
                        const ProgressFn& progress = {});

// A seed for a point on a structure's isosurface (a click lands there,
// between voxels in and out of the range, so the voxel nearest it may be
// out): the first point from `at` along `forward` (into what was clicked),
// half the smallest voxel spacing at a time up to three voxels, whose
// nearest voxel (grow_region's seed voxel) is within [lo, hi]. None when
// there is no such point.
std::optional<glm::dvec3> seed_within(const Volume& v, const glm::dvec3& at, const glm::dvec3& forward, double lo,
                                      double hi);

} // namespace iso
