// Mesh post-processing through VTK, with the settings users know from 3D
// Slicer: windowed-sinc smoothing, quadric decimation, keep the largest
// connected component. Positions stay in LPS mm; normals are recomputed.
#pragma once

#include <optional>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/progress.hpp"
#include "renderer/surface/box_clip.hpp"

namespace iso {

struct PostProcessOptions {
    // 0 (off) .. 1 (strong). Maps to vtkWindowedSincPolyDataFilter with
    // pass band 10^(-4 * smooth) and 20 iterations, as Slicer's "smoothing
    // factor" does; boundary and feature edges are left free, normalization on.
    double smooth = 0.0;
    // Fraction of triangles to remove, 0 (off) .. <1 (vtkQuadricDecimation,
    // volume preservation on).
    double decimate = 0.0;
    // Keep only the largest connected component (by triangle count).
    bool keep_largest = false;
    // Keep only the connected component nearest to this LPS point (3D
    // Slicer's "keep selected island"; the Isolate tool): the component of
    // the triangle nearest to it, as measure_surface numbers components.
    // Applied before the largest is kept, smoothing and decimation.
    std::optional<glm::dvec3> keep_at;
    // Keep only the part within this LPS box, cut at its faces and capped
    // (clip_to_box); with keep_at, the piece of that part nearest the point
    // (a structure separated from the tree it touches). Applied after
    // keep_at, before the rest.
    std::optional<LpsBox> keep_within;
    bool operator==(const PostProcessOptions&) const = default;
};

bool needs_postprocess(const PostProcessOptions& o);

// The connected component of `m` nearest to `at` (PostProcessOptions::keep_at),
// as it is: no normals recomputed. An empty mesh stays empty.
Mesh component_at(const Mesh& m, const glm::dvec3& at);

// Throws iso::Error for options out of range. An empty mesh stays empty.
Mesh postprocess(const Mesh& m, const PostProcessOptions& o, const ProgressFn& progress = {});

} // namespace iso
