// The CPU ray march of the stated model (reference.hpp).
#include "renderer/volume/reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "io/error.hpp"

namespace iso {

VolumeSampler::VolumeSampler(const Volume& v, std::optional<ValueRange> range) : v_(v) {
    if (v.voxel_count() <= 0) throw Error("volume rendering", "the volume has no samples");
    to_index_ = glm::inverse(v.index_to_lps);
    hi_ = glm::dvec3(double(v.dims[0] - 1), double(v.dims[1] - 1), double(v.dims[2] - 1));
    // Float volumes may hold NaN and Inf: NaN is the extractor's substitute
    // below every finite value, Inf clamps to the finite range.
    if (v.type == VoxelType::F32 || v.type == VoxelType::F64 || v.is_sparse()) {
        const ValueRange r = range ? *range : v.value_range();
        const bool any = r.min <= r.max;
        lo_ = any ? r.min : 0.0;
        hi_value_ = any ? r.max : 0.0;
        nan_value_ = lo_ - std::max(1.0, std::abs(lo_) * 1e-3);
        finite_check_ = true;
    }
}

double VolumeSampler::raw(std::int64_t i, std::int64_t j, std::int64_t k) const {
    const double x = v_.value(i, j, k);
    if (!finite_check_) return x;
    if (std::isnan(x)) return nan_value_;
    return std::clamp(x, lo_, hi_value_);
}

double VolumeSampler::at_index(const glm::dvec3& ijk) const {
    const glm::dvec3 p = glm::clamp(ijk, glm::dvec3(0.0), hi_);
    std::int64_t i0[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        i0[a] = std::min<std::int64_t>(std::int64_t(std::floor(p[a])), std::max<std::int64_t>(v_.dims[a] - 2, 0));
        f[a] = p[a] - double(i0[a]);
    }
    const std::int64_t i1[3] = {std::min(i0[0] + 1, v_.dims[0] - 1), std::min(i0[1] + 1, v_.dims[1] - 1),
                                std::min(i0[2] + 1, v_.dims[2] - 1)};
    double c[2][2];
    for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy) {
            const std::int64_t j = dy ? i1[1] : i0[1], k = dz ? i1[2] : i0[2];
            c[dz][dy] = raw(i0[0], j, k) * (1.0 - f[0]) + raw(i1[0], j, k) * f[0];
        }
    const double y0 = c[0][0] * (1.0 - f[1]) + c[0][1] * f[1], y1 = c[1][0] * (1.0 - f[1]) + c[1][1] * f[1];
    return y0 * (1.0 - f[2]) + y1 * f[2];
}

glm::dvec3 VolumeSampler::to_index(const glm::dvec3& lps) const { return glm::dvec3(to_index_ * glm::dvec4(lps, 1.0)); }

