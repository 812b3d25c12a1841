// Mesh post-processing through VTK, with the settings users know from 3D
// Slicer: windowed-sinc smoothing, quadric decimation, keep the largest
// connected component. Positions stay in LPS mm; normals are recomputed.
#pragma once

#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "io/mesh.hpp"
#include "io/progress.hpp"
#include "renderer/surface/box_clip.hpp"
#include "renderer/surface/scissors.hpp"

namespace iso {

// One step in the making of a part after everything else (a Scissors cut,
// or Isolate on a part cut already): the part within a box, then the
// connected piece nearest a point (either or both), or the part inside
// (outside) an outline swept along a view. Kept in order with the surface,
// so that a session or a moved iso value makes the same part again.
struct PartStep {
    std::optional<LpsBox> within;
    std::optional<glm::dvec3> keep_at;
    std::optional<ViewOutline> outline;
    bool operator==(const PartStep&) const = default;
};

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
    // Applied last, in order, to the surface as the rest made it (smoothed,
    // decimated): the cuts a user made on it.
    std::vector<PartStep> steps;
    bool operator==(const PostProcessOptions&) const = default;
};

// The surface is a part of what was extracted: a component kept (at a
// point, or the largest), a part within a box, or cut by steps.
bool keeps_a_part(const PostProcessOptions& o);
// The last component kept at a point (keep_at, or the last step's), if any.
std::optional<glm::dvec3> kept_at(const PostProcessOptions& o);

// `steps` applied to `m` in order (PostProcessOptions::steps). Throws
// iso::Error for a bad outline or a non-finite point.
Mesh apply_steps(const Mesh& m, const std::vector<PartStep>& steps);

bool needs_postprocess(const PostProcessOptions& o);

// The connected component of `m` nearest to `at` (PostProcessOptions::keep_at),
// as it is: no normals recomputed. An empty mesh stays empty.
Mesh component_at(const Mesh& m, const glm::dvec3& at);

// Throws iso::Error for options out of range. An empty mesh stays empty.
Mesh postprocess(const Mesh& m, const PostProcessOptions& o, const ProgressFn& progress = {});

} // namespace iso
