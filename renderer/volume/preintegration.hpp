// The transfer function as tables (docs/volume.md, "Pre-integration"): what
// the GPU march reads per sample instead of searching the points, and the
// pre-integrated classification of a ray segment (Engel, Kraus and Ertl
// 2001) in the integral-function form of Lum, Wilson and Ma (2004).
//
// The stated model (transfer_function.hpp) gives, per value v, a colour
// c(v) (linear light) and an opacity a(v) per mm, i.e. an extinction
// tau(v) = -ln(1 - a(v)) per mm. A ray segment of h mm whose value varies
// linearly from vf (front) to vb (back) then has the optical depth
//     h * (P(vb) - P(vf)) / (vb - vf),   P(v) = integral of tau dv,
// exact for any h and any pair of values; and it emits, front to back,
//     integral over s of tau c exp(-optical depth up to s) ds.
// The colour is taken as tau-weighted mean colour (E(vb) - E(vf)) /
// (P(vb) - P(vf)), E(v) = integral of tau c dv, per half of the segment,
// the front half in front of the back one: exact where the colour is
// constant over the segment's values, a second-order error (in the half's
// optical depth times its change of colour) where it varies. The march
// splits each segment at a middle value from the cubic through its ends and
// their neighbours (Catmull-Rom, no extra fetch), kept between its ends:
// in quarters, linear between the cubic's values at 1/4, 1/2 and 3/4.
// Measured on the angiogram phantom smoothed as a CT kernel would (Gaussian
// sigma 2.5 voxels; 256^2, flat, RMSE against a 0.05-voxel march), step 2
// and 4 voxels: sampled 0.0263 / 0.0505; one segment, linear 0.0090 /
// 0.0245; halves at the mean value 0.0054 / 0.0169 (the exact integral of
// linear values: 0.0056 / 0.0179); halves at the cubic's middle 0.0037 /
// 0.0128; quarters along the cubic 0.0017 / 0.0085. Unsmoothed (sharp 1-voxel walls, vessels of 1-6 voxels) every
// variant stays near the sampled error: there the values between samples
// are not near linear at all.
//
// Why tables of P and E and not Engel's 2D table of (vf, vb): these hold
// for every segment length (the drag frames' step and the still frames'
// use one table, and the pieces a ray is cut into by surfaces and clips
// are any length), values beyond the points extend them exactly (the
// transfer function is constant there), and they are 1D: 4096 texels
// rebuilt in well under a millisecond when the transfer function changes.
//
// Both tables have kTableTexels texels, texel i at value lo + i * width
// (lo, hi: the first and last points), read with linear interpolation.
#pragma once

#include <array>
#include <span>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "renderer/volume/transfer_function.hpp"

namespace iso {

// An opacity per mm of 1 is an infinite extinction: capped here (a
// millimetre at the cap transmits e^-20.7, 1e-9).
constexpr double kMaxExtinction = 20.72;
double extinction(double opacity_per_mm);

struct SegmentLight {
    glm::dvec3 color{0.0}; // linear RGB, premultiplied: what the segment emits towards its front
    double transmittance = 1;
};

class TransferTables {
public:
    static constexpr int kTexels = kTransferTableTexels;
    explicit TransferTables(const TransferFunction& tf);

    const TransferFunction& function() const { return tf_; }
    double lo() const { return lo_; }
    double width() const { return width_; } // value between texels (0: one point only)
    double hi() const { return hi_; }
    // Per texel: linear RGB and opacity per mm (the sampled march's table).
    const std::vector<glm::vec4>& classification() const { return classify_; }
    // Per texel: E (RGB) and P, from the first point (the pre-integrated march's table).
    const std::vector<glm::vec4>& integrals() const { return integral_f_; }
    // Beyond the points: (tau c, tau) at the first and the last point.
    glm::dvec4 low_end() const { return lo_end_; }
    glm::dvec4 high_end() const { return hi_end_; }
    // Values at or below clear_below() (at or above clear_above()) are
    // classified with opacity 0 by the tables, texel interpolation
    // included: a sample or segment there adds nothing, so the march skips
    // the lookup. -inf / +inf where there is no such range.
    double clear_below() const { return clear_below_; }
    double clear_above() const { return clear_above_; }

    // The classification at v as the GPU reads it (interpolated between texels).
    glm::dvec4 classify(double v) const;
    // (E, P) at v, interpolated, extended linearly beyond the points.
    glm::dvec4 integral(double v) const;
    // Their slope at v: (tau c, tau) averaged over the interval between the
    // two texels v lies between (beyond the points: the ends' own).
    glm::dvec4 slope(double v) const;
    // A segment of h mm, value linear from vf to vb (the model above).
    SegmentLight segment(double vf, double vb, double h) const {
        const double v[] = {vf, 0.5 * (vf + vb), vb};
        return segment(v, h);
    }
    // A segment of h mm whose value runs linearly between `values`, equally
    // spaced along it (the first at its front, the last at its back), each
    // piece integrated as above, front to back; within a texel's width of a
    // constant value a piece takes the integrals' slope at its back value
    // (the last piece: at its front value).
    SegmentLight segment(std::span<const double> values, double h) const;
    // The values the march takes inside the segment from v0 to v1, with
    // neighbours vp (before) and vn (after), equally spaced: the cubic
    // through the four (Catmull-Rom) at a quarter, a half and three quarters
    // of the way, kept between v0 and v1.
    static std::array<double, 3> inner_values(double vp, double v0, double v1, double vn);

private:
    TransferFunction tf_;
    double lo_ = 0, hi_ = 0, width_ = 0;
    int last_ = 0; // the last texel (0 when the function has one value)
    std::vector<glm::vec4> classify_, integral_f_;
    std::vector<glm::dvec4> integral_; // in double, for the CPU march
    glm::dvec4 lo_end_{0.0}, hi_end_{0.0};
    double clear_below_ = 0, clear_above_ = 0;
};

} // namespace iso