std::optional<std::pair<double, double>> VolumeSampler::box_interval(const glm::dvec3& origin,
                                                                     const glm::dvec3& dir) const {
    const glm::dvec3 o = to_index(origin), d = glm::dvec3(to_index_ * glm::dvec4(dir, 0.0));
    double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0) {
            if (o[a] < 0.0 || o[a] > hi_[a]) return std::nullopt;
            continue;
        }
        double ta = (0.0 - o[a]) / d[a], tb = (hi_[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    if (!(t0 <= t1)) return std::nullopt;
    return std::pair{t0, t1};
}

double VolumeSampler::min_spacing() const {
    const glm::dvec3 s = v_.spacing();
    return std::min({s.x, s.y, s.z});
}

std::optional<std::pair<double, double>> ray_interval(const VolumeSampler& s, const Clip& clip,
                                                      const glm::dvec3& origin, const glm::dvec3& dir, double t_near,
                                                      double t_far) {
    auto box = s.box_interval(origin, dir);
    if (!box) return std::nullopt;
    double t0 = std::max(box->first, t_near), t1 = std::min(box->second, t_far);
    for (const ClipPlane& h : clip.half_spaces()) {
        // dot(n, o + t d) >= offset
        const double a = glm::dot(h.normal, dir), b = h.offset - glm::dot(h.normal, origin);
        if (a == 0.0) {
            if (b > 0.0) return std::nullopt;
        } else if (a > 0.0) {
            t0 = std::max(t0, b / a);
        } else {
            t1 = std::min(t1, b / a);
        }
    }
    if (!(t0 < t1)) return std::nullopt;
    return std::pair{t0, t1};
}

VolumeLighting volume_lighting(const VolumeSampler& s, const TransferFunction& tf, const glm::dmat3& world_to_view) {
    VolumeLighting l;
    l.gradient_to_view = world_to_view * glm::transpose(glm::dmat3(glm::inverse(s.volume().index_to_lps)));
    l.gradient_ref = gradient_reference(tf, s.min_spacing());
    return l;
}

namespace {

// shading.glsl's shade() without AO, in double.
glm::dvec3 shade_view(const glm::dvec3& n, const glm::dvec3& albedo) {
    const glm::dvec3 v(0.0, 0.0, 1.0), key = glm::normalize(glm::dvec3(-0.45, 0.6, 0.65));
    glm::dvec3 color = albedo * (0.12 * (0.6 + 0.4 * n.y));
    for (int i = 0; i < 2; ++i) {
        const glm::dvec3 l = i == 0 ? key : v;
        const double intensity = i == 0 ? 0.75 : 0.35, ndl = std::max(glm::dot(n, l), 0.0);
        const glm::dvec3 h = glm::normalize(l + v);
        const double spec =
            ndl > 0.0 ? std::pow(std::max(glm::dot(n, h), 0.0), 48.0) * (48.0 + 8.0) / (8.0 * 3.14159265) : 0.0;
        color += intensity * (albedo * ndl + 0.04 * spec * ndl);
    }
    glm::dvec3 out;
    for (int k = 0; k < 3; ++k) { // ACES fitted
        const double x = color[k];
        out[k] = std::clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    }
    return out;
}

} // namespace

glm::dvec3 shade_volume_sample(const VolumeSampler& s, const VolumeLighting& l, const glm::dvec3& ijk,
                               const glm::dvec3& color) {
    glm::dvec3 g;
    for (int k = 0; k < 3; ++k) {
        glm::dvec3 e(0.0);
        e[k] = 1.0;
        g[k] = 0.5 * (s.at_index(glm::min(ijk + e, s.dims_max())) - s.at_index(glm::max(ijk - e, glm::dvec3(0.0))));
    }
    glm::dvec3 n = l.gradient_to_view * g;
    const double len = glm::length(n);
    if (!(len > 0.0)) return color;
    n /= len;
    if (n.z < 0.0) n = -n;
    return glm::mix(color, shade_view(n, color), std::clamp(len / l.gradient_ref, 0.0, 1.0));
}

namespace {

struct Accumulator {
    glm::dvec3 color{0.0};
    double transmittance = 1;
    double volume_transmittance = 1; // the volume's own, for the pick's 0.5 crossing
    void layer(const RayLayer& l) {
        color += transmittance * l.alpha * l.color;
        transmittance *= 1.0 - l.alpha;
    }
    // A step of h mm of the volume transmitting `keep`, uniform within it
    // (T(x) = before * keep^(x / h)): when the volume's own transmittance is
    // at or below 0.5 after it, where in the step (0..h mm) it got there.
    std::optional<double> volume_step(double keep, double h) {
        const double before = volume_transmittance;
        volume_transmittance *= keep;
        if (!(volume_transmittance <= 0.5)) return std::nullopt;
        const double x = keep > 0.0 ? h * std::log(0.5 / before) / std::log(keep) : 0.0;
        return std::clamp(x, 0.0, h);
    }
};

// Emission-absorption over [a, b]: n equal steps sampled at their midpoints.
void composite_piece(const VolumeSampler& s, const VolumeLook& look, const VolumeLighting* lighting,
                     const glm::dvec3& origin, const glm::dvec3& dir, double a, double b, double step, double epsilon,
                     Accumulator& acc, RayResult& out) {
    if (!(b > a)) return;
    const auto n = std::int64_t(std::ceil((b - a) / step));
    const double h = (b - a) / double(n);
    for (std::int64_t k = 0; k < n && acc.transmittance >= epsilon; ++k) {
        const double t = a + (double(k) + 0.5) * h;
        const glm::dvec3 ijk = s.to_index(origin + t * dir);
        const double v = s.at_index(ijk);
        const glm::dvec4 c = look.tf.at(v);
        ++out.samples;
        if (c.a <= 0.0) continue;
        const double keep = std::pow(1.0 - c.a, h), alpha = 1.0 - keep;
        const glm::dvec3 color = lighting ? shade_volume_sample(s, *lighting, ijk, glm::dvec3(c)) : glm::dvec3(c);
        acc.color += acc.transmittance * alpha * color;
        acc.transmittance *= keep;
        // Within the step the opacity is constant.
        if (const auto x = acc.volume_step(keep, h); x && !out.t_half) {
            out.t_half = t - 0.5 * h + *x;
            out.value_half = v;
        }
    }
}

// The pre-integrated march over [a, b] (preintegration.hpp), as the GPU
// marches it in its first frame: points a + k h (k = 0..n, b the last),
// every segment between two of them integrated in quarters, the values
// inside it from the cubic through its ends and their neighbours (the
// points one step beyond a and b included).
void preintegrated_piece(const VolumeSampler& s, const TransferTables& tables, const VolumeLighting* lighting,
                         const glm::dvec3& origin, const glm::dvec3& dir, double a, double b, double step,
                         double epsilon, Accumulator& acc, RayResult& out) {
    if (!(b > a)) return;
    const auto n = std::int64_t(std::ceil((b - a) / step));
    const double h = (b - a) / double(n);
    auto value = [&](std::int64_t k) {
        ++out.samples;
        return s.at_index(s.to_index(origin + (k == n ? b : a + double(k) * h) * dir));
    };
    double vp = value(-1), vf = value(0), vb = value(1);
    for (std::int64_t k = 1; k <= n && acc.transmittance >= epsilon; ++k) {
        const double t = k < n ? a + double(k) * h : b;
        const double vn = value(k + 1);
        const auto q = TransferTables::inner_values(vp, vf, vb, vn);
        const double values[] = {vf, q[0], q[1], q[2], vb};
        SegmentLight seg = tables.segment(values, h);
        if (lighting && seg.transmittance < 1.0) { // shaded at the segment's middle, as a colour
            const glm::dvec3 mid = s.to_index(origin + (t - 0.5 * h) * dir);
            const double alpha = 1.0 - seg.transmittance;
            seg.color = alpha * shade_volume_sample(s, *lighting, mid, seg.color / alpha);
        }
        acc.color += acc.transmittance * seg.color;
        acc.transmittance *= seg.transmittance;
        // Within the segment as if its extinction were uniform.
        if (const auto x = acc.volume_step(seg.transmittance, h); x && !out.t_half) {
            out.t_half = t - h + *x;
            out.value_half = vf + (vb - vf) * (*x / h);
        }
        vp = vf;
        vf = vb;
        vb = vn;
    }
}

} // namespace

RayResult march_ray(const VolumeSampler& s, const VolumeLook& look, const Clip& clip, const glm::dvec3& origin,
                    const glm::dvec3& dir, double t_near, double t_far, std::span<const RayLayer> layers,
                    double step_mm, double epsilon, const TransferTables* tables, const VolumeLighting* lighting) {
    RayResult out;
    auto piece = [&](double a, double b, Accumulator& acc) {
        if (tables)
            preintegrated_piece(s, *tables, lighting, origin, dir, a, b, step_mm, epsilon, acc, out);
        else
            composite_piece(s, look, lighting, origin, dir, a, b, step_mm, epsilon, acc, out);
    };
    std::vector<RayLayer> sorted(layers.begin(), layers.end());
    std::stable_sort(sorted.begin(), sorted.end(), [](const RayLayer& a, const RayLayer& b) { return a.t < b.t; });
    // An opaque layer ends the ray.
    double end = t_far;
    for (const auto& l : sorted)
        if (l.alpha >= 1.0) {
            end = std::min(end, l.t);
            break;
        }
    const auto span = ray_interval(s, clip, origin, dir, t_near, end);
    Accumulator acc;
    if (look.mode != VolumeMode::Composite) {
        std::optional<RayLayer> extreme;
        if (span) {
            const auto n = std::max<std::int64_t>(1, std::int64_t(std::ceil((span->second - span->first) / step_mm)));
            const double h = (span->second - span->first) / double(n);
            const bool mip = look.mode == VolumeMode::Mip;
            for (std::int64_t k = 0; k <= n; ++k) {
                const double t = span->first + double(k) * h, v = s.at_index(s.to_index(origin + t * dir));
                ++out.samples;
                if (!out.extreme || (mip ? v > *out.extreme : v < *out.extreme)) {
                    out.extreme = v;
                    out.t_extreme = t;
                }
            }
            const glm::dvec4 c = look.tf.at(*out.extreme);
            extreme = RayLayer{out.t_extreme, glm::dvec3(c), c.a};
            if (c.a >= 0.5) {
                out.t_half = out.t_extreme;
                out.value_half = *out.extreme;
            }
        }
        bool placed = !extreme;
        for (const auto& l : sorted) {
            if (l.t > end) break;
            if (!placed && extreme->t <= l.t) {
                acc.layer(*extreme);
                placed = true;
            }
            acc.layer(l);
            if (l.alpha >= 1.0) break;
        }
        if (!placed) acc.layer(*extreme);
        out.color = acc.color;
        out.transmittance = acc.transmittance;
        return out;
    }
    double t = span ? span->first : 0.0;
    for (const auto& l : sorted) {
        if (l.t > end || acc.transmittance < epsilon) break;
        if (span && l.t > t) {
            piece(t, std::min(l.t, span->second), acc);
            t = std::max(t, l.t);
        }
        acc.layer(l);
        if (l.alpha >= 1.0) break;
    }
    if (span && acc.transmittance >= epsilon) piece(t, span->second, acc);
    out.color = acc.color;
    out.transmittance = acc.transmittance;
    return out;
}

} // namespace iso
