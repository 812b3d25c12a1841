// The CPU ray march of the stated model (transfer_function.hpp), in double
// precision: the reference the GPU passes are checked and benchmarked
// against, and what picking on the volume marches. One ray at a time, from
// an origin along a unit direction, t in mm; the caller makes the rays
// (Camera::pixel_ray) and lists the surfaces the ray passes through.
//
// Sampling, the same as the GPU pass: the ray's interval inside the index
// box, the clip and [t_near, t_far] is cut at every surface layer; each
// piece of length L is divided into n = ceil(L / step) equal steps, sampled
// at their midpoints, each step of opacity a transmitting (1 - a)^(L / n)
// (exact for constant values, whatever the step). MIP and MinIP sample the
// whole interval at n + 1 points, ends included (an axis-aligned ray through
// voxel centres, stepped one voxel, meets every voxel of its column), and
// put the extreme value's colour, with its opacity as a plain alpha, at its
// place among the surfaces. Colour is the transfer function's, or shaded by
// the gradient as the GPU shades it (VolumeLighting).
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "io/volume.hpp"
#include "renderer/volume/preintegration.hpp"
#include "renderer/volume/transfer_function.hpp"

namespace iso {

// Trilinear values in the index box [0, n-1] per axis (NaN samples count as
// the lowest finite value of the volume, as the extractor's range index has it).
class VolumeSampler {
public:
    // `range`: the volume's value range when known (else computed for float data).
    explicit VolumeSampler(const Volume& v, std::optional<ValueRange> range = std::nullopt);
    const Volume& volume() const { return v_; }
    // The value at a continuous index inside the box (clamped onto it).
    double at_index(const glm::dvec3& ijk) const;
    glm::dvec3 to_index(const glm::dvec3& lps) const; // LPS mm -> continuous index
    glm::dvec3 dims_max() const { return hi_; }       // n - 1 per axis
    // The ray's interval inside the box (t along origin + t dir, dir in LPS);
    // none when it misses.
    std::optional<std::pair<double, double>> box_interval(const glm::dvec3& origin, const glm::dvec3& dir) const;
    double min_spacing() const;

private:
    double raw(std::int64_t i, std::int64_t j, std::int64_t k) const;
    const Volume& v_;
    glm::dmat4 to_index_{1.0};
    glm::dvec3 hi_{0.0};
    double nan_value_ = 0, lo_ = 0, hi_value_ = 0;
    bool finite_check_ = false; // float data: NaN substituted, Inf clamped
};

// A surface the ray passes through, t mm from the origin; alpha 1 ends the ray.
struct RayLayer {
    double t = 0;
    glm::dvec3 color{0.0}; // linear RGB (as shaded)
    double alpha = 1;
};

struct RayResult {
    glm::dvec3 color{0.0};    // linear RGB, premultiplied: what the ray adds
    double transmittance = 1; // of everything along it (the background's share)
    // Where the volume's own accumulated opacity (the surfaces left out)
    // reaches 0.5 (composite; MIP/MinIP: where the extreme value is, when
    // its opacity reaches 0.5), with the value there.
    std::optional<double> t_half;
    double value_half = 0;
    // MIP/MinIP: the extreme value and where it is (none: the ray misses the volume).
    std::optional<double> extreme;
    double t_extreme = 0;
    std::size_t samples = 0;
};

// Gradient shading as the GPU march does it (volume_march.glsl,
// vol_shaded; shading.glsl, shade): the gradient by central differences of
// one voxel in index space (clamped to the box), turned into view space,
// the surfaces' key light and headlight (no AO) and tone mapping, faded in
// with the gradient's magnitude up to `gradient_ref` (value per mm).
struct VolumeLighting {
    glm::dmat3 gradient_to_view{1.0}; // index-space gradient -> view space
    double gradient_ref = 1;
};
// The lighting of a frame whose world -> view rotation is `world_to_view`.
VolumeLighting volume_lighting(const VolumeSampler& s, const TransferFunction& tf, const glm::dmat3& world_to_view);
// A colour (linear) shaded at continuous index `ijk`.
glm::dvec3 shade_volume_sample(const VolumeSampler& s, const VolumeLighting& l, const glm::dvec3& ijk,
                               const glm::dvec3& color);

// The interval [t0, t1] of the ray kept by the box, the clip and near/far; none when empty.
std::optional<std::pair<double, double>> ray_interval(const VolumeSampler& s, const Clip& clip,
                                                      const glm::dvec3& origin, const glm::dvec3& dir, double t_near,
                                                      double t_far);

// Marches one ray; `layers` in any order; `step_mm` the sample step;
// stops once the transmittance is below `epsilon` (0: never). The stated
// model's sampling (the reference) unless `tables` are given: then the
// composite march is pre-integrated (preintegration.hpp) with those
// tables, as the GPU's first frame marches it (look.integration is not
// read: the reference stays the reference whatever the look). With
// `lighting`, each sample (pre-integrated: each segment, at its middle) is
// shaded as the GPU shades it; without, flat (look.shading is not read).
RayResult march_ray(const VolumeSampler& s, const VolumeLook& look, const Clip& clip, const glm::dvec3& origin,
                    const glm::dvec3& dir, double t_near, double t_far, std::span<const RayLayer> layers,
                    double step_mm, double epsilon = 0, const TransferTables* tables = nullptr,
                    const VolumeLighting* lighting = nullptr);

} // namespace iso
