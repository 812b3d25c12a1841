// The transfer function's tables and the pre-integrated segment (preintegration.hpp).
#include "renderer/volume/preintegration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "io/error.hpp"

namespace iso {

double extinction(double a) { return a >= 1.0 ? kMaxExtinction : std::min(-std::log1p(-a), kMaxExtinction); }

namespace {

// The mean extinction over a piece where the opacity runs linearly from a0
// to a1: the closed form (G(a1) - G(a0)) / (a1 - a0), G(a) = (1 - a) ln(1 - a) + a.
double mean_extinction(double a0, double a1) {
    if (std::abs(a1 - a0) < 1e-6) return extinction(0.5 * (a0 + a1));
    auto G = [](double a) { return a >= 1.0 ? 1.0 : (1.0 - a) * std::log1p(-a) + a; };
    return std::min((G(a1) - G(a0)) / (a1 - a0), kMaxExtinction);
}

// (integral of tau c, integral of tau) over [x0, x1], which no point of the
// transfer function lies strictly inside (colour and opacity linear there):
// tau in closed form, tau c by 4-point Gauss-Legendre.
glm::dvec4 piece_integral(const TransferFunction& tf, double x0, double x1) {
    const double L = x1 - x0;
    if (!(L > 0.0)) return glm::dvec4(0.0);
    static constexpr double kNodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                         0.8611363115940526};
    static constexpr double kWeights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                           0.3478548451374538};
    glm::dvec3 e(0.0);
    for (int i = 0; i < 4; ++i) {
        const glm::dvec4 c = tf.at(x0 + 0.5 * L * (kNodes[i] + 1.0));
        e += (0.5 * L * kWeights[i] * extinction(c.a)) * glm::dvec3(c);
    }
    // The opacity at the piece's ends, extrapolated from inside (linear
    // there; a step at an end belongs to the other side).
    const double q1 = tf.at(x0 + 0.25 * L).a, q3 = tf.at(x0 + 0.75 * L).a;
    const double a_lo = std::clamp(1.5 * q1 - 0.5 * q3, 0.0, 1.0), a_hi = std::clamp(1.5 * q3 - 0.5 * q1, 0.0, 1.0);
    return glm::dvec4(e, L * mean_extinction(a_lo, a_hi));
}

// The integrals over [x0, x1], split at the points inside.
glm::dvec4 span_integral(const TransferFunction& tf, double x0, double x1) {
    glm::dvec4 sum(0.0);
    double a = x0;
    for (const auto& p : tf.points())
        if (p.value > a && p.value < x1) {
            sum += piece_integral(tf, a, p.value);
            a = p.value;
        }
    return sum + piece_integral(tf, a, x1);
}

glm::dvec4 tau_c(const glm::dvec4& c) {
    const double tau = extinction(c.a);
    return glm::dvec4(tau * glm::dvec3(c), tau);
}

} // namespace

TransferTables::TransferTables(const TransferFunction& tf) : tf_(tf) {
    if (tf.empty()) throw Error("transfer function", "has no points");
    lo_ = tf.points().front().value;
    const double hi = hi_ = tf.points().back().value;
    last_ = hi > lo_ ? kTexels - 1 : 0;
    width_ = transfer_table_texel(tf);
    // kTexels always (one point: all alike), as the shader indexes them.
    classify_.resize(kTexels);
    integral_.resize(kTexels);
    integral_f_.resize(kTexels);
    glm::dvec4 sum(0.0);
    for (int i = 0; i < kTexels; ++i) {
        const int j = std::min(i, last_);
        const double v = lo_ + double(j) * width_;
        if (j > 0 && j == i) sum += span_integral(tf, lo_ + double(j - 1) * width_, j == last_ ? hi : v);
        classify_[std::size_t(i)] = glm::vec4(tf.at(j == last_ ? hi : v));
        integral_[std::size_t(i)] = sum;
        integral_f_[std::size_t(i)] = glm::vec4(sum);
    }
    lo_end_ = tau_c(tf.at(lo_));
    hi_end_ = tau_c(tf.at(hi));
    // The ranges of opacity 0 at the ends, less a texel (what interpolation reads).
    const auto& pts = tf.points();
    const double inf = std::numeric_limits<double>::infinity();
    clear_below_ = -inf;
    for (std::size_t i = 0; i < pts.size() && pts[i].opacity == 0.0; ++i) clear_below_ = pts[i].value - width_;
    clear_above_ = inf;
    for (std::size_t i = pts.size(); i > 0 && pts[i - 1].opacity == 0.0; --i) clear_above_ = pts[i - 1].value + width_;
}

glm::dvec4 TransferTables::classify(double v) const {
    if (!last_) return glm::dvec4(classify_[0]);
    const double x = std::clamp((v - lo_) / width_, 0.0, double(last_));
    const int i = std::min(int(x), last_ - 1);
    return glm::mix(glm::dvec4(classify_[std::size_t(i)]), glm::dvec4(classify_[std::size_t(i) + 1]), x - i);
}

glm::dvec4 TransferTables::integral(double v) const {
    if (v <= lo_) return lo_end_ * (v - lo_);
    if (v >= hi_) return integral_.back() + hi_end_ * (v - hi_);
    const double x = (v - lo_) / width_;
    const int i = std::min(int(x), last_ - 1);
    return glm::mix(integral_[std::size_t(i)], integral_[std::size_t(i) + 1], x - i);
}

std::array<double, 3> TransferTables::inner_values(double vp, double v0, double v1, double vn) {
    const double lo = std::min(v0, v1), hi = std::max(v0, v1);
    auto at = [&](double t) { // Catmull-Rom between v0 (t = 0) and v1 (t = 1)
        const double c = (-vp + 3.0 * v0 - 3.0 * v1 + vn) * t * t * t + (2.0 * vp - 5.0 * v0 + 4.0 * v1 - vn) * t * t +
                         (v1 - vp) * t + 2.0 * v0;
        return std::clamp(0.5 * c, lo, hi);
    };
    return {at(0.25), at(0.5), at(0.75)};
}

glm::dvec4 TransferTables::slope(double v) const {
    if (v <= lo_ || !last_) return lo_end_;
    if (v >= hi_) return hi_end_;
    const int i = std::min(int((v - lo_) / width_), last_ - 1);
    return (integral_[std::size_t(i) + 1] - integral_[std::size_t(i)]) / width_;
}

SegmentLight TransferTables::segment(std::span<const double> v, double h) const {
    const std::size_t pieces = v.size() - 1;
    const double len = h / double(pieces);
    SegmentLight out;
    for (std::size_t k = 0; k < pieces; ++k) {
        // The piece's optical depth and tau-weighted mean colour; within a
        // texel's width of a constant value, from the integrals' slope
        // (their difference would cancel).
        const double a = v[k], b = v[k + 1];
        const glm::dvec4 d = !(std::abs(b - a) >= width_) || last_ == 0 ? slope(v[std::min(k + 1, pieces - 1)])
                                                                        : (integral(b) - integral(a)) / (b - a);
        const glm::dvec3 color = d.w > 0.0 ? glm::dvec3(d) / d.w : glm::dvec3(0.0);
        const double keep = std::exp(-len * d.w);
        out.color += out.transmittance * (1.0 - keep) * color;
        out.transmittance *= keep;
    }
    return out;
}

} // namespace iso
